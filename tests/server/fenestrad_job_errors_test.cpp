// fenestrad end to end, how a job's errors reach clients: a job the daemon cannot run is
// refused at Submit naming the field, and a job that fails after Submit keeps its status
// code (JobInfo.error_code) through the store, `fenestra job show` and `fenestra job watch`.
#include "core/dc/dc_backend.h"
#include "tests/server/fenestrad_harness.h"

namespace fenestra {
namespace {

using namespace testing_fenestrad;
using ::testing::HasSubstr;

TEST_F(FenestradTest, ACudaJobIsRefusedAtSubmitWithoutAGpu) {
  auto d = StartDaemon();
  const auto submit = [&](const v1::SubmitJobRequest& request, v1::JobInfo* info) {
    grpc::ClientContext context;
    return d->jobs().Submit(&context, request, info);
  };
  v1::Job job = TinyJob(2);
  job.mutable_sampling()->set_backend("cuda");
  v1::JobInfo info;
  const grpc::Status asked_in_job = submit(InlineRequest(job), &info);
  if (CudaDevices() > 0) {
    // With a GPU the job is taken, and runs on it
    ASSERT_TRUE(asked_in_job.ok()) << asked_in_job.error_message();
    const v1::JobInfo ended = WaitJob(*d, info.id(), Ended);
    EXPECT_EQ(ended.state(), v1::JOB_STATE_SUCCEEDED) << ended.error();
    EXPECT_EQ(ended.backend(), "cuda");
    return;
  }
  EXPECT_EQ(asked_in_job.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_THAT(asked_in_job.error_message(),
              HasSubstr("job.sampling.backend: \"cuda\" needs a GPU, and this fenestrad has none"));
  // Asked for as the request's default backend, and through the client
  v1::SubmitJobRequest request = InlineRequest(TinyJob(2));
  request.mutable_job()->mutable_sampling()->clear_backend();
  request.set_default_backend("cuda");
  const grpc::Status asked_by_default = submit(request, &info);
  EXPECT_EQ(asked_by_default.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_THAT(asked_by_default.error_message(), HasSubstr("default_backend: \"cuda\""));
  const CliResult r = d->Cli({"job", "submit", WriteJob("cuda", job)});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("FAILED_PRECONDITION: job.sampling.backend: \"cuda\" needs a GPU"));
  // Nothing was stored; "auto" is taken and runs here
  grpc::ClientContext list_context;
  v1::ListJobsResponse listed;
  ASSERT_TRUE(d->jobs().List(&list_context, v1::ListJobsRequest(), &listed).ok());
  EXPECT_EQ(listed.jobs_size(), 0);
  job.mutable_sampling()->set_backend("auto");
  ASSERT_TRUE(submit(InlineRequest(job), &info).ok());
  EXPECT_EQ(WaitJob(*d, info.id(), Ended).state(), v1::JOB_STATE_SUCCEEDED);
}

// A job with nothing to search is refused at Submit, naming the field, and nothing is stored.
TEST_F(FenestradTest, AJobWithoutDesignVariablesIsRefusedAtSubmit) {
  auto d = StartDaemon();
  v1::Job job = TinyJob(2);
  job.clear_variables();
  grpc::ClientContext context;
  v1::JobInfo info;
  const grpc::Status refused = d->jobs().Submit(&context, InlineRequest(job), &info);
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(refused.error_message(), HasSubstr("job variables: none given"));
  grpc::ClientContext list_context;
  v1::ListJobsResponse listed;
  ASSERT_TRUE(d->jobs().List(&list_context, v1::ListJobsRequest(), &listed).ok());
  EXPECT_EQ(listed.jobs_size(), 0);
}

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
