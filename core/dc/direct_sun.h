#pragma once

// The direct sun where it is (core/README.md, "Direct sun"): per sensor and time step, the
// illuminance of the sun's beam alone, from one straight line towards the sun's position
// (a point at the centre of its disc, as Honeybee's direct-sunlight recipe and rtrace -ab 0
// with one sun per hour), exact rather than Monte Carlo. The lines are traced once through
// every surface but the blind (glazing passes them with its transmittance, anything opaque
// stops them); per design only the blind's slats are tested against the lines left, by
// their layout (LocalSlats), as the indoor replay tests its shadow rays. A line the blind of
// no design can reach is counted without a test.
//
// The daylight coefficients keep the sun's light after a reflection (in the sky patches the
// sky matrix spreads it over); their direct component, the part that reaches a sensor
// without a reflection, is what this replaces: E = D S - D_0 S_sun + E_sun (core/README.md).
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "core/common/radiance_matrix.h"
#include "core/common/vec3.h"
#include "core/dc/sun_entry.h"
#include "core/geometry/blind.h"
#include "core/geometry/scene.h"

namespace fenestra {

// The sun of one column of a product's sky: its unit direction (x east, y north, z up) and
// its direct normal illuminance [lx].
struct SunColumn {
  int column = 0;
  Vec3d direction;
  double normal_lux = 0;
};

class DirectSun {
 public:
  // Traces every sensor's line towards each sun of `suns` (columns below `columns`) through
  // `scene`'s fixed geometry. InvalidArgument for a column out of range or a sun that is not
  // a unit direction; what PrepareTraceGeometry refuses.
  static absl::StatusOr<std::unique_ptr<DirectSun>> Trace(const Scene& scene,
                                                          const std::vector<SunColumn>& suns,
                                                          int columns);
  ~DirectSun();
  DirectSun(const DirectSun&) = delete;
  DirectSun& operator=(const DirectSun&) = delete;

  // The nonzero entries at `design` (the scene's blind at those values and of the design's
  // finish, FinishOf; the bare window where the scene has no blind or `blind` is false), by
  // sensor, then column.
  std::vector<SunEntry> Entries(const BlindDesign& design, bool blind = true) const;
  // The same as a sensors x columns matrix [lx].
  Matrix Illuminance(const BlindDesign& design, bool blind = true) const;
  int Sensors() const;
  int Columns() const;
  // Lines that reach a sensor's side of the blind, of sensors x suns above its horizon.
  size_t Lines() const;

 private:
  struct Data;
  explicit DirectSun(std::unique_ptr<Data> data);
  std::unique_ptr<Data> data_;
};

// Adds `entries` to every row block of `illuminance` (stacked batches of `sensors` rows each,
// columns as the entries').
void AddSunEntries(std::span<const SunEntry> entries, int sensors, Matrix& illuminance);

// InvalidArgument unless every entry lies within the batches' sensors and the sky's columns,
// and the sky is split (kSplitSkyRows) where there are entries.
absl::Status CheckSunEntries(std::span<const SunEntry> entries, const std::vector<Matrix>& batches,
                             const Matrix& sky);

}  // namespace fenestra
