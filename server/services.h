#pragma once

#include "fenestra/v1/service.grpc.pb.h"
#include "server/job_manager.h"
#include "server/site_manager.h"
#include "server/users.h"

namespace fenestra {

// The services take their requests as streams (gRPC's "streamed" method variants: the
// same wire protocol as unary and server-streaming calls) so that each handler decodes
// the request itself. Every call is answered the same way: the caller authenticated
// (UNAUTHENTICATED otherwise, before the request is even read), the request decoded
// (INVALID_ARGUMENT naming the message type when its bytes do not decode), the manager's
// status converted to gRPC once, and one log line with client text escaped.

// SiteService over a SiteManager.
class SiteServiceImpl final : public v1::SiteService::StreamedService {
 public:
  SiteServiceImpl(SiteManager& sites, const Authenticator& auth) : sites_(sites), auth_(auth) {}
  grpc::Status StreamedRegister(
      grpc::ServerContext* context,
      grpc::ServerUnaryStreamer<v1::RegisterSiteRequest, v1::SiteInfo>* stream) override;
  grpc::Status StreamedGet(
      grpc::ServerContext* context,
      grpc::ServerUnaryStreamer<v1::GetSiteRequest, v1::SiteInfo>* stream) override;
  grpc::Status StreamedList(
      grpc::ServerContext* context,
      grpc::ServerUnaryStreamer<v1::ListSitesRequest, v1::ListSitesResponse>* stream) override;
  grpc::Status StreamedDelete(
      grpc::ServerContext* context,
      grpc::ServerUnaryStreamer<v1::DeleteSiteRequest, v1::DeleteSiteResponse>* stream) override;

 private:
  SiteManager& sites_;
  const Authenticator& auth_;
};

// JobService over a JobManager.
class JobServiceImpl final : public v1::JobService::StreamedService {
 public:
  JobServiceImpl(JobManager& jobs, const Authenticator& auth) : jobs_(jobs), auth_(auth) {}
  grpc::Status StreamedSubmit(
      grpc::ServerContext* context,
      grpc::ServerUnaryStreamer<v1::SubmitJobRequest, v1::JobInfo>* stream) override;
  grpc::Status StreamedGet(
      grpc::ServerContext* context,
      grpc::ServerUnaryStreamer<v1::GetJobRequest, v1::JobInfo>* stream) override;
  grpc::Status StreamedList(
      grpc::ServerContext* context,
      grpc::ServerUnaryStreamer<v1::ListJobsRequest, v1::ListJobsResponse>* stream) override;
  grpc::Status StreamedCancel(
      grpc::ServerContext* context,
      grpc::ServerUnaryStreamer<v1::CancelJobRequest, v1::JobInfo>* stream) override;
  grpc::Status StreamedWatch(
      grpc::ServerContext* context,
      grpc::ServerSplitStreamer<v1::WatchJobRequest, v1::JobEvent>* stream) override;
  grpc::Status StreamedDelete(
      grpc::ServerContext* context,
      grpc::ServerUnaryStreamer<v1::DeleteJobRequest, v1::DeleteJobResponse>* stream) override;

 private:
  JobManager& jobs_;
  const Authenticator& auth_;
};

}  // namespace fenestra
