// The blind variables a job may design: their names, the bounds of a real blind, and where
// each lives in a design and in the scene's blind.
#pragma once

#include <string_view>

#include "core/geometry/blind.h"

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

// The variable called `name`, or null.
inline const DesignVariableInfo* FindDesignVariable(std::string_view name) {
  for (const DesignVariableInfo& v : kDesignVariables) {
    if (name == v.name) return &v;
  }
  return nullptr;
}

}  // namespace fenestra
