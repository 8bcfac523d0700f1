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
  double total = 0;
  int count = 0;
  for (Eigen::Index s = 0; s < result.coefficients.rows(); ++s) {
    const double row_max = result.coefficients.row(s).maxCoeff();
    for (Eigen::Index b = 0; b < result.coefficients.cols(); ++b) {
      const double value = result.coefficients(s, b);
      if (value > 0 && value > min_fraction * row_max) {
        total += result.standard_error(s, b) / value;
        ++count;
      }
    }
  }
  return count > 0 ? total / count : 0.0;
}

}  // namespace fenestra
