#include "tests/client/recording_server.h"

#include "fenestra/v1/service.grpc.pb.h"

namespace fenestra {
namespace {

v1::JobResult Result() {
  v1::JobResult result;
  (*result.mutable_best_design())["alpha"] = 0.5;
  result.mutable_best_value()->set_value(50);
  result.mutable_best_value()->set_standard_error(1);
  result.set_evaluations(1);
  return result;
}

v1::JobInfo Job(const std::string& id, v1::JobState state) {
  v1::JobInfo job;
  job.set_id(id);
  job.set_name("recorded");
  job.set_state(state);
  if (state == v1::JOB_STATE_SUCCEEDED) *job.mutable_result() = Result();
  return job;
}

v1::SiteInfo Site(const std::string& id) {
  v1::SiteInfo site;
  site.set_id(id);
  site.set_name("recorded");
  site.set_state(v1::SITE_STATE_READY);
  return site;
}

}  // namespace

class RecordingServer::Sites final : public v1::SiteService::Service {
 public:
  explicit Sites(RecordingServer& server) : server_(server) {}
  grpc::Status Register(grpc::ServerContext* context, const v1::RegisterSiteRequest*,
                        v1::SiteInfo* site) override {
    *site = Site("site-1");
    return server_.Record(*context, "SiteService.Register");
  }
  grpc::Status Get(grpc::ServerContext* context, const v1::GetSiteRequest* request,
                   v1::SiteInfo* site) override {
    *site = Site(request->id());
    return server_.Record(*context, "SiteService.Get");
  }
  grpc::Status List(grpc::ServerContext* context, const v1::ListSitesRequest*,
                    v1::ListSitesResponse* response) override {
    *response->add_sites() = Site("site-1");
    return server_.Record(*context, "SiteService.List");
  }
  grpc::Status Delete(grpc::ServerContext* context, const v1::DeleteSiteRequest*,
                      v1::DeleteSiteResponse*) override {
    return server_.Record(*context, "SiteService.Delete");
  }

 private:
  RecordingServer& server_;
};

class RecordingServer::Jobs final : public v1::JobService::Service {
 public:
  explicit Jobs(RecordingServer& server) : server_(server) {}
  grpc::Status Submit(grpc::ServerContext* context, const v1::SubmitJobRequest*,
                      v1::JobInfo* job) override {
    *job = Job("job-1", v1::JOB_STATE_QUEUED);
    return server_.Record(*context, "JobService.Submit");
  }
  grpc::Status Get(grpc::ServerContext* context, const v1::GetJobRequest* request,
                   v1::JobInfo* job) override {
    *job = Job(request->id(), v1::JOB_STATE_SUCCEEDED);
    return server_.Record(*context, "JobService.Get");
  }
  grpc::Status List(grpc::ServerContext* context, const v1::ListJobsRequest*,
                    v1::ListJobsResponse* response) override {
    *response->add_jobs() = Job("job-1", v1::JOB_STATE_SUCCEEDED);
    return server_.Record(*context, "JobService.List");
  }
  grpc::Status Cancel(grpc::ServerContext* context, const v1::CancelJobRequest* request,
                      v1::JobInfo* job) override {
    *job = Job(request->id(), v1::JOB_STATE_CANCELLED);
    return server_.Record(*context, "JobService.Cancel");
  }
  grpc::Status Watch(grpc::ServerContext* context, const v1::WatchJobRequest* request,
                     grpc::ServerWriter<v1::JobEvent>* writer) override {
    if (grpc::Status status = server_.Record(*context, "JobService.Watch"); !status.ok()) {
      return status;
    }
    v1::JobEvent event;
    event.set_sequence(1);
    *event.mutable_snapshot() = Job(request->id(), v1::JOB_STATE_QUEUED);
    writer->Write(event);
    event.set_sequence(2);
    v1::JobProgress& progress = *event.mutable_progress();
    progress.set_evaluations(1);
    progress.set_max_evaluations(1);
    *progress.mutable_best()->mutable_design() = Result().best_design();
    *progress.mutable_best()->mutable_value() = Result().best_value();
    *progress.mutable_current() = progress.best();
    writer->Write(event);
    event.set_sequence(3);
    *event.mutable_finished() = Result();
    writer->Write(event);
    return grpc::Status::OK;
  }

 private:
  RecordingServer& server_;
};

RecordingServer::RecordingServer(std::shared_ptr<grpc::ServerCredentials> credentials,
                                 std::string required_token)
    : required_token_(std::move(required_token)),
      sites_(std::make_unique<Sites>(*this)),
      jobs_(std::make_unique<Jobs>(*this)) {
  int port = 0;
  grpc::ServerBuilder builder;
  builder.AddListeningPort("127.0.0.1:0", credentials, &port);
  builder.RegisterService(sites_.get());
  builder.RegisterService(jobs_.get());
  server_ = builder.BuildAndStart();
  address_ = "127.0.0.1:" + std::to_string(port);
}

RecordingServer::~RecordingServer() { server_->Shutdown(); }

std::vector<RecordingServer::Call> RecordingServer::calls() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return calls_;
}

grpc::Status RecordingServer::Record(const grpc::ServerContext& context, const char* method) {
  const auto& metadata = context.client_metadata();
  const auto found = metadata.find("authorization");
  const std::string authorization =
      found == metadata.end() ? "(none)" : std::string(found->second.data(), found->second.size());
  {
    std::lock_guard<std::mutex> lock(mutex_);
    calls_.push_back({method, authorization});
  }
  if (!required_token_.empty() && authorization != "Bearer " + required_token_) {
    return grpc::Status(grpc::StatusCode::UNAUTHENTICATED, "invalid bearer token");
  }
  return grpc::Status::OK;
}

}  // namespace fenestra
