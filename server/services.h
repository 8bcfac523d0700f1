#pragma once

#include "fenestra/v1/service.grpc.pb.h"
#include "server/job_manager.h"
#include "server/site_manager.h"

namespace fenestra {

// SiteService over a SiteManager: each handler converts its status to gRPC once and logs
// one line.
class SiteServiceImpl final : public v1::SiteService::Service {
 public:
  explicit SiteServiceImpl(SiteManager& sites) : sites_(sites) {}
  grpc::Status Register(grpc::ServerContext* context, const v1::RegisterSiteRequest* request,
                        v1::SiteInfo* response) override;
  grpc::Status Get(grpc::ServerContext* context, const v1::GetSiteRequest* request,
                   v1::SiteInfo* response) override;
  grpc::Status List(grpc::ServerContext* context, const v1::ListSitesRequest* request,
                    v1::ListSitesResponse* response) override;
  grpc::Status Delete(grpc::ServerContext* context, const v1::DeleteSiteRequest* request,
                      v1::DeleteSiteResponse* response) override;

 private:
  SiteManager& sites_;
};

// JobService over a JobManager: each handler converts its status to gRPC once and logs
// one line.
class JobServiceImpl final : public v1::JobService::Service {
 public:
  explicit JobServiceImpl(JobManager& jobs) : jobs_(jobs) {}
  grpc::Status Submit(grpc::ServerContext* context, const v1::SubmitJobRequest* request,
                      v1::JobInfo* response) override;
  grpc::Status Get(grpc::ServerContext* context, const v1::GetJobRequest* request,
                   v1::JobInfo* response) override;
  grpc::Status List(grpc::ServerContext* context, const v1::ListJobsRequest* request,
                    v1::ListJobsResponse* response) override;
  grpc::Status Cancel(grpc::ServerContext* context, const v1::CancelJobRequest* request,
                      v1::JobInfo* response) override;
  grpc::Status Watch(grpc::ServerContext* context, const v1::WatchJobRequest* request,
                     grpc::ServerWriter<v1::JobEvent>* writer) override;

 private:
  JobManager& jobs_;
};

}  // namespace fenestra
