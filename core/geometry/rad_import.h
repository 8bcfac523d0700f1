#pragma once

// Radiance models in and out: scene descriptions (.rad) and points files (.pts) as a scene
// (fenestra.v1.Scene), and a scene back as both, so that a model made for Radiance can be
// optimized here and a scene from here rendered in Radiance.
//
// What is read. Radiance's syntax: each primitive is `modifier type identifier`, then its
// string arguments (a count, then that many words), its integer arguments and its real
// arguments, tokens separated by any whitespace, so a primitive may span lines; `#` at the
// start of a word begins a comment to the end of its line. Supported types, with Radiance's
// arguments (doc/ray.html):
//   plastic  0 0 5 r g b specularity roughness
//   metal    0 0 5 r g b specularity roughness
//   trans    0 0 7 r g b specularity roughness transmissivity transmitted_specular
//   glass    0 0 3 r g b  or  0 0 4 r g b index (the index must be 1.52, Fenestra's pane)
//   polygon  0 0 3n x1 y1 z1 ... (3 <= n <= max_polygon_vertices)
// and `void` as the modifier of no material. Every other primitive (`!command` lines such
// as `!xform`, `xform`, `sphere`, `cone`, `mesh`, `instance`, `alias`, patterns, textures,
// `light`, `glow` and other sources, mixtures) is refused with "FILE:LINE: unsupported
// primitive 'TYPE'". A material's modifier must be `void`.
//
// Materials. Fenestra is grey: a colour (r, g, b) counts as its photopic luminance
// 0.265 r + 0.670 g + 0.065 b (Radiance's `bright` for its default primaries), for the
// colour of a plastic, metal or trans and the transmissivity of a glass. plastic, metal and
// trans become Material.plastic, metal and trans with the same parameters; a glass becomes
// Material.glass whose transmittance at normal incidence is what its transmissivity lets
// through (GlassPane::NormalTransmittance). A material is named by its identifier. Refused,
// naming file and line: a modifier used before it is defined or defined twice, one named
// `void`, wrong argument counts, numbers that are not finite, and parameters outside
// Fenestra's ranges (those BuildScene checks).
//
// Surfaces. Polygons whose modifier is `void` are invisible in Radiance: they are skipped
// and counted (RadImportSummary). Every vertex is finite and within kMaxCoordinateM; a
// polygon of zero area or one that is not planar is refused. A convex polygon becomes one
// Surface (a polygon) named by its identifier. A non-convex one (a wall with a window
// punched in it: its outline runs to the hole and back along a seam) has its seams opened
// into holes, whichever way round they run (SplitRadSeams, rad_geometry.h), and is split
// into triangles (TriangulatePlanarPolygon), Surfaces named "<identifier>#<k>", k = 0, 1,
// ...; triangles of no area are left out and counted; a polygon that crosses itself (a star
// too, whose corners all turn one way) is refused. The side is SIDE_INDOOR in sources that
// are not `outdoor`, SIDE_OUTDOOR in those that are.
//
// Windows. Fenestra's window is the opening (scene.h's Window); its glazing is an ordinary
// surface. A polygon on the indoor side whose modifier is a glass must be a rectangle (4
// vertices, planar and right-angled within 1e-6 relative; else "windows must be
// rectangles"): it becomes an entry of Scene.windows (the identifier with every character
// but letters, digits, '_', '-' and '.' replaced by '_', at most 64 of them, made unique;
// its centre; the outward normal, the polygon's normal turned away from the centroid of the
// sensors; `up` along the rectangle's edge closest to +z, or for a horizontal skylight the
// one closest to +y; width and height; depth 0; no blind) and a glazing Surface: the same
// rectangle of that glass, 1 mm into the room (along -outward_normal), so that the window's
// own plane stays open. The room check (ValidateScene) takes that glazing for a surface that
// closes the opening (core/README.md, "Radiance models"). Each window, and the windows
// together, are checked as BuildScene checks them (at most kMaxSceneWindows; blinds that it
// cannot yet trace together are refused with its Unimplemented).
//
// Sensors. The points file holds one sensor a line, `x y z dx dy dz`; blank lines and lines
// starting with `#` are skipped. They are named "sensor_<k>" (k = 0, 1, ... the line order)
// unless a `#@fenestra sensors` directive names them.
//
// Directives. Comment lines that start with `#@fenestra ` (the first thing on their line)
// carry what Radiance has no words for, so that an export reads back as the same scene:
//   #@fenestra scene NAME            the scene's name (else the first source's file stem)
//   #@fenestra site JSON             Scene.site (protobuf's JSON form)
//   #@fenestra sensors JSON          a JSON list of sensor names, appended in order
//   #@fenestra side indoor|outdoor   the side of the primitives that follow in this source
//   #@fenestra material JSON         a Material for the material primitive that follows
//                                    (whose Radiance arguments must match it): Fenestra's
//                                    own parameters, e.g. Lambertian glazing, exactly
//   #@fenestra surface NAME          the name of the polygon that follows; a glass polygon
//                                    after it is a surface (glazing), not a window
//   #@fenestra window JSON           an entry of Scene.windows (with its blind): a window is
//                                    an opening, so it has no primitive
//   #@fenestra blind-geometry begin  ... end: the slats as Radiance sees them, skipped (the
//                                    blind is rebuilt from its window's JSON)
// NAME is the rest of the line; a directive is at most kMaxRadDirectiveBytes, its JSON
// nested at most kRadMaxJsonDepth (8) deep.
//
// What is written (ExportRadiance): every directive above, then each material as its
// Radiance modifier (rad_io.h's rules) after its `material` directive, each window as its
// directive (and its blind's slats at the blind's design in a blind-geometry block), each
// polygon surface after its `side` and `surface` directives, and the sensors' names; the
// points file holds the sensors. Numbers have 17 significant digits, so that
// ImportRadiance(ExportRadiance(S)) == RadianceRoundTripForm(S).
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "fenestra/v1/scene.pb.h"

namespace fenestra {

// Longest `#@fenestra` directive line [bytes].
inline constexpr size_t kMaxRadDirectiveBytes = 1 << 20;

// One input file's text and the name used in errors ("room.rad"). Primitives of an `outdoor`
// source are outdoor surfaces (context: neighbours, ground), those of the others indoor
// unless a `#@fenestra side` directive says otherwise.
struct RadSource {
  std::string name;
  std::string text;
  bool outdoor = false;
};

// The bounds on what the input makes ImportRadiance allocate; each is refused beyond.
struct RadImportOptions {
  // Longest text of one source or points file [bytes].
  size_t max_source_bytes = size_t{1} << 30;
  // Most vertices of one polygon.
  int64_t max_polygon_vertices = 10'000;
  // Most primitives (materials and polygons) and most polygon vertices in all sources.
  int64_t max_primitives = 2'000'000;
  int64_t max_vertices = 20'000'000;
};

// What an import read and did besides the scene it returns.
struct RadImportSummary {
  int64_t materials = 0;              // material primitives
  int64_t polygons = 0;               // polygon primitives, `void` ones included
  int64_t void_polygons = 0;          // polygons of modifier `void`, skipped
  int64_t windows = 0;                // glass rectangles made windows
  int64_t triangulated_polygons = 0;  // non-convex polygons split into triangles
  int64_t dropped_triangles = 0;      // zero-area triangles of those, left out
};

// One line for people about an import that made `surfaces` surfaces, e.g. "14 polygons (1
// window, 2 non-convex split into triangles) as 27 surfaces, 6 materials; 1 void polygons
// skipped".
std::string DescribeRadImport(const RadImportSummary& summary, int64_t surfaces);

// Builds a scene from Radiance scene descriptions, read in order (a modifier is defined in
// an earlier source or earlier in its own), and a points file (`points.text` may be empty:
// no sensors): materials from the modifiers, surfaces from the polygons, windows from the
// glass rectangles, sensors from the points, as the top of this file says. InvalidArgument
// "FILE:LINE: reason" on bad input; `summary`, when given, receives the counts.
absl::StatusOr<v1::Scene> ImportRadiance(const std::vector<RadSource>& sources,
                                         const RadSource& points,
                                         const RadImportOptions& options = {},
                                         RadImportSummary* summary = nullptr);

// Writes `scene` (the v1::Scene as given, not its triangles) as a Radiance scene description
// that Radiance renders and ImportRadiance reads back into RadianceRoundTripForm(scene);
// `points` receives its points file. InvalidArgument for a scene that cannot be written
// (an unknown material, a polygon of fewer than 3 vertices, a side not given, a part that
// BuildScene refuses), FailedPrecondition for OBJ surfaces.
absl::StatusOr<std::string> ExportRadiance(const v1::Scene& scene, std::string* points);

// `scene` in the form ImportRadiance gives it back after ExportRadiance: the one-window form
// (`window`, `blind`) as one entry of `windows`; each box as its 6 faces, polygon surfaces
// of the box's name and material (a box does not read back as a box, nor as a solid); each
// sensor grid as its sensors (BuildScene's names). FailedPrecondition for OBJ surfaces.
absl::StatusOr<v1::Scene> RadianceRoundTripForm(const v1::Scene& scene);

}  // namespace fenestra
