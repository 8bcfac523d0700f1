// fenestra job submit/watch/list/show/cancel/result/report: optimization jobs run by fenestrad.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <ctime>
#include <memory>
#include <optional>

#include "absl/status/status.h"
#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "client/cli_util.h"
#include "client/commands.h"
#include "client/grpc_client.h"
#include "client/job_request.h"
#include "client/progress_display.h"
#include "client/report/annual_outputs.h"
#include "client/report/html_report.h"

namespace fenestra {
namespace {

std::string LocalTime(int64_t unix_ms) {
  if (unix_ms == 0) return "-";
  const std::time_t t = unix_ms / 1000;
  std::tm tm{};
  localtime_r(&t, &tm);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%d %H:%M:%S", &tm);
  return text;
}

// Why a job failed: its status code's name when fenestrad recorded one, and the reason.
std::string FailureText(const v1::JobInfo& j) {
  if (j.error_code() == 0) return j.error();
  return absl::StrCat(absl::StatusCodeToString(static_cast<absl::StatusCode>(j.error_code())), ": ",
                      j.error());
}

void PrintJob(const v1::JobInfo& j) {
  fmt::print("{} ({}): {}{}\n", j.id(), j.name(), StateName(j.state()),
             j.cancel_requested() && j.state() == v1::JOB_STATE_RUNNING ? ", cancelling" : "");
  if (!j.site_id().empty()) fmt::print("  site: {}\n", j.site_id());
  fmt::print("  submitted {}, started {}, finished {}\n", LocalTime(j.created_unix_ms()),
             LocalTime(j.started_unix_ms()), LocalTime(j.finished_unix_ms()));
  if (j.state() == v1::JOB_STATE_QUEUED) fmt::print("  {} job(s) ahead\n", j.queue_position());
  if (j.state() == v1::JOB_STATE_RUNNING) fmt::print("  stage: {}\n", j.stage());
  if (j.started_unix_ms() && j.stage() != "outdoor") {
    fmt::print("  outdoor matrix: {} in {:.3f} s\n",
               j.outdoor_reused() ? "reused from the cache" : "traced", j.outdoor_seconds());
  }
  if (j.has_progress()) fmt::print("  {}\n", FormatProgress(FromProto(j.progress())));
  if (!j.error().empty() || j.error_code() != 0) fmt::print("  error: {}\n", FailureText(j));
  if (j.has_result()) {
    fmt::print("{}", FormatResult(j.result()));
  }
}

// How a job ended, as its event stream told.
struct JobEnd {
  std::optional<v1::JobState> state;  // unset while the job runs
  v1::JobResult result;               // the best design, when there is one
  std::string error;                  // FAILED: the reason
};

// Records the end that `event` announces, if any.
void RecordEnd(const v1::JobEvent& event, JobEnd& end) {
  switch (event.kind_case()) {
    case v1::JobEvent::kSnapshot:
      if (IsFinalState(event.snapshot().state())) {
        end = {event.snapshot().state(), event.snapshot().result(), FailureText(event.snapshot())};
      }
      break;
    case v1::JobEvent::kFinished:
      end = {v1::JOB_STATE_SUCCEEDED, event.finished(), ""};
      break;
    case v1::JobEvent::kFailed:
      end = {v1::JOB_STATE_FAILED, {}, event.failed()};
      break;
    case v1::JobEvent::kCancelled:
      end = {v1::JOB_STATE_CANCELLED, event.cancelled().result(), ""};
      break;
    case v1::JobEvent::kInterrupted:
      end = {v1::JOB_STATE_INTERRUPTED, event.interrupted().result(), ""};
      break;
    default:
      break;
  }
}

// Shows an event as text: a line, or the live progress line.
void ShowEvent(const v1::JobEvent& event) {
  switch (event.kind_case()) {
    case v1::JobEvent::kSnapshot: {
      const v1::JobInfo& j = event.snapshot();
      fmt::print("{} ({}): {}", j.id(), j.name(), StateName(j.state()));
      if (j.state() == v1::JOB_STATE_QUEUED) fmt::print(", {} job(s) ahead", j.queue_position());
      if (j.state() == v1::JOB_STATE_RUNNING) fmt::print(", stage {}", j.stage());
      fmt::print("\n");
      if (j.has_progress() && j.state() == v1::JOB_STATE_RUNNING) {
        ShowProgress(FromProto(j.progress()));
      }
      break;
    }
    case v1::JobEvent::kQueued:
      fmt::print("queued, {} job(s) ahead\n", event.queued());
      break;
    case v1::JobEvent::kStarted:
      fmt::print("started (backend {})\n", event.started().backend());
      break;
    case v1::JobEvent::kStage:
      EndProgress();
      fmt::print("{}...\n", StageText(event.stage().name(), event.stage().cached()));
      break;
    case v1::JobEvent::kProgress:
      ShowProgress(FromProto(event.progress()));
      break;
    default:
      break;
  }
}

// Follows a job's events until it ends; returns the process exit code (0 = succeeded).
int Watch(FenestraClient& client, const std::string& id, bool json) {
  JobEnd end;
  const absl::Status status = client.WatchJob(id, [&](const v1::JobEvent& event) {
    if (json) {
      fmt::print("{}\n", ToJson(event, JsonLayout::kLine));
    } else {
      ShowEvent(event);
    }
    RecordEnd(event, end);
    std::fflush(stdout);
  });
  if (!json) EndProgress();
  if (!end.state) {
    const absl::Status st =
        status.ok() ? absl::UnavailableError("the event stream ended before the job did") : status;
    Fail(absl::Status(st.code(), absl::StrCat(st.message(), "; follow the job again with: ",
                                              "fenestra job watch ", id)));
  }
  if (json) return *end.state == v1::JOB_STATE_SUCCEEDED ? 0 : 1;
  switch (*end.state) {
    case v1::JOB_STATE_SUCCEEDED:
      fmt::print("{} succeeded\n{}", id, FormatResult(end.result));
      return 0;
    case v1::JOB_STATE_FAILED: {
      // The failed event says why; the job's info also the status code
      const absl::StatusOr<v1::JobInfo> info = client.GetJob(id);
      fmt::print(
          stderr, "error: {} failed: {}\n", id,
          info.ok() && info->state() == v1::JOB_STATE_FAILED ? FailureText(*info) : end.error);
      return 1;
    }
    default:
      fmt::print("{} {}{}\n", id, StateName(*end.state),
                 *end.state == v1::JOB_STATE_INTERRUPTED ? " (fenestrad shut down)" : "");
      if (end.result.evaluations() > 0) fmt::print("best so far:\n{}", FormatResult(end.result));
      return 1;
  }
}

// The job's result; Fail()s saying why when it has none.
const v1::JobResult& ResultOrFail(const v1::JobInfo& info) {
  if (!info.has_result()) {
    if (info.state() == v1::JOB_STATE_FAILED) {
      Fail(absl::FailedPreconditionError(absl::StrCat(info.id(), " failed: ", FailureText(info))));
    }
    Fail(absl::FailedPreconditionError(
        absl::StrCat(info.id(), " is ", StateName(info.state()),
                     IsFinalState(info.state())
                         ? " without a result"
                         : absl::StrCat("; no result yet (fenestra job watch ", info.id(), ")"))));
  }
  return info.result();
}

// fenestra job submit
void AddJobSubmit(CLI::App* job) {
  struct SubmitArgs {
    ServerOptions server;
    std::string file, site, backend;
    bool watch = false, quiet = false, json = false;
  };
  auto submit = std::make_shared<SubmitArgs>();
  CLI::App* submit_cmd = job->add_subcommand(
      "submit", "Submit a job file; its scene, OBJ meshes and weather file travel inline");
  submit_cmd->add_option("JOB", submit->file, "Job file (JSON)")->required();
  submit_cmd->add_option("--site", submit->site, "Reuse this site's cached outdoor matrix");
  submit_cmd->add_option("--backend", submit->backend,
                         "cpu, cuda or auto when the job names none; default: the daemon's");
  submit_cmd->add_flag("--watch", submit->watch, "Follow its progress until it ends");
  submit_cmd->add_flag("-q,--quiet", submit->quiet, "Print only the job id");
  submit_cmd->add_flag("--json", submit->json, "With --watch: print the events as JSON lines");
  AddServerOptions(submit_cmd, submit->server);
  submit_cmd->callback([submit] {
    v1::SubmitJobRequest request = ValueOrFail(SubmitRequestFromJobFile(submit->file));
    request.set_site_id(submit->site);
    request.set_default_backend(submit->backend);
    FenestraClient client = ConnectOrFail(submit->server);
    const v1::JobInfo info = ValueOrFail(client.SubmitJob(request));
    if (submit->quiet) {
      fmt::print("{}\n", info.id());
    } else if (!submit->json) {
      fmt::print("{} submitted ({}), {} job(s) ahead\n", info.id(), info.name(),
                 info.queue_position());
    }
    std::fflush(stdout);
    if (submit->watch) {
      const int code = Watch(client, info.id(), submit->json);
      if (code != 0) throw CLI::RuntimeError(code);
    }
  });
}

// fenestra job watch
void AddJobWatch(CLI::App* job) {
  struct WatchArgs {
    ServerOptions server;
    std::string id;
    bool json = false;
  };
  auto watch = std::make_shared<WatchArgs>();
  CLI::App* watch_cmd = job->add_subcommand(
      "watch", "Follow a job: its current state, then its progress until it ends");
  watch_cmd->add_option("ID", watch->id, "Job id")->required();
  watch_cmd->add_flag("--json", watch->json, "Print the events as JSON lines");
  AddServerOptions(watch_cmd, watch->server);
  watch_cmd->callback([watch] {
    FenestraClient client = ConnectOrFail(watch->server);
    const int code = Watch(client, watch->id, watch->json);
    if (code != 0) throw CLI::RuntimeError(code);
  });
}

// fenestra job list
void AddJobList(CLI::App* job) {
  struct ListArgs {
    ServerOptions server;
    std::string state;
    int limit = 0;
  };
  auto list = std::make_shared<ListArgs>();
  CLI::App* list_cmd = job->add_subcommand("list", "List jobs, newest first");
  list_cmd->add_option("--state", list->state,
                       "Only: queued, running, succeeded, failed, cancelled, interrupted");
  list_cmd->add_option("--limit", list->limit, "At most this many [100]");
  AddServerOptions(list_cmd, list->server);
  list_cmd->callback([list] {
    v1::ListJobsRequest request;
    if (!list->state.empty()) {
      v1::JobState state;
      if (!v1::JobState_Parse("JOB_STATE_" + absl::AsciiStrToUpper(list->state), &state)) {
        Fail(
            absl::InvalidArgumentError(absl::StrCat("--state: unknown state '", list->state, "'")));
      }
      request.set_state(state);
    }
    request.set_limit(list->limit);
    const v1::ListJobsResponse response =
        ValueOrFail(ConnectOrFail(list->server).ListJobs(request));
    fmt::print("{:<10} {:<12} {:>11} {:>18}  {}\n", "ID", "STATE", "EVALUATIONS", "BEST [%]",
               "NAME");
    for (const v1::JobInfo& j : response.jobs()) {
      const v1::JobProgress& p = j.progress();
      fmt::print(
          "{:<10} {:<12} {:>11} {:>18}  {}\n", j.id(), StateName(j.state()),
          j.has_progress() ? fmt::format("{}/{}", p.evaluations(), p.max_evaluations()) : "-",
          j.has_progress() ? fmt::format("{:.2f} ± {:.2f}", p.best().value().value(),
                                         p.best().value().standard_error())
                           : "-",
          j.name());
    }
  });
}

// fenestra job show
void AddJobShow(CLI::App* job) {
  struct ShowArgs {
    ServerOptions server;
    std::string id;
    bool json = false;
  };
  auto show = std::make_shared<ShowArgs>();
  CLI::App* show_cmd = job->add_subcommand("show", "Show a job's state, progress and result");
  show_cmd->add_option("ID", show->id, "Job id")->required();
  show_cmd->add_flag("--json", show->json, "Print the job as JSON");
  AddServerOptions(show_cmd, show->server);
  show_cmd->callback([show] {
    const v1::JobInfo info = ValueOrFail(ConnectOrFail(show->server).GetJob(show->id));
    if (show->json) {
      fmt::print("{}\n", ToJson(info, JsonLayout::kIndented));
    } else {
      PrintJob(info);
    }
  });
}

// fenestra job cancel
void AddJobCancel(CLI::App* job) {
  struct CancelArgs {
    ServerOptions server;
    std::string id;
  };
  auto cancel = std::make_shared<CancelArgs>();
  CLI::App* cancel_cmd =
      job->add_subcommand("cancel", "Cancel a job (a running one stops at its next checkpoint)");
  cancel_cmd->add_option("ID", cancel->id, "Job id")->required();
  AddServerOptions(cancel_cmd, cancel->server);
  cancel_cmd->callback([cancel] {
    const v1::JobInfo info = ValueOrFail(ConnectOrFail(cancel->server).CancelJob(cancel->id));
    if (info.state() == v1::JOB_STATE_RUNNING) {
      fmt::print("{}: cancelling; it stops at its next checkpoint\n", info.id());
    } else {
      fmt::print("{}: {}\n", info.id(), StateName(info.state()));
    }
  });
}

// fenestra job delete
void AddJobDelete(CLI::App* job) {
  struct DeleteArgs {
    ServerOptions server;
    std::string id;
  };
  auto args = std::make_shared<DeleteArgs>();
  CLI::App* cmd = job->add_subcommand(
      "delete", "Forget an ended job with its result (a queued or running one: cancel it first)");
  cmd->add_option("ID", args->id, "Job id")->required();
  AddServerOptions(cmd, args->server);
  cmd->callback([args] {
    if (const absl::Status s = ConnectOrFail(args->server).DeleteJob(args->id); !s.ok()) Fail(s);
    fmt::print("{}: deleted\n", args->id);
  });
}

// fenestra job result
void AddJobResult(CLI::App* job) {
  struct ResultArgs {
    ServerOptions server;
    std::string id, output;
    bool json = false;
    AnnualOutputPaths annual;
  };
  auto result = std::make_shared<ResultArgs>();
  CLI::App* result_cmd = job->add_subcommand("result", "Print a job's result (best design)");
  result_cmd->add_option("ID", result->id, "Job id")->required();
  result_cmd->add_flag("--json", result->json, "Print the result as JSON");
  result_cmd->add_option("-o,--output", result->output,
                         "Also write the result file here (JSON, as optimize --local writes it)");
  AddAnnualOutputOptions(result_cmd, result->annual);
  AddServerOptions(result_cmd, result->server);
  result_cmd->callback([result] {
    const v1::JobInfo info = ValueOrFail(ConnectOrFail(result->server).GetJob(result->id));
    ResultOrFail(info);
    if (!result->output.empty()) {
      if (absl::Status st = WriteJsonFile(result->output, info.result()); !st.ok()) Fail(st);
    }
    if (absl::Status st = WriteAnnualOutputs(info.result(), result->annual); !st.ok()) Fail(st);
    if (result->json) {
      fmt::print("{}\n", ToJson(info.result(), JsonLayout::kIndented));
    } else {
      fmt::print("{} ({}): {}\n{}{}", info.id(), info.name(), StateName(info.state()),
                 FormatResult(info.result()), AnnualOutputLines(result->annual));
    }
  });
}

// fenestra job report
void AddJobReport(CLI::App* job) {
  struct ReportArgs {
    ServerOptions server;
    std::string id, output, sensor;
  };
  auto report = std::make_shared<ReportArgs>();
  CLI::App* report_cmd = job->add_subcommand(
      "report", "Write the report of a job's result: one self-contained HTML page");
  report_cmd->add_option("ID", report->id, "Job id")->required();
  report_cmd->add_option("-o,--output", report->output, "Report file (HTML)")->required();
  AddReportSensorOption(report_cmd, report->sensor);
  AddServerOptions(report_cmd, report->server);
  report_cmd->callback([report] {
    const v1::JobInfo info = ValueOrFail(ConnectOrFail(report->server).GetJob(report->id));
    const absl::Status written =
        WriteReport(ResultOrFail(info), {info.id(), report->sensor}, report->output);
    if (!written.ok()) Fail(written);
    fmt::print("report: {}\n", report->output);
  });
}

}  // namespace

void AddJobCommand(CLI::App& app) {
  CLI::App* job = app.add_subcommand("job", "Optimization jobs run by fenestrad");
  job->require_subcommand(1);
  AddJobSubmit(job);
  AddJobWatch(job);
  AddJobList(job);
  AddJobShow(job);
  AddJobCancel(job);
  AddJobDelete(job);
  AddJobResult(job);
  AddJobReport(job);
}

}  // namespace fenestra
