// ValidateJob and PrepareJob refuse every kind of bad job field, naming the field and the
// reason; the example jobs pass.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "core/optimize/job.h"

namespace fenestra {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

const std::string kOffice = FENESTRA_SOURCE_DIR "/examples/city_office";
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The quick tilt job with the four variables free, the scene inline.
v1::Job QuickJob() {
  absl::StatusOr<v1::Job> job = ReadJobFile(kOffice + "/alpha_max_quick.json");
  EXPECT_TRUE(job.ok()) << job.status();
  absl::StatusOr<v1::Scene> scene = ReadSceneProto(kOffice + "/scene.json");
  EXPECT_TRUE(scene.ok()) << scene.status();
  job->clear_scene_file();
  *job->mutable_scene() = *scene;
  return *job;
}

std::string ErrorOf(const v1::Job& job) {
  absl::StatusOr<PreparedJob> prepared = ValidateJob(job, kOffice);
  EXPECT_FALSE(prepared.ok()) << "accepted";
  if (prepared.ok()) return "";
  EXPECT_EQ(prepared.status().code(), absl::StatusCode::kInvalidArgument);
  return std::string(prepared.status().message());
}

v1::DesignVariable& Variable(v1::Job& job, const std::string& name) {
  for (v1::DesignVariable& v : *job.mutable_variables()) {
    if (v.name() == name) return v;
  }
  ADD_FAILURE() << name;
  return *job.add_variables();
}

TEST(JobValidationTest, ExampleJobsPrepare) {
  for (const auto& file : std::filesystem::directory_iterator(kOffice)) {
    if (file.path().filename() == "scene.json") continue;
    absl::StatusOr<v1::Job> job = ReadJobFile(file.path().string());
    ASSERT_TRUE(job.ok()) << job.status();
    absl::StatusOr<PreparedJob> prepared = PrepareJob(*job, kOffice);
    EXPECT_TRUE(prepared.ok()) << file.path() << ": " << prepared.status();
    if (prepared.ok()) {
      EXPECT_EQ(prepared->weather.records.size(), 8760u);
    }
  }
  EXPECT_TRUE(ValidateJob(QuickJob(), kOffice).ok());
}

// The corner office's job (examples/corner_office: two windows) prepares; the outdoor matrix of
// both windows is bounded at the door, where one window's would fit.
TEST(JobValidationTest, AJobOfTwoWindowsPreparesAndItsOutdoorMatrixIsBounded) {
  const std::string corner = FENESTRA_SOURCE_DIR "/examples/corner_office";
  absl::StatusOr<v1::Job> job = ReadJobFile(corner + "/tilt_and_spacing.json");
  ASSERT_TRUE(job.ok()) << job.status();
  absl::StatusOr<PreparedJob> prepared = ValidateJob(*job, corner);
  ASSERT_TRUE(prepared.ok()) << prepared.status();
  EXPECT_EQ(prepared->scene.windows.size(), 2u);
  // 16 x 16 parts of 1152 cells and 8 batches: 3.4 GB for one window, 6.9 GB for two
  v1::Sampling& s = *job->mutable_sampling();
  s.set_basis_cells(1152);
  s.set_window_columns(16);
  s.set_window_rows(16);
  s.set_outdoor_paths(int64_t{1} << 40);
  prepared = ValidateJob(*job, corner);
  ASSERT_FALSE(prepared.ok());
  EXPECT_EQ(prepared.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(prepared.status().message(),
              HasSubstr("job sampling: the outdoor matrix of the scene's 2 windows"));
}

TEST(JobValidationTest, UnknownEnumValues) {
  v1::Job job = QuickJob();
  job.mutable_objective()->set_goal(static_cast<v1::Goal>(42));
  EXPECT_THAT(ErrorOf(job), HasSubstr("job objective.goal: unknown goal 42"));
  job = QuickJob();
  job.mutable_objective()->set_metric(static_cast<v1::Metric>(99));
  EXPECT_THAT(ErrorOf(job), HasSubstr("job objective.metric: unknown metric 99"));
  job = QuickJob();
  job.mutable_scene()->mutable_surfaces(0)->set_side(static_cast<v1::Side>(99));
  EXPECT_THAT(ErrorOf(job), HasSubstr("surfaces[0].side: must be SIDE_INDOOR or SIDE_OUTDOOR"));
  job = QuickJob();
  job.mutable_scene()->mutable_blind()->set_orientation(
      static_cast<v1::VenetianBlind::Orientation>(7));
  EXPECT_THAT(ErrorOf(job), HasSubstr("blind.orientation: must be HORIZONTAL or VERTICAL, got 7"));
}

TEST(JobValidationTest, DesignVariablesOfARealBlind) {
  v1::Job job = QuickJob();
  Variable(job, "width").set_upper(2);
  EXPECT_THAT(ErrorOf(job), HasSubstr("job variables[1]: width must stay within [0.001, 1] m"));
  job = QuickJob();
  Variable(job, "alpha").set_lower(-2);
  EXPECT_THAT(ErrorOf(job), HasSubstr("alpha must stay within [-1.5708, 1.5708] rad"));
  job = QuickJob();
  Variable(job, "spacing").set_upper(-0.1);
  EXPECT_THAT(ErrorOf(job), HasSubstr("empty design range"));
  job = QuickJob();
  Variable(job, "alpha").set_start(2);
  EXPECT_THAT(ErrorOf(job), HasSubstr("job variables[0].start: start 2 is outside [0, 1.5708]"));
  job = QuickJob();
  Variable(job, "alpha").set_upper(kNaN);
  EXPECT_THAT(ErrorOf(job), HasSubstr("must be finite"));
  // Slats as thick as they are wide, at some design of the ranges
  job = QuickJob();
  v1::DesignVariable& thickness = Variable(job, "thickness");
  thickness.set_upper(0.1);
  thickness.set_fixed(false);
  EXPECT_THAT(ErrorOf(job), AllOf(HasSubstr("job variables: with the scene's blind: slats up to "
                                            "0.1 m thick and from 0.05 m wide")));
}

// A job without design variables has nothing to search (RunVns would refuse it after the
// outdoor stage); one whose variables are all fixed evaluates its start design, and passes.
TEST(JobValidationTest, AtLeastOneDesignVariable) {
  v1::Job job = QuickJob();
  job.clear_variables();
  EXPECT_THAT(ErrorOf(job), HasSubstr("job variables: none given; the search needs at least one "
                                      "design variable (alpha, width, spacing, thickness or "
                                      "finish"));
  job.mutable_scene()->clear_blind();  // nothing to design either way: the variables named
  EXPECT_THAT(ErrorOf(job), HasSubstr("job variables: none given"));
  job = QuickJob();
  for (v1::DesignVariable& v : *job.mutable_variables()) v.set_fixed(true);
  EXPECT_TRUE(ValidateJob(job, kOffice).ok()) << ErrorOf(job);
}

// The quick tilt job with slat materials to choose from (white, black, a metal and a glass in
// the scene) and a finish variable over `finishes` (material, outer material or "" for none).
v1::Job FinishJob(const std::vector<std::pair<std::string, std::string>>& finishes) {
  v1::Job job = QuickJob();
  v1::Scene& scene = *job.mutable_scene();
  v1::Material* white = scene.add_materials();
  white->set_name("white");
  white->set_reflectance(0.8);
  scene.add_materials()->set_name("black");
  v1::Material* alu = scene.add_materials();
  alu->set_name("alu");
  alu->mutable_metal()->set_reflectance(0.8);
  alu->mutable_metal()->set_specularity(0.9);
  alu->mutable_metal()->set_roughness(0.05);
  v1::Material* pane = scene.add_materials();
  pane->set_name("pane");
  pane->mutable_glass()->set_transmittance(0.88);
  v1::DesignVariable& finish = *job.add_variables();
  finish.set_name("finish");
  for (const auto& [material, outer] : finishes) {
    v1::BlindFinish& f = *finish.add_finishes();
    f.set_material(material);
    if (!outer.empty()) f.set_outer_material(outer);
  }
  return job;
}

// A finish variable: its finishes resolved against the scene's materials, its range the whole
// list and its step 1 when unset, its values checked as indices.
TEST(JobValidationTest, FinishVariableListsTheScenesSlatMaterials) {
  v1::Job job = FinishJob({{"white", ""}, {"black", "alu"}, {"alu", "alu"}});
  absl::StatusOr<PreparedJob> prepared = ValidateJob(job, kOffice);
  ASSERT_TRUE(prepared.ok()) << prepared.status();
  const v1::DesignVariable& filled = prepared->job.variables(4);
  EXPECT_EQ(filled.lower(), 0);
  EXPECT_EQ(filled.upper(), 2);
  EXPECT_EQ(filled.start(), 0);
  EXPECT_EQ(filled.step(), 1);
  const std::vector<Material>& materials = prepared->scene.materials;
  ASSERT_EQ(prepared->finishes.size(), 3u);
  const auto name = [&](uint32_t index) { return materials[index].name; };
  EXPECT_EQ(name(prepared->finishes[0].material), "white");
  EXPECT_EQ(name(prepared->finishes[0].outer_material), "white");  // absent: the material
  EXPECT_EQ(name(prepared->finishes[1].material), "black");
  EXPECT_EQ(name(prepared->finishes[1].outer_material), "alu");
  EXPECT_EQ(name(prepared->finishes[2].outer_material), "alu");
  // A part of the list, started within it; fixed
  Variable(job, "finish").set_lower(1);
  Variable(job, "finish").set_upper(2);
  Variable(job, "finish").set_start(2);
  Variable(job, "finish").set_step(1);
  EXPECT_TRUE(ValidateJob(job, kOffice).ok()) << ErrorOf(job);
  job = FinishJob({{"white", ""}, {"black", ""}});
  Variable(job, "finish").set_fixed(true);
  Variable(job, "finish").set_start(1);
  prepared = ValidateJob(job, kOffice);
  ASSERT_TRUE(prepared.ok()) << prepared.status();
  EXPECT_EQ(prepared->job.variables(4).upper(), 1);
  // Without a finish variable, no finishes
  prepared = ValidateJob(QuickJob(), kOffice);
  ASSERT_TRUE(prepared.ok()) << prepared.status();
  EXPECT_TRUE(prepared->finishes.empty());
}

TEST(JobValidationTest, BadFinishesAreRefused) {
  // Materials the scene does not have, or a glass
  EXPECT_THAT(ErrorOf(FinishJob({{"white", ""}, {"brick", ""}})),
              HasSubstr("job variables[4].finishes[1].material: unknown material 'brick'"));
  EXPECT_THAT(ErrorOf(FinishJob({{"white", "brick"}})),
              HasSubstr("job variables[4].finishes[0].outer_material: unknown material 'brick'"));
  EXPECT_THAT(ErrorOf(FinishJob({{"pane", ""}})),
              HasSubstr("job variables[4].finishes[0].material: 'pane' is a glass: slats of glass "
                        "make no blind"));
  EXPECT_THAT(ErrorOf(FinishJob({{"white", "pane"}})),
              HasSubstr("job variables[4].finishes[0].outer_material: 'pane' is a glass"));
  // None, or too many
  EXPECT_THAT(ErrorOf(FinishJob({})),
              HasSubstr("job variables[4].finishes: the finish variable lists 1 to 64 finishes, "
                        "got 0"));
  EXPECT_THAT(
      ErrorOf(FinishJob(std::vector<std::pair<std::string, std::string>>(65, {"white", ""}))),
      HasSubstr("lists 1 to 64 finishes, got 65"));
  // Values that are no index of the list
  const auto with = [](auto edit) {
    v1::Job job = FinishJob({{"white", ""}, {"black", ""}});
    edit(Variable(job, "finish"));
    return ErrorOf(job);
  };
  EXPECT_THAT(with([](v1::DesignVariable& v) { v.set_upper(2); }),
              HasSubstr("job variables[4].upper: must be the index of one of the 2 finishes, a "
                        "whole number in [0, 1], got 2"));
  EXPECT_THAT(with([](v1::DesignVariable& v) { v.set_lower(-1); }),
              HasSubstr("job variables[4].lower: must be the index"));
  EXPECT_THAT(with([](v1::DesignVariable& v) { v.set_start(0.5); }),
              HasSubstr("job variables[4].start: must be the index of one of the 2 finishes"));
  EXPECT_THAT(with([](v1::DesignVariable& v) { v.set_start(kNaN); }),
              HasSubstr("job variables[4].start"));
  EXPECT_THAT(with([](v1::DesignVariable& v) {
                v.set_lower(1);
                v.set_upper(1);
                v.set_start(0);
              }),
              HasSubstr("job variables[4].start: start 0 is outside [1, 1]"));
  EXPECT_THAT(with([](v1::DesignVariable& v) { v.set_step(0.5); }),
              HasSubstr("job variables[4].step: must be 1 or unset"));
  // Finishes on another variable
  v1::Job job = QuickJob();
  Variable(job, "alpha").add_finishes()->set_material("blind");
  EXPECT_THAT(ErrorOf(job),
              HasSubstr("job variables[0].finishes: only the finish variable lists finishes"));
  // Twice
  job = FinishJob({{"white", ""}});
  *job.add_variables() = job.variables(4);
  EXPECT_THAT(ErrorOf(job), HasSubstr("job variables[5].name: variable 'finish' given twice"));
}

// Slats narrow enough for more than kMaxBlindSlats at some design of the job's ranges: the
// scene's slats, 5 cm at the narrowest, fit its 4 km window 80001 times; 2.5 cm ones would
// need 160001
TEST(JobValidationTest, TooManySlatsAtSomeDesignOfTheJob) {
  v1::Job job = QuickJob();
  job.mutable_scene()->mutable_window()->set_height_m(4000);
  v1::DesignVariable& width = Variable(job, "width");
  width.set_lower(0.025);
  width.set_fixed(false);
  EXPECT_THAT(ErrorOf(job),
              AllOf(HasSubstr("job variables: with the scene's blind: slats from 0.025 m wide need "
                              "up to 16000"),
                    HasSubstr("a blind has at most 100000")));
}

// A sensor clear of the scene's slats (up to 15 cm wide) but where 60 cm slats would turn
TEST(JobValidationTest, SensorsClearOfTheBlindAtEveryDesignOfTheJob) {
  v1::Job job = QuickJob();
  v1::Sensor& sensor = *job.mutable_scene()->add_sensors();
  sensor.set_name("by the window");
  sensor.mutable_position()->set_y(-0.4);
  sensor.mutable_position()->set_z(7.65);
  sensor.mutable_direction()->set_z(1);
  ASSERT_TRUE(ValidateJob(job, kOffice).ok());
  v1::DesignVariable& width = Variable(job, "width");
  width.set_upper(0.6);
  width.set_fixed(false);
  EXPECT_THAT(ErrorOf(job), HasSubstr("sensors[9] (\"by the window\") at (0, -0.4, 7.65) lies in "
                                      "the space the blind's slats take"));
}

TEST(JobValidationTest, MetricSettings) {
  const auto with = [](auto edit) {
    v1::Job job = QuickJob();
    edit(*job.mutable_metrics());
    return ErrorOf(job);
  };
  EXPECT_THAT(with([](v1::MetricSettings& m) { m.set_occupied_start_h(25); }),
              HasSubstr("job metrics.occupied_start_h: must be in [0, 24] h, got 25"));
  EXPECT_THAT(with([](v1::MetricSettings& m) { m.set_occupied_end_h(-3); }),
              HasSubstr("job metrics.occupied_end_h: must be in [0, 24] h, got -3"));
  EXPECT_THAT(with([](v1::MetricSettings& m) { m.set_occupied_start_h(kNaN); }),
              HasSubstr("metrics.occupied_start_h"));
  EXPECT_THAT(with([](v1::MetricSettings& m) { m.set_occupied_end_h(8); }),
              HasSubstr("occupied_start_h and occupied_end_h must differ"));
  EXPECT_THAT(with([](v1::MetricSettings& m) { m.set_sda_time_fraction_percent(1e300); }),
              HasSubstr("job metrics.sda_time_fraction_percent: must be in (0, 100] %"));
  EXPECT_THAT(with([](v1::MetricSettings& m) { m.set_udi_lower_lux(3000); }),
              HasSubstr("udi_lower_lux 3000 must be below udi_upper_lux 3000"));
  EXPECT_THAT(with([](v1::MetricSettings& m) { m.set_udi_lower_lux(-100); }),
              HasSubstr("job metrics.udi_lower_lux: must be in [0, 1e+06] lx, got -100"));
  EXPECT_THAT(with([](v1::MetricSettings& m) { m.set_udi_upper_lux(kNaN); }),
              HasSubstr("metrics.udi_upper_lux"));
  EXPECT_THAT(with([](v1::MetricSettings& m) { m.set_da_threshold_lux(-300); }),
              HasSubstr("job metrics.da_threshold_lux: must be in (0, 1e+06] lx"));
  // The direct sun's settings: ASE's thresholds and an operated blind's rule
  EXPECT_THAT(with([](v1::MetricSettings& m) { m.set_ase_threshold_lux(-1000); }),
              HasSubstr("job metrics.ase_threshold_lux: must be in (0, 1e+06] lx"));
  EXPECT_THAT(with([](v1::MetricSettings& m) { m.set_ase_threshold_lux(kNaN); }),
              HasSubstr("metrics.ase_threshold_lux"));
  EXPECT_THAT(with([](v1::MetricSettings& m) { m.set_ase_threshold_lux(1e300); }),
              HasSubstr("metrics.ase_threshold_lux"));
  EXPECT_THAT(with([](v1::MetricSettings& m) { m.set_ase_min_hours(-5); }),
              HasSubstr("job metrics.ase_min_hours: must be in [1, 8784] h, got -5"));
  EXPECT_THAT(with([](v1::MetricSettings& m) { m.set_ase_min_hours(2147483647); }),
              HasSubstr("job metrics.ase_min_hours"));
  EXPECT_THAT(with([](v1::MetricSettings& m) { m.set_operation_sensor_percent(150); }),
              HasSubstr("job metrics.operation_sensor_percent: must be in (0, 100] %"));
  EXPECT_THAT(with([](v1::MetricSettings& m) { m.set_operation_sensor_percent(kNaN); }),
              HasSubstr("metrics.operation_sensor_percent"));
  EXPECT_THAT(with([](v1::MetricSettings& m) { m.set_operation_threshold_lux(-1); }),
              HasSubstr("job metrics.operation_threshold_lux"));
  // Unset: the defaults, from MetricOptions
  absl::StatusOr<PreparedJob> prepared =
      ValidateJob(QuickJob(), FENESTRA_SOURCE_DIR "/examples/city_office");
  ASSERT_TRUE(prepared.ok()) << prepared.status();
  const MetricOptions defaults;
  EXPECT_EQ(prepared->job.metrics().ase_threshold_lux(), defaults.ase_threshold_lux);
  EXPECT_EQ(prepared->job.metrics().ase_min_hours(), defaults.ase_min_hours);
  EXPECT_EQ(prepared->job.metrics().operation_sensor_percent(), defaults.operation_sensor_percent);
  EXPECT_EQ(prepared->job.metrics().operation_threshold_lux(), defaults.operation_threshold_lux);
}

TEST(JobValidationTest, BudgetObjectiveAndSampling) {
  v1::Job job = QuickJob();
  job.mutable_budget()->set_max_seconds(std::numeric_limits<double>::infinity());
  EXPECT_THAT(ErrorOf(job), HasSubstr("job budget.max_seconds: must be a finite number >= 0"));
  job = QuickJob();
  job.mutable_objective()->set_target(kNaN);
  EXPECT_THAT(ErrorOf(job), HasSubstr("job objective.target: must be in [0, 100] %"));
  job = QuickJob();
  job.mutable_objective()->set_target_tolerance(-1);
  EXPECT_THAT(ErrorOf(job), HasSubstr("job objective.target_tolerance"));
  job = QuickJob();
  job.mutable_sampling()->set_indoor_bounces(1'000'000);
  EXPECT_THAT(ErrorOf(job), HasSubstr("bounces must be in [0, 1000], or -1 for unlimited"));
  job = QuickJob();  // 0 is no reflection; unset is the default, unlimited
  job.mutable_sampling()->set_indoor_bounces(0);
  job.mutable_sampling()->clear_outdoor_bounces();
  const absl::StatusOr<PreparedJob> accepted = ValidateJob(job, kOffice);
  EXPECT_TRUE(accepted.ok()) << accepted.status();
  const absl::StatusOr<v1::Sampling> resolved = ResolveSampling(job.sampling());
  ASSERT_TRUE(resolved.ok()) << resolved.status();
  EXPECT_EQ(resolved->indoor_bounces(), 0);
  EXPECT_EQ(resolved->outdoor_bounces(), kUnlimitedBounces);
  job = QuickJob();  // an outdoor matrix of 22 GB
  job.mutable_sampling()->set_basis_cells(1152);
  job.mutable_sampling()->set_batches(64);
  job.mutable_sampling()->set_outdoor_paths(100'000'000);
  EXPECT_THAT(ErrorOf(job),
              HasSubstr("job sampling: the outdoor matrix with its batches could take "
                        "21702 MiB (1152 direction cells x 16x16 window parts at "
                        "most, automatic x 64 batches), more than the 4096 MiB"));
  job.mutable_sampling()->set_window_columns(4);
  job.mutable_sampling()->set_window_rows(3);
  EXPECT_TRUE(ValidateJob(job, kOffice).ok()) << ErrorOf(job);
  job = QuickJob();
  job.add_neighborhoods()->set_radius(kNaN);
  EXPECT_THAT(ErrorOf(job), HasSubstr("job neighborhoods[0]: needs variables >= 0"));
}

// Racing's settings: k a finite number in its range, rounds increasing eighths below all of
// them, a long list refused; the defaults filled in, racing itself left to the backend.
TEST(JobValidationTest, RacingSettings) {
  for (const double k : {kNaN, -4.0, 1.0, 1e9, std::numeric_limits<double>::infinity()}) {
    v1::Job job = QuickJob();
    job.mutable_sampling()->set_racing_standard_errors(k);
    EXPECT_THAT(ErrorOf(job), HasSubstr("sampling.racing_standard_errors")) << k;
  }
  for (const std::vector<int>& rounds : std::vector<std::vector<int>>{
           {0}, {8}, {-1}, {2, 1}, {1, 1}, {1, 2, 3, 4, 5, 6, 7, 7}, {1 << 30}}) {
    v1::Job job = QuickJob();
    for (const int parts : rounds) job.mutable_sampling()->add_racing_rounds(parts);
    EXPECT_THAT(ErrorOf(job), HasSubstr("sampling.racing_rounds"));
  }
  v1::Job many = QuickJob();
  for (int i = 0; i < 100'000; ++i) many.mutable_sampling()->add_racing_rounds(1 + i % 7);
  EXPECT_THAT(ErrorOf(many), HasSubstr("sampling.racing_rounds"));

  absl::StatusOr<PreparedJob> prepared = ValidateJob(QuickJob(), kOffice);
  ASSERT_TRUE(prepared.ok()) << prepared.status();
  const v1::Sampling& sampling = prepared->job.sampling();
  EXPECT_FALSE(sampling.has_racing());  // decided by the backend (DesignTallies::RacesByDefault)
  EXPECT_EQ(sampling.racing_standard_errors(), 4);
  EXPECT_THAT(sampling.racing_rounds(), ::testing::ElementsAre(1, 2));
  v1::Job custom = QuickJob();
  custom.mutable_sampling()->set_racing_standard_errors(2.5);
  custom.mutable_sampling()->add_racing_rounds(3);
  custom.mutable_sampling()->add_racing_rounds(7);
  EXPECT_TRUE(ValidateJob(custom, kOffice).ok()) << ErrorOf(custom);
}

// A constraint's metric known, its bound set, its value a share; at most 8 of them; the
// standard errors a design may be beyond a bound in (0, 100], the default filled in where
// there are constraints.
TEST(JobValidationTest, Constraints) {
  const auto with = [](v1::Metric metric, v1::Constraint::Bound bound, double value) {
    v1::Job job = QuickJob();
    v1::Constraint& c = *job.mutable_objective()->add_constraints();
    c.set_metric(metric);
    c.set_bound(bound);
    c.set_value(value);
    return job;
  };
  v1::Job job = with(v1::METRIC_ASE, v1::Constraint::AT_MOST, 10);
  absl::StatusOr<PreparedJob> prepared = ValidateJob(job, kOffice);
  ASSERT_TRUE(prepared.ok()) << prepared.status();
  EXPECT_EQ(prepared->job.objective().constraint_standard_errors(), 1);
  prepared = ValidateJob(QuickJob(), kOffice);  // no constraints: left unset
  ASSERT_TRUE(prepared.ok()) << prepared.status();
  EXPECT_EQ(prepared->job.objective().constraint_standard_errors(), 0);

  EXPECT_THAT(ErrorOf(with(static_cast<v1::Metric>(99), v1::Constraint::AT_MOST, 10)),
              HasSubstr("job objective.constraints[0].metric: unknown metric 99"));
  EXPECT_THAT(ErrorOf(with(v1::METRIC_DA, v1::Constraint::BOUND_UNSPECIFIED, 10)),
              HasSubstr("job objective.constraints[0].bound: must be AT_MOST or AT_LEAST"));
  EXPECT_THAT(ErrorOf(with(v1::METRIC_DA, static_cast<v1::Constraint::Bound>(5), 10)),
              HasSubstr("job objective.constraints[0].bound"));
  for (const double bad : {kNaN, -0.5, 100.5, std::numeric_limits<double>::infinity()}) {
    EXPECT_THAT(ErrorOf(with(v1::METRIC_SDA, v1::Constraint::AT_LEAST, bad)),
                HasSubstr("job objective.constraints[0].value: must be in [0, 100] %"))
        << bad;
  }
  job = with(v1::METRIC_SDA, v1::Constraint::AT_LEAST, 50);
  *job.mutable_objective()->add_constraints() = job.objective().constraints(0);
  job.mutable_objective()->mutable_constraints(1)->set_value(101);
  EXPECT_THAT(ErrorOf(job), HasSubstr("job objective.constraints[1].value"));
  job = QuickJob();
  for (int i = 0; i < 9; ++i) {
    *job.mutable_objective()->add_constraints() =
        with(v1::METRIC_UDI_EXCEEDED, v1::Constraint::AT_MOST, 5).objective().constraints(0);
  }
  EXPECT_THAT(ErrorOf(job), HasSubstr("job objective.constraints: at most 8 constraints, got 9"));
  job.mutable_objective()->mutable_constraints()->RemoveLast();
  EXPECT_TRUE(ValidateJob(job, kOffice).ok()) << ErrorOf(job);

  for (const double k : {kNaN, -1.0, 100.5, std::numeric_limits<double>::infinity()}) {
    job = with(v1::METRIC_ASE, v1::Constraint::AT_MOST, 10);
    job.mutable_objective()->set_constraint_standard_errors(k);
    EXPECT_THAT(ErrorOf(job), HasSubstr("job objective.constraint_standard_errors: must be in "
                                        "(0, 100] (0 = the default, 1)"))
        << k;
  }
  job = with(v1::METRIC_ASE, v1::Constraint::AT_MOST, 10);
  job.mutable_objective()->set_constraint_standard_errors(2.5);
  prepared = ValidateJob(job, kOffice);
  ASSERT_TRUE(prepared.ok()) << prepared.status();
  EXPECT_EQ(prepared->job.objective().constraint_standard_errors(), 2.5);
}

TEST(JobValidationTest, CandidatesAtOnce) {
  for (const int n : {-1, kMaxCandidatesAtOnce + 1, 1 << 30, INT32_MIN}) {
    v1::Job job = QuickJob();
    job.mutable_sampling()->set_candidates_at_once(n);
    EXPECT_THAT(ErrorOf(job), HasSubstr("sampling.candidates_at_once")) << n;
  }
  for (const int n : {0, 1, kMaxCandidatesAtOnce}) {
    v1::Job job = QuickJob();
    job.mutable_sampling()->set_candidates_at_once(n);
    absl::StatusOr<PreparedJob> prepared = ValidateJob(job, kOffice);
    ASSERT_TRUE(prepared.ok()) << prepared.status();
    EXPECT_EQ(prepared->job.sampling().candidates_at_once(), n);  // 0: decided by the backend
  }
}

// Sampling.sequence: unset is the default (pseudo-random), an unknown value is refused, and
// the outdoor matrix of Sobol draws is cached under a key of its own.
TEST(JobValidationTest, Sequence) {
  v1::Job job = QuickJob();
  job.mutable_sampling()->set_sequence(static_cast<v1::Sequence>(7));
  EXPECT_THAT(ErrorOf(job), HasSubstr("job sampling.sequence: unknown sequence"));
  job = QuickJob();
  absl::StatusOr<PreparedJob> plain = ValidateJob(job, kOffice);
  ASSERT_TRUE(plain.ok()) << plain.status();
  EXPECT_EQ(plain->job.sampling().sequence(), v1::SEQUENCE_PSEUDO_RANDOM);
  job.mutable_sampling()->set_sequence(v1::SEQUENCE_SOBOL);
  absl::StatusOr<PreparedJob> sobol = ValidateJob(job, kOffice);
  ASSERT_TRUE(sobol.ok()) << sobol.status();
  EXPECT_EQ(sobol->job.sampling().sequence(), v1::SEQUENCE_SOBOL);
  EXPECT_NE(OutdoorMatrixKey(sobol->scene, sobol->job.sampling()),
            OutdoorMatrixKey(plain->scene, plain->job.sampling()));
}

TEST(JobValidationTest, Names) {
  v1::Job job = QuickJob();
  job.set_name("tilt\n2024-01-01 [info] job-9 succeeded");
  EXPECT_THAT(ErrorOf(job), HasSubstr("job name: holds the control character U+000A at offset 4"));
  job = QuickJob();
  job.mutable_scene()->set_name(std::string(300, 'x'));
  EXPECT_THAT(ErrorOf(job), HasSubstr("job scene.name: is 300 bytes long, more than the 256"));
  job = QuickJob();
  job.mutable_scene()->mutable_sensors(2)->set_name("desk \xff");
  EXPECT_THAT(ErrorOf(job),
              HasSubstr("job scene.sensors[2].name: is not valid UTF-8 (byte 0xFF at offset 5)"));
  job = QuickJob();
  job.mutable_scene()->mutable_materials(1)->set_name("office\x1b[2J");
  EXPECT_THAT(ErrorOf(job), HasSubstr("job scene.materials[1].name: holds the control character "
                                      "U+001B"));
  job = QuickJob();
  job.mutable_scene()->set_name("Büro Süd 東");  // UTF-8 is welcome
  EXPECT_TRUE(ValidateJob(job, kOffice).ok());
}

TEST(JobValidationTest, PrepareRefusesBadWeather) {
  const std::string dir = ::testing::TempDir() + "/job_validation_weather";
  std::filesystem::create_directories(dir);
  std::ifstream in(FENESTRA_SOURCE_DIR "/examples/weather/URY_Montevideo.865800_IWEC.epw");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  text.resize(text.size() / 2);  // cut in the middle of the year
  std::ofstream(dir + "/cut.epw") << text;
  v1::Job job = QuickJob();
  job.set_weather_file("cut.epw");
  absl::StatusOr<PreparedJob> prepared = PrepareJob(job, dir);
  ASSERT_FALSE(prepared.ok());
  EXPECT_THAT(prepared.status().message(),
              AllOf(HasSubstr("cut.epw, line "), HasSubstr("truncated")));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace fenestra
