// The blind variables a job may design: their names, the bounds of a real blind, and where
// each lives in a design and in the scene's blind; and the slats' finish, a choice among the
// finishes a job lists (job.proto, DesignVariable.finishes), by index.
#pragma once

#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "core/geometry/blind.h"
#include "core/geometry/scene.h"
#include "fenestra/v1/job.pb.h"

namespace fenestra {

struct DesignVariableInfo {
  const char* name;
  const char* unit;
  ParameterBounds bounds;
  double BlindDesign::*field;
  ParameterRange BlindSpec::*range;
};

inline constexpr DesignVariableInfo kDesignVariables[] = {
    {"alpha", "rad", kTiltBoundsRad, &BlindDesign::tilt_rad, &BlindSpec::tilt_rad},
    {"width", "m", kSlatWidthBoundsM, &BlindDesign::slat_width_m, &BlindSpec::slat_width_m},
    {"spacing", "m", kSlatSpacingBoundsM, &BlindDesign::slat_spacing_m, &BlindSpec::slat_spacing_m},
    {"thickness", "m", kSlatThicknessBoundsM, &BlindDesign::slat_thickness_m,
     &BlindSpec::slat_thickness_m},
};

// The variable called `name`, or null (also for the finish, which is no field of the blind).
inline const DesignVariableInfo* FindDesignVariable(std::string_view name) {
  for (const DesignVariableInfo& v : kDesignVariables) {
    if (name == v.name) return &v;
  }
  return nullptr;
}

// The name of the slats' finish variable, and the most finishes it may list.
inline constexpr std::string_view kFinishVariable = "finish";
inline constexpr int kMaxFinishes = 64;

// The index that `value` stands for among `count` finishes: a whole number in [0, count), else
// none.
std::optional<size_t> FinishIndex(double value, size_t count);

// The finishes of `variable` as the slats' materials of `scene`, in their order; `field` is the
// variable's (e.g. "variables[4]"). InvalidArgument "job FIELD.finishes[i].material: REASON"
// (InvalidJobField) for a material the scene does not have, or a glass.
absl::StatusOr<std::vector<SlatFinish>> ResolveFinishes(const v1::DesignVariable& variable,
                                                        const Scene& scene,
                                                        const std::string& field);

// The finish at `value` of `finishes`, a value the door checked (FinishIndex; else the first).
SlatFinish FinishAt(const std::vector<SlatFinish>& finishes, double value);

// A finish as people read it: "white", or "white / aluminium outer".
std::string FinishName(const v1::BlindFinish& finish);

// The name of the finish at `value` of `job`'s finish variable (FinishName); empty where the
// job has no finish variable or `value` is none of its indices.
std::string FinishNameAt(const v1::Job& job, double value);

// DesignWithOverrides (core/geometry/scene.h) with the job's finish too: `values` may hold
// "finish", an index of `job`'s finish variable, whose materials are taken from `scene` (the
// scene the job ran). InvalidArgument where the job has no finish variable, the index is not
// one of its, or its materials are not the scene's slat materials.
absl::StatusOr<BlindDesign> JobDesignWithOverrides(const Scene& scene, const v1::Job& job,
                                                   const std::map<std::string, double>& values);

}  // namespace fenestra
