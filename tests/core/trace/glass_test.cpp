#include "core/trace/glass.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

namespace fenestra {
namespace {

// The transmittance against the angle of incidence is Radiance's own (rtrace through a pane of
// `glass` 0.96, tests/data/reference/glass_radiance.txt), from normal to grazing incidence.
TEST(GlassTest, TransmittanceIsRadiances) {
  std::ifstream in(FENESTRA_SOURCE_DIR "/tests/data/reference/glass_radiance.txt");
  ASSERT_TRUE(in) << "no reference";
  const GlassPane pane{0.96f};
  int compared = 0;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    double degrees = 0, radiance = 0;
    fields >> degrees >> radiance;
    const float c = static_cast<float>(std::cos(degrees * 3.14159265358979323846 / 180));
    EXPECT_NEAR(pane.Transmittance(c), radiance, 2e-5 + 1e-4 * radiance) << degrees << " degrees";
    ++compared;
  }
  EXPECT_EQ(compared, 11);
}

// Energy: transmittance and reflectance never add up to more than 1, and to 1 exactly for a
// clear pane (transmissivity 1); the transmissivity of a normal transmittance comes back.
TEST(GlassTest, EnergyAndTheTransmissivityOfATransmittance) {
  for (const float t : {0.0f, 0.5f, 0.96f, 1.0f}) {
    const GlassPane pane{t};
    for (float c = 0.01f; c <= 1.0f; c += 0.01f) {
      const float sum = pane.Transmittance(c) + pane.Reflectance(c);
      EXPECT_LE(sum, 1.0f + 1e-5f);
      if (t == 1.0f) {
        EXPECT_NEAR(sum, 1.0f, 1e-5f);
      }
    }
  }
  EXPECT_NEAR(GlassPane::TransmissivityFor(0.8815f), 0.96f, 1e-4f);
  EXPECT_EQ(GlassPane{0.9f}.Transmittance(0.0f), 0.0f);
}

}  // namespace
}  // namespace fenestra
