#pragma once

// A built scene written back as a scene message, self-contained: every surface as its
// triangles (one polygon surface each, named after its part), sensor grids expanded, OBJ
// meshes inlined, and no file paths (the site's weather file is left out). Each material is
// written as the scene gave it (Lambertian, or its kind's parameters, recovered from its parts
// so that they give the same parts). BuildScene of it gives the same triangles, materials,
// window, sensors and blind.
#include "core/geometry/scene.h"
#include "fenestra/v1/scene.pb.h"

namespace fenestra {

v1::Scene SelfContainedSceneProto(const Scene& scene);

}  // namespace fenestra
