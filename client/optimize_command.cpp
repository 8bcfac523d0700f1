// fenestra optimize --local JOB.json
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <iostream>
#include <memory>

#include "client/cli_util.h"
#include "client/commands.h"
#include "client/progress_display.h"
#include "client/report/annual_outputs.h"
#include "client/report/html_report.h"
#include "core/common/atomic_file.h"
#include "core/optimize/job.h"

namespace fenestra {
namespace {

// One row per step of the search: its design, value and timing, and the best value so far
// with its standard error (the job's error against elapsed_seconds).
absl::Status WriteHistoryCsv(const std::string& path, const v1::JobResult& result) {
  return WriteFileAtomically(path, [&](std::ostream& out) {
    std::vector<std::string> names;
    for (const auto& [name, value] : result.best_design()) names.push_back(name);
    std::sort(names.begin(), names.end());
    out << "index";
    for (const std::string& n : names) out << ',' << n;
    out << ",value,standard_error,seconds,cached,raced_out,paths_fraction,improved,neighborhood,"
           "elapsed_seconds,best_value,best_standard_error\n";
    v1::Estimate best;
    for (const v1::Evaluation& e : result.history()) {
      if (e.improved()) best = e.value();
      out << e.index();
      for (const std::string& n : names) out << ',' << fmt::format("{:.9g}", e.design().at(n));
      out << fmt::format(",{:.9g},{:.9g},{:.6f},{},{},{:.6g},{},{},{:.6f},{:.9g},{:.9g}\n",
                         e.value().value(), e.value().standard_error(), e.seconds(),
                         e.cached() ? 1 : 0, e.raced_out() ? 1 : 0, e.paths_fraction(),
                         e.improved() ? 1 : 0, e.neighborhood(), e.elapsed_seconds(), best.value(),
                         best.standard_error());
    }
    return absl::OkStatus();
  });
}

}  // namespace

void AddOptimizeCommand(CLI::App& app) {
  struct Args {
    std::string job, output, csv, backend, report, sensor;
    bool local = false;
    AnnualOutputPaths annual;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand("optimize", "Run an optimization job in this process");
  cmd->add_option("JOB", args->job, "Job file (JSON)")->required();
  cmd->add_flag("--local", args->local, "Run here, without the service")->required();
  cmd->add_option("-o,--output", args->output, "Result file (JSON); default: JOB.result.json");
  cmd->add_option("--csv", args->csv, "History as CSV; default: the result file with .csv");
  cmd->add_option("--backend", args->backend,
                  "Tracer for this run: cpu, cuda or auto, in place of the job's sampling.backend");
  cmd->add_option("--report", args->report, "Also write the report page here (HTML)");
  AddReportSensorOption(cmd, args->sensor);
  AddAnnualOutputOptions(cmd, args->annual);
  cmd->callback([args] {
    v1::Job job = ValueOrFail(ReadJobFile(args->job));
    if (!args->backend.empty()) job.mutable_sampling()->set_backend(args->backend);
    const std::string base = std::filesystem::path(args->job).parent_path().string();
    const PreparedJob prepared = ValueOrFail(PrepareJob(job, base.empty() ? "." : base));
    std::string output = args->output;
    if (output.empty()) {
      output = std::filesystem::path(args->job).replace_extension(".result.json").string();
    }
    std::string csv = args->csv;
    if (csv.empty()) csv = std::filesystem::path(output).replace_extension(".csv").string();

    JobCallbacks callbacks;
    callbacks.stage = [](const std::string& stage) {
      EndProgress();
      fmt::print("{}...\n", StageText(stage));
      std::fflush(stdout);
    };
    callbacks.progress = ShowProgress;
    const v1::JobResult result = ValueOrFail(RunJob(prepared, nullptr, callbacks));
    EndProgress();
    if (absl::Status s = WriteJsonFile(output, result); !s.ok()) Fail(s);
    if (absl::Status s = WriteHistoryCsv(csv, result); !s.ok()) Fail(s);
    fmt::print("{}result: {}\nhistory: {}\n", FormatResult(result), output, csv);
    if (absl::Status s = WriteAnnualOutputs(result, args->annual); !s.ok()) Fail(s);
    fmt::print("{}", AnnualOutputLines(args->annual));
    if (!args->report.empty()) {
      if (absl::Status s = WriteReport(result, {output, args->sensor}, args->report); !s.ok()) {
        Fail(s);
      }
      fmt::print("report: {}\n", args->report);
    }
  });
}

}  // namespace fenestra
