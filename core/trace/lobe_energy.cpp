#include "core/trace/lobe_energy.h"

#include <map>
#include <mutex>

#include "core/common/vec3.h"
#include "core/trace/ward.h"

namespace fenestra {
namespace {

// E(mu) of a unit lobe: the mean of Ward's sample weights over a stratified grid of its
// half vectors (SampleLobe's weight is f_s cos_l / pdf, 0 below the surface).
double Albedo(float alpha, double mu) {
  constexpr int kRadial = 512, kAzimuthal = 128;
  const WardLobe lobe{0.0f, 1.0f, alpha};
  const Vec3f n{0, 0, 1}, u{1, 0, 0}, w{0, 1, 0};
  const Vec3f v{static_cast<float>(std::sqrt(1 - mu * mu)), 0.0f, static_cast<float>(mu)};
  double sum = 0;
  for (int i = 0; i < kAzimuthal; ++i) {
    for (int j = 0; j < kRadial; ++j) {
      float weight;
      lobe.SampleLobe(n, u, w, v, (i + 0.5f) / kAzimuthal, (j + 0.5f) / kRadial, &weight);
      sum += weight;
    }
  }
  return sum / (double{kRadial} * kAzimuthal);
}

LobeEnergy Tabulate(float alpha) {
  LobeEnergy table;
  for (int k = 0; k < kLobeEnergyNodes; ++k) {
    const double t = static_cast<double>(k) / (kLobeEnergyNodes - 1);
    table.albedo[k] = static_cast<float>(Albedo(alpha, std::max(t * t, 1e-4)));
  }
  // E_avg of the interpolated table, so that f_c's integral is exactly what the lobe loses
  constexpr int kSteps = 20000;
  double average = 0;
  for (int s = 0; s < kSteps; ++s) {
    const double mu = (s + 0.5) / kSteps;
    average += 2 * table.At(static_cast<float>(mu)) * mu / kSteps;
  }
  table.average = static_cast<float>(average);
  // The draws' masses per interval: the integral of Lost(mu) mu over it, normalized
  double masses[kLobeEnergyNodes] = {}, total = 0;
  constexpr int kSub = 256;
  for (int k = 0; k + 1 < kLobeEnergyNodes; ++k) {
    for (int j = 0; j < kSub; ++j) {
      const double t = (k + (j + 0.5) / kSub) / (kLobeEnergyNodes - 1);
      const double mu = t * t;
      masses[k] += table.Lost(static_cast<float>(mu)) * mu * 2 * t;  // d mu = 2 t dt
    }
    total += masses[k];
  }
  double cumulative = 0;
  for (int k = 0; k + 1 < kLobeEnergyNodes; ++k) {
    table.cdf[k] = static_cast<float>(total > 0 ? cumulative / total : 0);
    cumulative += masses[k];
  }
  table.cdf[kLobeEnergyNodes - 1] = 1.0f;
  return table;
}

}  // namespace

LobeEnergy LobeEnergyOf(float alpha) {
  static std::mutex mutex;
  static std::map<float, LobeEnergy>* tables = new std::map<float, LobeEnergy>;
  std::lock_guard<std::mutex> lock(mutex);
  if (tables->size() >= 4096) tables->clear();  // bounded, whatever the scenes ask for
  auto it = tables->find(alpha);
  if (it == tables->end()) it = tables->emplace(alpha, Tabulate(alpha)).first;
  return it->second;
}

}  // namespace fenestra
