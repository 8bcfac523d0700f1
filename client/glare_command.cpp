// fenestra glare: the annual glare at a scene's view points (core/optimize/view_glare.h).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "client/cli_util.h"
#include "client/commands.h"
#include "client/dc_options.h"
#include "client/report/annual_outputs.h"
#include "core/metrics/occupancy.h"
#include "core/optimize/view_glare.h"
#include "core/sky/epw.h"
#include "core/sky/sky_matrix.h"

namespace fenestra {
namespace {

struct GlareArgs {
  DcFlags flags;
  std::string weather, hourly;
  double threshold = kDefaultGlareThreshold;
  double target = kDefaultGlareAutonomyTargetPercent;
  OccupancySchedule occupancy;
};

// Each view's figures, a paragraph per view.
void PrintViews(const Scene& scene, const ViewGlareResult& r, const GlareArgs& args) {
  for (size_t i = 0; i < r.views.size(); ++i) {
    const ViewPoint& v = scene.views[i];
    const ViewGlare& g = r.views[i];
    fmt::print("view {} at ({:.2f}, {:.2f}, {:.2f}) looking ({:.2f}, {:.2f}, {:.2f}):\n", v.name,
               v.position.x, v.position.y, v.position.z, v.direction.x, v.direction.y,
               v.direction.z);
    fmt::print(
        "  glare autonomy {:.1f} ± {:.1f} % of {} occupied hours (DGP < {:.2f}; target "
        "{:.0f}%: {})\n",
        g.autonomy_percent, r.autonomy_standard_error[i], g.occupied_hours, args.threshold,
        args.target, g.autonomy_percent >= args.target ? "met" : "not met");
    fmt::print(
        "  mean DGP {:.3f} ± {:.3f}; EN 17037 glare protection {} (DGP {:.3f} exceeded in "
        "at most {:.0f}% of the hours)\n",
        g.mean_dgp, r.mean_dgp_standard_error[i], En17037GlareName(g.en17037), g.dgp_95,
        kEn17037ExceedancePercent);
    fmt::print("  hours imperceptible {}, perceptible {}, disturbing {}, intolerable {}\n",
               g.class_hours[0], g.class_hours[1], g.class_hours[2], g.class_hours[3]);
    if (g.sunlit_hours > 0) {
      fmt::print("  the sun's beam reaches the eye in {} of the hours, a glare source there\n",
                 g.sunlit_hours);
    }
  }
}

// The hourly table: step, then each view's Ev, its standard error, DGPs and the DGP with the
// sun.
void WriteHourly(const std::string& path, const Scene& scene, const SkyMatrix& sky,
                 const ViewGlareResult& r) {
  std::ofstream out(path);
  out << "month,day,hour";
  for (const ViewPoint& v : scene.views) {
    out << "," << CsvField(v.name + " Ev [lx]") << "," << CsvField(v.name + " Ev SE [lx]") << ","
        << CsvField(v.name + " DGPs") << "," << CsvField(v.name + " DGP");
  }
  out << "\n";
  for (size_t s = 0; s < sky.steps.size(); ++s) {
    const SkyStep& step = sky.steps[s];
    out << step.month << "," << step.day << "," << step.hour;
    for (size_t v = 0; v < scene.views.size(); ++v) {
      const double ev = r.eye_lux(static_cast<Eigen::Index>(v), static_cast<Eigen::Index>(s));
      out << "," << ev << ","
          << r.eye_lux_standard_error(static_cast<Eigen::Index>(v), static_cast<Eigen::Index>(s))
          << "," << SimplifiedDgp(ev) << ","
          << r.dgp(static_cast<Eigen::Index>(v), static_cast<Eigen::Index>(s));
    }
    out << "\n";
  }
  out.close();
  if (!out) Fail(absl::UnavailableError(fmt::format("cannot write {}", path)));
}

void RunGlare(const GlareArgs& args) {
  if (args.flags.method != "one-stage") {
    Fail(absl::InvalidArgumentError("glare traces the views by the one-stage method"));
  }
  if (const absl::Status s = CheckMethodFlags(args.flags); !s.ok()) Fail(s);
  DcInput in = ValueOrFail(LoadDcInput(args.flags));
  const std::string weather = args.weather.empty() ? in.scene.site.weather_file : args.weather;
  if (weather.empty()) {
    Fail(absl::InvalidArgumentError(
        "no weather: give --weather, or site.weather_file in the scene"));
  }
  const EpwData epw = ValueOrFail(ReadEpw(weather));
  SkyMatrixOptions sky_options;
  sky_options.ground_reflectance = in.scene.site.ground_reflectance;
  const SkyMatrix sky = ValueOrFail(BuildSkyMatrix(epw, sky_options));
  std::vector<double> hours;
  for (const EpwRecord& record : epw.records) {
    hours.push_back(StepCentreHours(record, epw.records_per_hour));
  }
  const std::vector<bool> occupied = ValueOrFail(OccupiedSteps(hours, args.occupancy));
  ViewGlareOptions options;
  options.tracing = OneStageOptionsFrom(args.flags);
  options.tracing.batches = kDcBatches;  // as dc's, for the errors
  options.threshold = args.threshold;
  const ViewGlareResult r =
      ValueOrFail(ComputeViewGlare(in.scene, in.design, sky, occupied, options, in.backend.get()));
  fmt::print("glare: {} views x {} paths, {} batches, {:.2f} s; occupied {:g}-{:g} h\n",
             r.views.size(), r.paths_per_view, options.tracing.batches, r.seconds,
             args.occupancy.start_hour, args.occupancy.end_hour);
  PrintViews(in.scene, r, args);
  if (!args.hourly.empty()) {
    WriteHourly(args.hourly, in.scene, sky, r);
    fmt::print("hourly: {}\n", args.hourly);
  }
}

}  // namespace

void AddGlareCommand(CLI::App& app) {
  auto args = std::make_shared<GlareArgs>();
  CLI::App* command = app.add_subcommand(
      "glare",
      "The annual glare at the scene's view points: vertical eye illuminance per hour, the "
      "daylight glare probability with the sun as glare source where its beam reaches the eye "
      "(evalglare's DGP; the simplified DGPs = 6.22e-5 Ev + 0.184 beside it), glare autonomy "
      "and the EN 17037 glare protection class");
  AddDcFlags(command, &args->flags);
  command->add_option("--weather", args->weather,
                      "EnergyPlus weather file (default: the scene's site.weather_file)");
  command
      ->add_option("--threshold", args->threshold,
                   "DGP below which an hour counts as free of glare")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  command->add_option("--target", args->target, "Glare autonomy to reach [%]")
      ->check(CLI::Range(0.0, 100.0))
      ->capture_default_str();
  command->add_option("--occupied-from", args->occupancy.start_hour, "Occupied from [h]")
      ->capture_default_str();
  command->add_option("--occupied-to", args->occupancy.end_hour, "Occupied until [h]")
      ->capture_default_str();
  command->add_option("--hourly", args->hourly,
                      "Also write each view's Ev, its standard error, DGPs and DGP per step (CSV)");
  command->callback([args] { RunGlare(*args); });
}

}  // namespace fenestra
