#pragma once

#include <vector>

#include "absl/status/statusor.h"
#include "core/dc/dc_backend.h"
#include "core/geometry/scene.h"

namespace fenestra {

// One-stage daylight coefficients of `scene` at `design` (blind included when the design
// has one): D[i, j] for every sensor i and bin j (0 = ground, 1..145 = Tregenza), with
// standard errors. Traced by `backend`, or by the Embree CPU backend when null.
absl::StatusOr<OneStageResult> ComputeOneStage(const Scene& scene, const BlindDesign& design,
                                               const OneStageOptions& options,
                                               DcBackend* backend = nullptr);

// The same for explicit geometry (tests, tools): `mesh` with `materials` and `sensors`.
absl::StatusOr<OneStageResult> ComputeOneStage(const TriangleMesh& mesh,
                                               const std::vector<Material>& materials,
                                               const std::vector<Sensor>& sensors,
                                               const OneStageOptions& options,
                                               DcBackend* backend = nullptr);

// Mean over coefficients of standard error / value, counting only coefficients above
// `min_fraction` of their row's maximum (0 when there are none).
double MeanRelativeStandardError(const OneStageResult& result, double min_fraction = 0.01);

}  // namespace fenestra
