// How a scene's surfaces, window and sensors fit together as a room, checked with probe
// rays against the indoor surfaces (Embree): the window must sit at an opening of the room
// and every sensor in the room's air.
#pragma once

#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/geometry/scene.h"
#include "fenestra/v1/scene.pb.h"

namespace fenestra {

// Nearest a sensor may come to a surface, the window or the blind's space [m].
inline constexpr double kSensorClearanceM = 0.001;
// How closely the window rectangle must match its opening in the indoor surfaces [m]: the
// edges of both within this of each other, the wall's inner face within this of depth_m.
inline constexpr double kWindowFitM = 0.02;

// Checks, with the blind at every design within the scene's blind ranges:
// - the window lies at an opening of the indoor surfaces: its rectangle is open through
//   the wall (depth_m), the room lies behind it and nothing of the room in front of it, and
//   just outside each edge the indoor surfaces close the gap (the wall's inner face within
//   depth_m, or a surface across the edge);
// - every sensor lies in the room's air: no probe ray (26 directions) leaves without
//   meeting an indoor surface or the window (else it is outside the room), none meets a
//   surface within kSensorClearanceM (on a surface), the first surface met is not a face of
//   a box the sensor is in (inside a solid), and the sensor is outside the space the slats
//   can take (EnvelopeOfBlind).
// Polygons and OBJ meshes are two-sided sheets: only boxes and slats are solids. Errors are
// InvalidArgument "<scene source>: <field> ...: <reason>".
absl::Status CheckRoom(const Scene& scene);

// BuildScene, then CheckRoom: the door every scene from a file or a client passes.
absl::StatusOr<Scene> ValidateScene(const v1::Scene& proto, const std::string& path);

// ReadSceneProto, then ValidateScene.
absl::StatusOr<Scene> LoadValidScene(const std::string& path);

}  // namespace fenestra
