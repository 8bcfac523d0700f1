#include "server/services.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <optional>
#include <string_view>

#include "absl/strings/str_cat.h"
#include "server/log_safe.h"

namespace fenestra {
namespace {

grpc::Status ToGrpcStatus(const absl::Status& status) {
  if (status.ok()) return grpc::Status::OK;
  return grpc::Status(static_cast<grpc::StatusCode>(status.code()), std::string(status.message()));
}

// The value of the call's "authorization" metadata, when it carries exactly one.
std::optional<std::string_view> Authorization(const grpc::ServerContext& context) {
  const auto [first, last] = context.client_metadata().equal_range("authorization");
  if (first == last || std::next(first) != last) return std::nullopt;
  return std::string_view(first->second.data(), first->second.size());
}

// What a log line names for a request: the id it asks about, or the name of what it makes.
std::string_view TargetOf(const v1::RegisterSiteRequest& r) {
  return r.name().empty() ? r.scene().name() : r.name();
}
std::string_view TargetOf(const v1::SubmitJobRequest& r) { return r.job().name(); }
template <typename Request>
std::string_view TargetOf(const Request& r) {
  if constexpr (requires { r.id(); }) {
    return r.id();
  } else {
    return {};
  }
}

// Serves one call: authenticates the caller, reads the request from `stream`, runs
// `body(caller, request)` and logs "rpc <method> <peer> <user> "<target>" -> <code>
// (<ms> ms)": at info, or at debug when a read-only call (Get, List, Watch, which clients
// poll) succeeds.
template <typename Request, typename Stream, typename Body>
grpc::Status Serve(const Authenticator& auth, const char* method, grpc::ServerContext* context,
                   Stream* stream, Body&& body) {
  const auto start = std::chrono::steady_clock::now();
  std::string user = "-", target;
  const absl::Status status = [&]() -> absl::Status {
    absl::StatusOr<Caller> caller = auth.Authenticate(Authorization(*context));
    if (!caller.ok()) return caller.status();
    user = caller->name;
    Request request;
    if (!stream->Read(&request)) {
      if (context->IsCancelled()) {
        return absl::CancelledError("the call ended before its request arrived");
      }
      return absl::InvalidArgumentError(
          absl::StrCat("request does not decode as ", Request::descriptor()->full_name()));
    }
    target = TargetOf(request);
    return body(*caller, request);
  }();
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  if (status.ok()) {
    const std::string_view name(method);
    const bool read_only =
        name.ends_with(".Get") || name.ends_with(".List") || name.ends_with(".Watch");
    spdlog::log(read_only ? spdlog::level::debug : spdlog::level::info,
                "rpc {} {} {} \"{}\" -> OK ({:.1f} ms)", method, LogSafe(context->peer()), user,
                LogSafe(target), ms);
  } else {
    spdlog::info("rpc {} {} {} \"{}\" -> {}: {} ({:.1f} ms)", method, LogSafe(context->peer()),
                 user, LogSafe(target), absl::StatusCodeToString(status.code()),
                 LogSafe(std::string(status.message())), ms);
  }
  return ToGrpcStatus(status);
}

// Serve for a unary call: `body(caller, request)` returns the response, which is sent.
template <typename Request, typename Response, typename Body>
grpc::Status Unary(const Authenticator& auth, const char* method, grpc::ServerContext* context,
                   grpc::ServerUnaryStreamer<Request, Response>* stream, Body&& body) {
  return Serve<Request>(auth, method, context, stream,
                        [&](const Caller& caller, const Request& request) -> absl::Status {
                          absl::StatusOr<Response> response = body(caller, request);
                          if (!response.ok()) return response.status();
                          if (!stream->Write(*response)) {
                            return absl::CancelledError("the client left before the answer");
                          }
                          return absl::OkStatus();
                        });
}

}  // namespace

grpc::Status SiteServiceImpl::StreamedRegister(
    grpc::ServerContext* context,
    grpc::ServerUnaryStreamer<v1::RegisterSiteRequest, v1::SiteInfo>* stream) {
  return Unary(auth_, "SiteService.Register", context, stream,
               [&](const Caller& caller, const v1::RegisterSiteRequest& request) {
                 return sites_.Register(request, caller);
               });
}

grpc::Status SiteServiceImpl::StreamedGet(
    grpc::ServerContext* context,
    grpc::ServerUnaryStreamer<v1::GetSiteRequest, v1::SiteInfo>* stream) {
  return Unary(auth_, "SiteService.Get", context, stream,
               [&](const Caller& caller, const v1::GetSiteRequest& request) {
                 return sites_.Get(request.id(), caller);
               });
}

grpc::Status SiteServiceImpl::StreamedList(
    grpc::ServerContext* context,
    grpc::ServerUnaryStreamer<v1::ListSitesRequest, v1::ListSitesResponse>* stream) {
  return Unary(auth_, "SiteService.List", context, stream,
               [&](const Caller& caller,
                   const v1::ListSitesRequest&) -> absl::StatusOr<v1::ListSitesResponse> {
                 absl::StatusOr<std::vector<v1::SiteInfo>> sites = sites_.List(caller);
                 if (!sites.ok()) return sites.status();
                 v1::ListSitesResponse response;
                 for (v1::SiteInfo& site : *sites) *response.add_sites() = std::move(site);
                 return response;
               });
}

grpc::Status SiteServiceImpl::StreamedDelete(
    grpc::ServerContext* context,
    grpc::ServerUnaryStreamer<v1::DeleteSiteRequest, v1::DeleteSiteResponse>* stream) {
  return Unary(auth_, "SiteService.Delete", context, stream,
               [&](const Caller& caller,
                   const v1::DeleteSiteRequest& request) -> absl::StatusOr<v1::DeleteSiteResponse> {
                 if (absl::Status s = sites_.Delete(request.id(), caller); !s.ok()) return s;
                 return v1::DeleteSiteResponse();
               });
}

grpc::Status JobServiceImpl::StreamedSubmit(
    grpc::ServerContext* context,
    grpc::ServerUnaryStreamer<v1::SubmitJobRequest, v1::JobInfo>* stream) {
  return Unary(auth_, "JobService.Submit", context, stream,
               [&](const Caller& caller, const v1::SubmitJobRequest& request) {
                 return jobs_.Submit(request, caller);
               });
}

grpc::Status JobServiceImpl::StreamedGet(
    grpc::ServerContext* context,
    grpc::ServerUnaryStreamer<v1::GetJobRequest, v1::JobInfo>* stream) {
  return Unary(auth_, "JobService.Get", context, stream,
               [&](const Caller& caller, const v1::GetJobRequest& request) {
                 return jobs_.Get(request.id(), caller);
               });
}

grpc::Status JobServiceImpl::StreamedList(
    grpc::ServerContext* context,
    grpc::ServerUnaryStreamer<v1::ListJobsRequest, v1::ListJobsResponse>* stream) {
  return Unary(auth_, "JobService.List", context, stream,
               [&](const Caller& caller,
                   const v1::ListJobsRequest& request) -> absl::StatusOr<v1::ListJobsResponse> {
                 absl::StatusOr<std::vector<v1::JobInfo>> jobs =
                     jobs_.List(request.state(), request.limit(), caller);
                 if (!jobs.ok()) return jobs.status();
                 v1::ListJobsResponse response;
                 for (v1::JobInfo& job : *jobs) *response.add_jobs() = std::move(job);
                 return response;
               });
}

grpc::Status JobServiceImpl::StreamedCancel(
    grpc::ServerContext* context,
    grpc::ServerUnaryStreamer<v1::CancelJobRequest, v1::JobInfo>* stream) {
  return Unary(auth_, "JobService.Cancel", context, stream,
               [&](const Caller& caller, const v1::CancelJobRequest& request) {
                 return jobs_.Cancel(request.id(), caller);
               });
}

grpc::Status JobServiceImpl::StreamedDelete(
    grpc::ServerContext* context,
    grpc::ServerUnaryStreamer<v1::DeleteJobRequest, v1::DeleteJobResponse>* stream) {
  return Unary(auth_, "JobService.Delete", context, stream,
               [&](const Caller& caller,
                   const v1::DeleteJobRequest& request) -> absl::StatusOr<v1::DeleteJobResponse> {
                 if (absl::Status s = jobs_.Delete(request.id(), caller); !s.ok()) return s;
                 return v1::DeleteJobResponse();
               });
}

grpc::Status JobServiceImpl::StreamedWatch(
    grpc::ServerContext* context,
    grpc::ServerSplitStreamer<v1::WatchJobRequest, v1::JobEvent>* stream) {
  return Serve<v1::WatchJobRequest>(
      auth_, "JobService.Watch", context, stream,
      [&](const Caller& caller, const v1::WatchJobRequest& request) {
        return jobs_.Watch(
            request.id(), caller, [&](const v1::JobEvent& event) { return stream->Write(event); },
            [&] { return context->IsCancelled(); });
      });
}

}  // namespace fenestra
