// fenestrad end to end, how a job's errors reach clients: a job that fails after Submit
// keeps its status code (JobInfo.error_code) through the store, `fenestra job show` and
// `fenestra job watch`.
#include "tests/server/fenestrad_harness.h"

namespace fenestra {
namespace {

using namespace testing_fenestrad;
using ::testing::HasSubstr;

bool Ended(const v1::JobInfo& job) { return job.state() >= v1::JOB_STATE_SUCCEEDED; }

TEST_F(FenestradTest, AJobThatFailsAfterSubmitKeepsItsStatusCode) {
  auto d = StartDaemon({"--shutdown-grace", "0.3"});
  const std::string running = Submit(*d, WriteJob("long", LongJob()));
  const std::string queued = Submit(*d, WriteJob("tiny", TinyJob(2)));
  WaitJob(*d, running, Running);
  EXPECT_EQ(d->Stop(), 0);  // the running job is interrupted, the queued one stays queued

  // The queued job's weather file is lost while the daemon is down: it fails when it runs
  for (const auto& file : fs::directory_iterator(d->data_dir() + "/weather")) {
    fs::remove(file.path());
  }
  d->Start();
  const v1::JobInfo failed = WaitJob(*d, queued, Ended);
  ASSERT_EQ(failed.state(), v1::JOB_STATE_FAILED);
  EXPECT_EQ(failed.error_code(), grpc::StatusCode::DATA_LOSS);
  EXPECT_EQ(failed.error(), "the job's stored weather file cannot be read");
  CliResult r = d->Cli({"job", "show", queued});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("error: DATA_LOSS: the job's stored weather file cannot be read"));
  r = d->Cli({"job", "watch", queued});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("error: " + queued + " failed: DATA_LOSS: the job's stored"));
  // Not a record that does not parse: the job is kept, not quarantined
  EXPECT_THAT(d->Log(), ::testing::Not(HasSubstr("moved to the quarantine table")));

  // The code is stored with the job
  EXPECT_EQ(d->Stop(), 0);
  d->Start();
  EXPECT_EQ(GetJob(*d, queued).error_code(), grpc::StatusCode::DATA_LOSS);
  EXPECT_EQ(GetJob(*d, running).error_code(), 0);  // interrupted, not failed
}

}  // namespace
}  // namespace fenestra
