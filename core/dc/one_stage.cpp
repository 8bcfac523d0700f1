#include "core/dc/one_stage.h"

#include <memory>

namespace fenestra {

absl::StatusOr<OneStageResult> ComputeOneStage(const TriangleMesh& mesh,
                                               const std::vector<Material>& materials,
                                               const std::vector<Sensor>& sensors,
                                               const OneStageOptions& options, DcBackend* backend) {
  std::unique_ptr<DcBackend> fallback;
  if (backend == nullptr) {
    fallback = MakeEmbreeBackend();
    backend = fallback.get();
  }
  return backend->OneStage(mesh, materials, sensors, options);
}

absl::StatusOr<OneStageResult> ComputeOneStage(const Scene& scene, const BlindDesign& design,
                                               const OneStageOptions& options, DcBackend* backend) {
  return ComputeOneStage(AssembleMesh(scene, design), scene.materials, scene.sensors, options,
                         backend);
}

double MeanRelativeStandardError(const OneStageResult& result, double min_fraction) {
  return MeanRelativeError(result.coefficients, result.standard_error, min_fraction);
}

}  // namespace fenestra
