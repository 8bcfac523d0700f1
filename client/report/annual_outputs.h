#pragma once

// Annual results of a job for other tools, from its result (job.proto, JobResult): the best
// design's hourly illuminance as CSV and as a Radiance matrix, and the best design's
// assembled scene as OBJ. `fenestra optimize --local` and `fenestra job result` write them.
#include <string>

#include "absl/status/status.h"
#include "fenestra/v1/job.pb.h"

namespace CLI {
class App;
}  // namespace CLI

namespace fenestra {

// Which files to write; empty = not asked for.
struct AnnualOutputPaths {
  std::string hourly_csv, hourly_matrix, best_obj;
};

// A CSV field, quoted when it holds a separator, a quote or a line break (RFC 4180).
std::string CsvField(const std::string& text);

// Adds --hourly-csv, --hourly-matrix and --best-obj to `command`.
void AddAnnualOutputOptions(CLI::App* command, AnnualOutputPaths& paths);

// The best design's illuminance as CSV: a header "month,day,hour,<sensor names>", then one
// row per time step: month, day, local standard time of the step's centre [h], and each
// sensor's illuminance [lx] (as the result stores it). FailedPrecondition when the result
// holds no hourly illuminance.
absl::Status WriteHourlyCsv(const v1::JobResult& result, const std::string& path);

// The same as a Radiance matrix in dctimestep's output layout: rows = sensors, columns =
// time steps, 3 equal components (grey R G B), ASCII; the values are the irradiance of
// visible light [W/m²], illuminance / 179 lm/W, as dctimestep gives it (rmtxop -c 47.4
// 119.9 11.6 turns it into lux).
absl::Status WriteHourlyMatrix(const v1::JobResult& result, const std::string& path);

// The result's scene at the best design (the blind included) as OBJ, one group per
// material, as `fenestra scene export` writes it. FailedPrecondition when the result holds
// no scene.
absl::Status WriteBestObj(const v1::JobResult& result, const std::string& path);

// One line per file `paths` names: "hourly illuminance (CSV): FILE" and so on.
std::string AnnualOutputLines(const AnnualOutputPaths& paths);

// Writes every file `paths` asks for; the first error, naming its flag.
absl::Status WriteAnnualOutputs(const v1::JobResult& result, const AnnualOutputPaths& paths);

}  // namespace fenestra
