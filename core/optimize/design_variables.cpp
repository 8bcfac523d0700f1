// The slats' finish as a design variable (design_variables.h).
#include "core/optimize/design_variables.h"

#include <cmath>

#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "core/optimize/job.h"

namespace fenestra {

std::optional<size_t> FinishIndex(double value, size_t count) {
  if (!(value >= 0 && value < static_cast<double>(count)) || value != std::floor(value)) {
    return std::nullopt;
  }
  return static_cast<size_t>(value);
}

absl::StatusOr<std::vector<SlatFinish>> ResolveFinishes(const v1::DesignVariable& variable,
                                                        const Scene& scene,
                                                        const std::string& field) {
  std::vector<SlatFinish> finishes;
  for (int i = 0; i < variable.finishes_size(); ++i) {
    const v1::BlindFinish& f = variable.finishes(i);
    const std::string at = absl::StrCat(field, ".finishes[", i, "].");
    const auto index = [&](const std::string& name,
                           const std::string& which) -> absl::StatusOr<uint32_t> {
      absl::StatusOr<uint32_t> found = SlatMaterialIndex(scene.materials, name);
      if (found.ok()) return found;
      return InvalidJobField(at + which, std::string(found.status().message()));
    };
    FENESTRA_ASSIGN_OR_RETURN(material, index(f.material(), "material"));
    FENESTRA_ASSIGN_OR_RETURN(outer, f.has_outer_material()
                                         ? index(f.outer_material(), "outer_material")
                                         : absl::StatusOr<uint32_t>(material));
    finishes.push_back({material, outer});
  }
  return finishes;
}

SlatFinish FinishAt(const std::vector<SlatFinish>& finishes, double value) {
  return finishes[FinishIndex(value, finishes.size()).value_or(0)];
}

std::string FinishName(const v1::BlindFinish& finish) {
  if (!finish.has_outer_material() || finish.outer_material() == finish.material()) {
    return finish.material();
  }
  return absl::StrCat(finish.material(), " / ", finish.outer_material(), " outer");
}

namespace {

// The index of the job's finish variable among its variables, or -1.
int FinishVariableIndex(const v1::Job& job) {
  for (int i = 0; i < job.variables_size(); ++i) {
    if (job.variables(i).name() == kFinishVariable) return i;
  }
  return -1;
}

}  // namespace

std::string FinishNameAt(const v1::Job& job, double value) {
  const int variable = FinishVariableIndex(job);
  if (variable < 0) return "";
  const v1::DesignVariable& finish = job.variables(variable);
  const std::optional<size_t> index = FinishIndex(value, finish.finishes_size());
  return index ? FinishName(finish.finishes(static_cast<int>(*index))) : "";
}

absl::StatusOr<BlindDesign> JobDesignWithOverrides(const Scene& scene, const v1::Job& job,
                                                   const std::map<std::string, double>& values) {
  std::map<std::string, double> blind = values;
  const auto given = blind.find(std::string(kFinishVariable));
  if (given == blind.end()) return DesignWithOverrides(scene, blind);
  const double value = given->second;
  blind.erase(given);
  FENESTRA_ASSIGN_OR_RETURN(design, DesignWithOverrides(scene, blind));
  const int variable = FinishVariableIndex(job);
  if (variable < 0 || !design.has_blind) {
    return absl::InvalidArgumentError("a finish given, but the job has no finish variable");
  }
  FENESTRA_ASSIGN_OR_RETURN(finishes, ResolveFinishes(job.variables(variable), scene,
                                                      absl::StrCat("variables[", variable, "]")));
  if (!FinishIndex(value, finishes.size())) {
    return absl::InvalidArgumentError(absl::StrCat("finish ", value, " is not an index of the ",
                                                   finishes.size(), " finishes of the job"));
  }
  design.finish = FinishAt(finishes, value);
  return design;
}

}  // namespace fenestra
