// Honeybee models (HBJSON, honeybee-schema's Model, as Grasshopper/Rhino's Honeybee saves
// them) as Fenestra scenes: one room to simulate, with its windows and sensors, and all else
// the window sees. core/README.md, "Honeybee models", says what becomes what.
//
// - Units: Model.units (Meters, Millimeters, Centimeters, Feet, Inches) to metres; the model's
//   tolerance (default 0.01 of its units) bounds how far a face may be off its plane and an
//   aperture off its face's plane, its angle_tolerance (default 1 degree) how far an
//   aperture's corners may be from right angles.
// - The room: options.room, else the only room, else the one room that holds the chosen
//   sensor grids (the one a grid names as its room_identifier, else the one whose bounding
//   box, grown by the tolerance, holds every sensor of the grid). Its faces, apertures and
//   doors and its indoor shades are SIDE_INDOOR; every other room's, orphaned faces,
//   apertures and doors, shade meshes and every outdoor shade are SIDE_OUTDOOR (what the
//   window sees). Other rooms' faces that touch the room (a Surface boundary condition naming
//   it) coincide with its own and are left out; so are their AirBoundary faces (air). An
//   AirBoundary face of the room itself is refused: it opens the room to another.
// - Geometry: each face less its holes and its apertures' and doors' polygons (coplanar,
//   projected onto its plane); a convex face without openings stays one polygon, any other
//   becomes convex pieces (TriangulatePlanarPolygon's triangles merged: ConvexPiecesOf-
//   PlanarPolygon) named "<face id>#<k>".
// - Windows: each aperture of the room in a face with an Outdoors boundary condition, and each
//   such door whose modifier is a glass, is a window (a rectangle: 4 vertices, right angles),
//   named by its identifier (other characters than letters, digits, '_', '-' and '.' made '_',
//   at most 64, made unique): its centre, the face's outward normal (Honeybee's faces point
//   out of their room: the room's faces must enclose a positive volume), `up` the rectangle's
//   side closest to +z (+y for a horizontal skylight), depth 0. Its modifier becomes a pane:
//   the same rectangle 1 mm into the room (kGlazingInsetM), named "<aperture id>#pane", so
//   the window's plane stays free. Other apertures and doors are surfaces in their place.
// - Materials: an element's own modifier, else its room's modifier set's for its kind and
//   boundary condition, else honeybee-radiance's generic ones (core/geometry/hbjson_materials.h).
//   Void: the element is left out (counted).
// - Sensors: the chosen grid (options.sensor_grid), else every grid of the room (naming it as
//   room_identifier, or inside its bounding box); "<grid id>_<k>", k from 0.
// - No site: the weather comes with the job.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "fenestra/v1/scene.pb.h"

namespace fenestra {

// Largest model taken by default [bytes].
inline constexpr size_t kMaxHoneybeeModelBytes = size_t{64} << 20;
// Most rooms, most faces (or shades, apertures, doors) in one list, most sensor grids, and
// most scene surfaces an import may make.
inline constexpr size_t kMaxHoneybeeRooms = 10'000;
inline constexpr size_t kMaxHoneybeeElements = 100'000;
inline constexpr size_t kMaxHoneybeeGrids = 10'000;
inline constexpr size_t kMaxHoneybeeSurfaces = 1'000'000;
// How far into the room a window's pane lies behind the window's rectangle [m].
inline constexpr double kGlazingInsetM = 0.001;

struct HoneybeeImportOptions {
  std::string room;         // identifier of the room to simulate; empty = automatic
  std::string sensor_grid;  // identifier of the sensor grid; empty = every grid of that room
  size_t max_bytes = kMaxHoneybeeModelBytes;  // the largest JSON text taken
};

// What an import took, for a summary.
struct HoneybeeImportSummary {
  std::string room;                       // the room simulated
  std::vector<std::string> sensor_grids;  // the grids its sensors come from
  size_t rooms = 0;                       // rooms in the model
  size_t faces = 0;                       // the room's faces
  size_t apertures = 0;                   // the room's apertures
  size_t doors = 0;                       // the room's doors
  size_t windows = 0;                     // windows made (apertures and glass doors)
  size_t shades = 0;                      // shades taken (of the room, other rooms, orphaned)
  size_t context_faces = 0;  // faces of other rooms and orphaned ones, as outdoor surfaces
  size_t hidden_faces = 0;   // faces of other rooms left out (touching the room, air)
  size_t void_elements = 0;  // elements left out for a Void modifier
  size_t sensors = 0;
  size_t surfaces = 0;           // surfaces of the scene
  size_t degenerate_pieces = 0;  // zero-area pieces of shade meshes or cut faces dropped
};

// Builds a scene (fenestra.v1.Scene) from a Honeybee model's JSON text: `source_name` names it
// in errors. InvalidArgument "<source_name>: <JSON path of the offending element>: <reason>"
// ("model.hbjson: rooms[0].faces[3].apertures[0].geometry: ..."): JSON that does not parse or
// exceeds the bounds (size, nesting, counts), a field of the wrong type, a non-finite number or
// a coordinate beyond kMaxCoordinateM, a non-planar face, a non-rectangular window, an
// AirBoundary face of the room, a modifier Fenestra does not have, no sensor grid, a room that
// cannot be chosen (the message lists the rooms), a room without a window. `summary`, when
// given, receives what was taken.
absl::StatusOr<v1::Scene> ImportHoneybee(std::string_view json, const std::string& source_name,
                                         const HoneybeeImportOptions& options,
                                         HoneybeeImportSummary* summary = nullptr);

}  // namespace fenestra
