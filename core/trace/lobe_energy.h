// The energy a Ward lobe loses, for CPU and GPU: E(mu), the directional albedo of the
// normalized Ward lobe of core/trace/ward.h with rho_s = 1 for light from a direction of cosine
// mu, tabulated per roughness, and its cosine-weighted mean E_avg = 2 int E(mu) mu dmu.
//
// The lobe alone reflects rho_s E(mu) <= rho_s: it loses light at grazing angles and the more
// the rougher it is (alpha = 0.2: E = 0.96 at normal incidence, 0.81 at 85 degrees), where
// Radiance's Monte Carlo reflects rho_s exactly (it weighs every sample by rho_s). The lost
// light comes back as a second, broad lobe (Kulla and Conty, "Revisiting physically based
// shading at Imageworks", 2017):
//
//   f_c(v, l) = rho_s (1 - E(mu_v)) (1 - E(mu_l)) / (pi (1 - E_avg)),
//
// which is reciprocal and makes the two together reflect rho_s exactly from every direction:
// the integral of f_c cos over l is rho_s (1 - E(mu_v)) (core/README.md, "Materials").
#pragma once

#include <math.h>

#include "core/common/cpu_gpu.h"

namespace fenestra {

inline constexpr int kLobeEnergyNodes = 32;

struct LobeEnergy {
  // E at mu = (k / (kLobeEnergyNodes - 1))^2: nodes close together at grazing angles, where E
  // changes fastest
  float albedo[kLobeEnergyNodes] = {};
  float average = 1.0f;  // E_avg of the table as interpolated; 1 = nothing lost (no lobe)

  // E(mu), linear between the nodes in sqrt(mu).
  FENESTRA_CPU_GPU float At(float mu) const {
    const float t = sqrtf(mu > 0.0f ? (mu < 1.0f ? mu : 1.0f) : 0.0f) * (kLobeEnergyNodes - 1);
    int k = static_cast<int>(t);
    if (k > kLobeEnergyNodes - 2) k = kLobeEnergyNodes - 2;
    const float f = t - static_cast<float>(k);
    return albedo[k] + f * (albedo[k + 1] - albedo[k]);
  }

  // The share of rho_s that comes back as f_c from a direction of cosine mu, and f_c's factor
  // for the far direction: f_c = rho_s Lost(mu_v) Lost(mu_l) / (pi (1 - E_avg)).
  FENESTRA_CPU_GPU float Lost(float mu) const { return 1.0f - At(mu); }
  FENESTRA_CPU_GPU bool Compensates() const { return average < 1.0f - 1e-6f; }

  // f_c is drawn in proportion to Lost(mu_l) mu_l (its weight is then rho_s Lost(mu_v) / its
  // share of the draws, whatever mu_l): sqrt(mu_l) from a density constant on each interval
  // between the nodes, whose masses are f_c's there (`cdf`, at the nodes), the azimuth uniform.
  float cdf[kLobeEnergyNodes] = {};

  // The cosine mu of a draw for a uniform u.
  FENESTRA_CPU_GPU float SampleLostCosine(float u) const {
    int k = 0;
    while (k < kLobeEnergyNodes - 2 && !(u < cdf[k + 1])) ++k;
    const float width = cdf[k + 1] - cdf[k];
    const float f = width > 0.0f ? (u - cdf[k]) / width : 0.0f;
    const float t = (static_cast<float>(k) + (f < 1.0f ? f : 1.0f)) / (kLobeEnergyNodes - 1);
    return t * t;
  }

  // The solid-angle density of SampleLostCosine's directions at cosine mu (> 0).
  FENESTRA_CPU_GPU float LostDensity(float mu) const {
    const float t = sqrtf(mu < 1.0f ? mu : 1.0f);
    int k = static_cast<int>(t * (kLobeEnergyNodes - 1));
    if (k > kLobeEnergyNodes - 2) k = kLobeEnergyNodes - 2;
    constexpr float kStep = 1.0f / (kLobeEnergyNodes - 1), kFourPi = 12.5663706f;
    // per unit t: mass / step; per unit mu: / (2 t); per steradian: / (2 pi)
    return t > 1e-6f ? (cdf[k + 1] - cdf[k]) / (kStep * kFourPi * t) : 0.0f;
  }
};

// The table of a lobe of roughness `alpha` (> 0), by quadrature of Ward's sampling (a
// stratified grid of 512 x 128 half vectors per node); computed once per roughness and kept.
LobeEnergy LobeEnergyOf(float alpha);

}  // namespace fenestra
