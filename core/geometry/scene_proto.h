#pragma once

// A built scene written back as a scene message, self-contained: every surface as its
// triangles (one polygon surface each, named after its part), sensor grids expanded, OBJ
// meshes inlined, and no file paths (the site's weather file is left out). BuildScene of
// it gives the same triangles, window, sensors and blind.
#include "core/geometry/scene.h"
#include "fenestra/v1/scene.pb.h"

namespace fenestra {

v1::Scene SelfContainedSceneProto(const Scene& scene);

}  // namespace fenestra
