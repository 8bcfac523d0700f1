// The report and annual-output flags through the fenestra executable: on a result file of
// `optimize --local`, and through a real fenestrad (`job report`, `job result`), whose
// result makes the same page and files as the local one.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "client/cli_util.h"
#include "client/report/annual_outputs.h"
#include "client/report/html_report.h"
#include "core/common/json_proto.h"
#include "tests/child_process.h"
#include "tests/quick_job.h"

namespace fenestra {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

// A file's bytes; empty when it cannot be read.
std::string Read(const std::string& path) { return ReadFileBytes(path).value_or(""); }

class ReportCliTest : public testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("fenestra_report_cli_" +
            std::string(testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    // The quick job with its scene by absolute path, so the job file may live here
    v1::Job job = QuickJob(3);
    job.set_scene_file(FENESTRA_SOURCE_DIR "/examples/city_office/scene.json");
    std::ofstream(Path("job.json")) << ToJson(job, JsonLayout::kIndented);
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  // The result file `path` as a message.
  v1::JobResult ReadResult(const std::string& path) {
    v1::JobResult result;
    const absl::Status read = ReadJsonProtoFile(path, "result", &result);
    EXPECT_TRUE(read.ok()) << read;
    return result;
  }

  fs::path dir_;
};

TEST_F(ReportCliTest, OptimizeLocalWritesTheAnnualOutputsAndReportMakesThePage) {
  CommandResult run = RunCommand({FENESTRA_CLI, "optimize", "--local", Path("job.json"), "-o",
                                  Path("r.json"), "--hourly-csv", Path("h.csv"), "--hourly-matrix",
                                  Path("h.mtx"), "--best-obj", Path("b.obj")});
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_THAT(run.output, HasSubstr("hourly illuminance (CSV): " + Path("h.csv")));
  EXPECT_THAT(run.output, HasSubstr("best design (OBJ): " + Path("b.obj")));
  const v1::JobResult result = ReadResult(Path("r.json"));
  ASSERT_TRUE(WriteAnnualOutputs(result, {Path("h2.csv"), Path("h2.mtx"), Path("b2.obj")}).ok());
  EXPECT_TRUE(Read(Path("h.csv")) == Read(Path("h2.csv"))) << "h.csv differs";
  EXPECT_TRUE(Read(Path("h.mtx")) == Read(Path("h2.mtx"))) << "h.mtx differs";
  EXPECT_TRUE(Read(Path("b.obj")) == Read(Path("b2.obj"))) << "b.obj differs";

  run =
      RunCommand({FENESTRA_CLI, "report", Path("r.json"), "-o", Path("r.html"), "--sensor", "S2"});
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const std::string page = Read(Path("r.html"));
  EXPECT_THAT(page, HasSubstr("Illuminance at S2 (UDI"));
  EXPECT_TRUE(page == *RenderReport(result, {Path("r.json"), "S2"})) << "the page differs";

  // Errors name what is wrong and write nothing
  run =
      RunCommand({FENESTRA_CLI, "report", Path("r.json"), "-o", Path("x.html"), "--sensor", "S0"});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_THAT(run.output, HasSubstr("error: --sensor: no sensor 'S0'"));
  run = RunCommand({FENESTRA_CLI, "report", Path("missing.json"), "-o", Path("x.html")});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_THAT(run.output, HasSubstr("missing.json: cannot open"));
  std::ofstream(Path("bad.json")) << "{\"history\": [{\"value\": {\"value\": \"NaN\"}}]}";
  run = RunCommand({FENESTRA_CLI, "report", Path("bad.json"), "-o", Path("x.html")});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_THAT(run.output,
              HasSubstr("history[0]: value, standard_error and seconds must be finite"));
  EXPECT_FALSE(fs::exists(Path("x.html")));
}

// --backend replaces the job's tracer (here a GPU the test machine may lack) and --report
// writes the page of the result file in the same run.
TEST_F(ReportCliTest, OptimizeLocalTakesTheBackendAndWritesTheReport) {
  v1::Job job = QuickJob(2);
  job.set_scene_file(FENESTRA_SOURCE_DIR "/examples/city_office/scene.json");
  job.mutable_sampling()->set_backend("cuda");
  std::ofstream(Path("gpu_job.json")) << ToJson(job, JsonLayout::kIndented);
  CommandResult run =
      RunCommand({FENESTRA_CLI, "optimize", "--local", Path("gpu_job.json"), "-o", Path("r.json"),
                  "--backend", "cpu", "--report", Path("r.html")});
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_THAT(run.output, HasSubstr("report: " + Path("r.html")));
  const v1::JobResult result = ReadResult(Path("r.json"));
  EXPECT_EQ(result.backend(), "embree-cpu");
  EXPECT_TRUE(Read(Path("r.html")) == *RenderReport(result, {Path("r.json"), ""}))
      << "the page differs";

  run = RunCommand({FENESTRA_CLI, "optimize", "--local", Path("gpu_job.json"), "-o",
                    Path("x.json"), "--backend", "gpu"});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_THAT(run.output, HasSubstr("sampling.backend"));
  EXPECT_FALSE(fs::exists(Path("x.json")));
}

TEST_F(ReportCliTest, JobReportAndResultThroughFenestrad) {
  FenestradProcess daemon(FENESTRAD, Path("data"));
  ASSERT_FALSE(daemon.address().empty()) << daemon.Log();
  const std::string server = daemon.address();
  CommandResult run =
      RunCommand({FENESTRA_CLI, "job", "submit", Path("job.json"), "--server", server, "-q"});
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const std::string id = run.output.substr(0, run.output.find('\n'));
  run = RunCommand({FENESTRA_CLI, "job", "watch", id, "--server", server});
  ASSERT_EQ(run.exit_code, 0) << run.output << daemon.Log();

  run = RunCommand({FENESTRA_CLI, "job", "result", id, "--server", server, "-o", Path("r.json"),
                    "--hourly-csv", Path("h.csv"), "--hourly-matrix", Path("h.mtx"), "--best-obj",
                    Path("b.obj")});
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_THAT(run.output, HasSubstr("hourly illuminance (Radiance matrix): " + Path("h.mtx")));
  const v1::JobResult result = ReadResult(Path("r.json"));
  ASSERT_EQ(result.best_hourly().illuminance_lux_size(), 9 * 8760);
  ASSERT_TRUE(WriteAnnualOutputs(result, {Path("h2.csv"), Path("h2.mtx"), Path("b2.obj")}).ok());
  EXPECT_TRUE(Read(Path("h.csv")) == Read(Path("h2.csv"))) << "h.csv differs";
  EXPECT_TRUE(Read(Path("h.mtx")) == Read(Path("h2.mtx"))) << "h.mtx differs";
  EXPECT_TRUE(Read(Path("b.obj")) == Read(Path("b2.obj"))) << "b.obj differs";
  // --json prints the result alone
  run = RunCommand({FENESTRA_CLI, "job", "result", id, "--server", server, "--json", "--hourly-csv",
                    Path("h3.csv")});
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_EQ(run.output.find("hourly illuminance (CSV)"), std::string::npos);

  run = RunCommand({FENESTRA_CLI, "job", "report", id, "--server", server, "-o", Path("r.html")});
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_TRUE(Read(Path("r.html")) == *RenderReport(result, {id, ""})) << "the page differs";
  run = RunCommand(
      {FENESTRA_CLI, "job", "report", "job-99", "--server", server, "-o", Path("x.html")});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_THAT(run.output, HasSubstr("job-99"));
  EXPECT_FALSE(fs::exists(Path("x.html")));
}

}  // namespace
}  // namespace fenestra
