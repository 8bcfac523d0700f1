// fenestra report RESULT.json -o REPORT.html: the report page of a result file.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <memory>

#include "client/cli_util.h"
#include "client/commands.h"
#include "client/report/html_report.h"
#include "core/common/json_proto.h"

namespace fenestra {

void AddReportCommand(CLI::App& app) {
  struct Args {
    std::string result, output, sensor;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand(
      "report", "Write the report of a job result: one self-contained HTML page");
  cmd->add_option("RESULT", args->result, "Result file (JSON, as optimize --local writes it)")
      ->required();
  cmd->add_option("-o,--output", args->output, "Report file (HTML)")->required();
  AddReportSensorOption(cmd, args->sensor);
  cmd->callback([args] {
    v1::JobResult result;
    if (absl::Status s = ReadJsonProtoFile(args->result, "result", &result); !s.ok()) Fail(s);
    if (absl::Status s = WriteReport(result, {args->result, args->sensor}, args->output); !s.ok()) {
      Fail(s);
    }
    fmt::print("report: {}\n", args->output);
  });
}

void AddReportSensorOption(CLI::App* command, std::string& sensor) {
  command->add_option("--sensor", sensor,
                      "Sensor of the temporal map: its name, or its index from 0; default: the "
                      "one with the lowest UDI");
}

}  // namespace fenestra
