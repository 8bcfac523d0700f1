#include "client/report/annual_outputs.h"

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <map>

#include "absl/strings/str_cat.h"
#include "core/common/atomic_file.h"
#include "core/common/radiance_matrix.h"
#include "core/common/status_macros.h"
#include "core/geometry/obj_io.h"
#include "core/geometry/scene.h"
#include "core/metrics/illuminance.h"
#include "core/optimize/design_variables.h"

namespace fenestra {
namespace {

// The result's hourly illuminance, checked for consistent sizes.
absl::StatusOr<const v1::HourlyIlluminance*> Hourly(const v1::JobResult& result) {
  if (!result.has_best_hourly()) {
    return absl::FailedPreconditionError(
        "the result holds no hourly illuminance (the search was cancelled, the job had more "
        "sensors x time steps than a result holds, or the result predates it)");
  }
  const v1::HourlyIlluminance& h = result.best_hourly();
  const int64_t steps = h.month_size();
  if (h.day_size() != steps || h.hour_size() != steps ||
      h.illuminance_lux_size() != static_cast<int64_t>(h.sensors_size()) * steps) {
    return absl::InvalidArgumentError(absl::StrCat("best_hourly: ", h.illuminance_lux_size(),
                                                   " values do not fill ", h.sensors_size(),
                                                   " sensors x ", steps, " time steps"));
  }
  return &h;
}

absl::Status WithFlag(const std::string& flag, const absl::Status& status) {
  if (status.ok()) return status;
  return absl::Status(status.code(), absl::StrCat(flag, ": ", status.message()));
}

}  // namespace

std::string CsvField(const std::string& text) {
  if (text.find_first_of(",\"\r\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (const char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

void AddAnnualOutputOptions(CLI::App* command, AnnualOutputPaths& paths) {
  command->add_option("--hourly-csv", paths.hourly_csv,
                      "Best design's hourly illuminance as CSV (month, day, hour, a column [lx] "
                      "per sensor)");
  command->add_option("--hourly-matrix", paths.hourly_matrix,
                      "The same as a Radiance matrix (sensors x time steps, 3 components, W/m2 "
                      "as dctimestep writes)");
  command->add_option("--best-obj", paths.best_obj,
                      "Best design's scene (the blind included) as OBJ");
}

absl::Status WriteHourlyCsv(const v1::JobResult& result, const std::string& path) {
  FENESTRA_ASSIGN_OR_RETURN(hourly, Hourly(result));
  const v1::HourlyIlluminance& h = *hourly;
  const int steps = h.month_size();
  return WriteFileAtomically(path, [&](std::ostream& out) {
    out << "month,day,hour";
    for (const std::string& name : h.sensors()) out << ',' << CsvField(name);
    out << '\n';
    for (int j = 0; j < steps; ++j) {
      std::string row = fmt::format("{},{},{}", h.month(j), h.day(j), h.hour(j));
      for (int i = 0; i < h.sensors_size(); ++i) {
        row += fmt::format(",{}", h.illuminance_lux(i * steps + j));
      }
      out << row << '\n';
    }
    return absl::OkStatus();
  });
}

absl::Status WriteHourlyMatrix(const v1::JobResult& result, const std::string& path) {
  FENESTRA_ASSIGN_OR_RETURN(hourly, Hourly(result));
  const v1::HourlyIlluminance& h = *hourly;
  const int steps = h.month_size();
  Matrix irradiance(h.sensors_size(), steps);
  for (int i = 0; i < h.sensors_size(); ++i) {
    for (int j = 0; j < steps; ++j) {
      irradiance(i, j) = h.illuminance_lux(i * steps + j) / kWhiteEfficacyLumensPerWatt;
    }
  }
  return WriteRadianceMatrix(path, irradiance, MatrixFormat::kAscii, 3);
}

absl::Status WriteBestObj(const v1::JobResult& result, const std::string& path) {
  if (!result.job().has_scene()) {
    return absl::FailedPreconditionError("the result holds no scene (it predates them)");
  }
  FENESTRA_ASSIGN_OR_RETURN(scene, BuildScene(result.job().scene(), "the result's job.scene"));
  const std::map<std::string, double> best(result.best_design().begin(),
                                           result.best_design().end());
  FENESTRA_ASSIGN_OR_RETURN(design, JobDesignWithOverrides(scene, result.job(), best));
  return WriteSceneObj(path, scene, design).status();
}

std::string AnnualOutputLines(const AnnualOutputPaths& paths) {
  std::string lines;
  if (!paths.hourly_csv.empty()) lines += "hourly illuminance (CSV): " + paths.hourly_csv + "\n";
  if (!paths.hourly_matrix.empty()) {
    lines += "hourly illuminance (Radiance matrix): " + paths.hourly_matrix + "\n";
  }
  if (!paths.best_obj.empty()) lines += "best design (OBJ): " + paths.best_obj + "\n";
  return lines;
}

absl::Status WriteAnnualOutputs(const v1::JobResult& result, const AnnualOutputPaths& paths) {
  if (!paths.hourly_csv.empty()) {
    FENESTRA_RETURN_IF_ERROR(WithFlag("--hourly-csv", WriteHourlyCsv(result, paths.hourly_csv)));
  }
  if (!paths.hourly_matrix.empty()) {
    FENESTRA_RETURN_IF_ERROR(
        WithFlag("--hourly-matrix", WriteHourlyMatrix(result, paths.hourly_matrix)));
  }
  if (!paths.best_obj.empty()) {
    FENESTRA_RETURN_IF_ERROR(WithFlag("--best-obj", WriteBestObj(result, paths.best_obj)));
  }
  return absl::OkStatus();
}

}  // namespace fenestra
