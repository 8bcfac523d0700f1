// The DGP with the sun as glare source (core/optimize/view_glare.h) against evalglare on
// Radiance's rendered fisheye images of the city office's two views, for three hours of
// Montevideo: the sun in view of the first view, a clear hour with the sun out of view and an
// overcast one (tests/data/evalglare/reference.csv, made by bench/evalglare/make_reference.sh;
// bench/evalglare/README.md). evalglare counts only the solar disc as glare source there, as
// Fenestra's DGP does. The tolerance is 0.02 in DGP. Ev: not below rtrace's (less 3 standard
// errors; those are below 3% of Ev), and within 25% of it: rtrace stops at 6 ambient bounces (-ab
// 6) where Fenestra's paths go on, and with walls of reflectance 0.8 the later reflections carry
// 1-20% of an eye's light (most at the desk 2.5 m in). Seed fixed.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/geometry/scene_proto.h"
#include "core/metrics/occupancy.h"
#include "core/optimize/job.h"
#include "core/optimize/view_glare.h"
#include "core/sky/epw.h"
#include "core/trace/room_check.h"
#include "tests/core/optimize/scene_year.h"

namespace fenestra {
namespace {

const std::string kDir = FENESTRA_SOURCE_DIR "/tests/data/evalglare";

struct Reference {
  int view = 0, month = 0, day = 0;
  double hour = 0, ev_rtrace = 0, dgp_evalglare = 0;
};

// reference.csv's rows: view, month, day, hour, ..., ev_rtrace_lx (7th), ..., dgp_sun_only (9th)
std::vector<Reference> ReadReference() {
  std::ifstream in(kDir + "/reference.csv");
  EXPECT_TRUE(in.good());
  std::vector<Reference> rows;
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream fields(line);
    for (std::string x; std::getline(fields, x, ',');) f.push_back(x);
    EXPECT_GE(f.size(), 9u) << line;
    if (f.size() < 9) continue;
    rows.push_back({std::stoi(f[0]), std::stoi(f[1]), std::stoi(f[2]), std::stod(f[3]),
                    std::stod(f[6]), std::stod(f[8])});
  }
  return rows;
}

TEST(EvalglareReferenceTest, DgpWithTheSunMatchesEvalglareWithin002) {
  const std::string path = kDir + "/city_office_views.json";
  absl::StatusOr<v1::Scene> proto = ReadSceneProto(path);
  ASSERT_TRUE(proto.ok()) << proto.status();
  absl::StatusOr<Scene> scene = ValidateScene(*proto, path);
  ASSERT_TRUE(scene.ok()) << scene.status();
  const SceneYear year = YearOf(*scene);
  const std::vector<double>& hours = year.hours;
  // The design the references were rendered with: horizontal slats, 0.1 m apart
  absl::StatusOr<BlindDesign> design =
      DesignWithOverrides(*scene, {{"alpha", 0}, {"spacing", 0.1}});
  ASSERT_TRUE(design.ok()) << design.status();
  ViewGlareOptions options;
  options.tracing.paths_per_sensor = 400000;
  options.tracing.batches = 32;
  options.tracing.seed = 1;
  absl::StatusOr<ViewGlareResult> r =
      ComputeViewGlare(*scene, *design, year.sky, year.occupied, options);
  ASSERT_TRUE(r.ok()) << r.status();

  const std::vector<Reference> references = ReadReference();
  ASSERT_EQ(references.size(), 6u);  // two views, three hours
  int with_sun = 0;
  for (const Reference& ref : references) {
    // The record of the reference's hour
    int step = -1;
    for (size_t s = 0; s < year.sky.steps.size(); ++s) {
      if (year.sky.steps[s].month == ref.month && year.sky.steps[s].day == ref.day &&
          std::abs(hours[s] - ref.hour) < 1e-6) {
        step = static_cast<int>(s);
      }
    }
    ASSERT_GE(step, 0) << ref.month << "/" << ref.day << " " << ref.hour;
    const double dgp = r->dgp(ref.view, step), ev = r->eye_lux(ref.view, step);
    const double se = r->eye_lux_standard_error(ref.view, step);
    with_sun += r->sun_lux(ref.view, step) > 0 ? 1 : 0;
    SCOPED_TRACE(testing::Message()
                 << "view " << ref.view << ", " << ref.month << "/" << ref.day << " " << ref.hour
                 << " h: Ev " << ev << " ± " << se << " lx against rtrace's " << ref.ev_rtrace);
    EXPECT_LT(se, 0.03 * ev);
    EXPECT_GT(ev, ref.ev_rtrace - 3 * se);
    EXPECT_NEAR(ev, ref.ev_rtrace, 0.25 * ref.ev_rtrace);
    EXPECT_NEAR(dgp, ref.dgp_evalglare, 0.02);
  }
  EXPECT_EQ(with_sun, 1);  // the first view's sunny hour, and no other
}

}  // namespace
}  // namespace fenestra
