#include "server/services.h"

#include <spdlog/spdlog.h>

#include <chrono>

#include "absl/strings/str_cat.h"
#include "core/common/text.h"

namespace fenestra {
namespace {

grpc::Status ToGrpcStatus(const absl::Status& status) {
  if (status.ok()) return grpc::Status::OK;
  return grpc::Status(static_cast<grpc::StatusCode>(status.code()), std::string(status.message()));
}

// Runs one handler body, logs "rpc <method> <peer> <target> -> <code> (<ms> ms)" and
// converts its status. Client text in the line (target, message) is escaped: one request,
// one log line.
template <typename Body>
grpc::Status Handle(const char* method, grpc::ServerContext* context, const std::string& target,
                    Body&& body) {
  const auto start = std::chrono::steady_clock::now();
  const absl::Status status = body();
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  const std::string shown = LoggableText(target, kMaxNameBytes);
  if (status.ok()) {
    spdlog::info("rpc {} {} {} -> OK ({:.1f} ms)", method, context->peer(), shown, ms);
  } else {
    spdlog::info("rpc {} {} {} -> {}: {} ({:.1f} ms)", method, context->peer(), shown,
                 absl::StatusCodeToString(status.code()), LoggableText(status.message()), ms);
  }
  return ToGrpcStatus(status);
}

}  // namespace

grpc::Status SiteServiceImpl::Register(grpc::ServerContext* context,
                                       const v1::RegisterSiteRequest* request,
                                       v1::SiteInfo* response) {
  return Handle("SiteService.Register", context, request->scene().name(), [&]() -> absl::Status {
    absl::StatusOr<v1::SiteInfo> info = sites_.Register(*request);
    if (!info.ok()) return info.status();
    *response = *std::move(info);
    return absl::OkStatus();
  });
}

grpc::Status SiteServiceImpl::Get(grpc::ServerContext* context, const v1::GetSiteRequest* request,
                                  v1::SiteInfo* response) {
  return Handle("SiteService.Get", context, request->id(), [&]() -> absl::Status {
    absl::StatusOr<v1::SiteInfo> info = sites_.Get(request->id());
    if (!info.ok()) return info.status();
    *response = *std::move(info);
    return absl::OkStatus();
  });
}

grpc::Status SiteServiceImpl::List(grpc::ServerContext* context, const v1::ListSitesRequest*,
                                   v1::ListSitesResponse* response) {
  return Handle("SiteService.List", context, "", [&]() -> absl::Status {
    for (v1::SiteInfo& site : sites_.List()) *response->add_sites() = std::move(site);
    return absl::OkStatus();
  });
}

grpc::Status SiteServiceImpl::Delete(grpc::ServerContext* context,
                                     const v1::DeleteSiteRequest* request,
                                     v1::DeleteSiteResponse*) {
  return Handle("SiteService.Delete", context, request->id(),
                [&]() -> absl::Status { return sites_.Delete(request->id()); });
}

grpc::Status JobServiceImpl::Submit(grpc::ServerContext* context,
                                    const v1::SubmitJobRequest* request, v1::JobInfo* response) {
  return Handle("JobService.Submit", context, request->job().name(), [&]() -> absl::Status {
    absl::StatusOr<v1::JobInfo> info = jobs_.Submit(*request);
    if (!info.ok()) return info.status();
    *response = *std::move(info);
    return absl::OkStatus();
  });
}

grpc::Status JobServiceImpl::Get(grpc::ServerContext* context, const v1::GetJobRequest* request,
                                 v1::JobInfo* response) {
  return Handle("JobService.Get", context, request->id(), [&]() -> absl::Status {
    absl::StatusOr<v1::JobInfo> info = jobs_.Get(request->id());
    if (!info.ok()) return info.status();
    *response = *std::move(info);
    return absl::OkStatus();
  });
}

grpc::Status JobServiceImpl::List(grpc::ServerContext* context, const v1::ListJobsRequest* request,
                                  v1::ListJobsResponse* response) {
  return Handle("JobService.List", context, "", [&]() -> absl::Status {
    for (v1::JobInfo& job : jobs_.List(request->state(), request->limit())) {
      *response->add_jobs() = std::move(job);
    }
    return absl::OkStatus();
  });
}

grpc::Status JobServiceImpl::Cancel(grpc::ServerContext* context,
                                    const v1::CancelJobRequest* request, v1::JobInfo* response) {
  return Handle("JobService.Cancel", context, request->id(), [&]() -> absl::Status {
    absl::StatusOr<v1::JobInfo> info = jobs_.Cancel(request->id());
    if (!info.ok()) return info.status();
    *response = *std::move(info);
    return absl::OkStatus();
  });
}

grpc::Status JobServiceImpl::Watch(grpc::ServerContext* context, const v1::WatchJobRequest* request,
                                   grpc::ServerWriter<v1::JobEvent>* writer) {
  return Handle("JobService.Watch", context, request->id(), [&]() -> absl::Status {
    return jobs_.Watch(
        request->id(), [&](const v1::JobEvent& event) { return writer->Write(event); },
        [&] { return context->IsCancelled(); });
  });
}

}  // namespace fenestra
