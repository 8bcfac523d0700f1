#include "server/http_gateway.h"

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <httplib.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <memory>
#include <mutex>
#include <optional>
#include <string_view>
#include <unordered_map>
#include <utility>

#include "absl/strings/escaping.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "client/report/html_report.h"
#include "core/common/json_proto.h"
#include "core/common/status_macros.h"
#include "server/checksum.h"
#include "server/limits.h"
#include "server/log_safe.h"
#include "server/web_files.h"

namespace fenestra {
namespace {

// Threads answering requests; a page polls twice a second, so a few serve many pages.
constexpr int kHttpThreads = 8;
// A request's reads and writes [s].
constexpr int kHttpTimeoutSeconds = 10;
// Client addresses whose request budgets are remembered; beyond it the full ones are dropped.
constexpr size_t kMaxTrackedClients = 10000;
// Where a Submit error's field (job, scene, weather) travels inside the status.
constexpr char kFieldPayload[] = "type.fenestra.dev/http-field";
// Job and site ids in routes: the daemon's own ("job-12"), nothing a path could climb with.
constexpr char kId[] = R"(([A-Za-z0-9_-]{1,64}))";

int HttpStatusOf(absl::StatusCode code) {
  switch (code) {
    case absl::StatusCode::kInvalidArgument:
    case absl::StatusCode::kOutOfRange:
      return 400;
    case absl::StatusCode::kUnauthenticated:
      return 401;
    case absl::StatusCode::kPermissionDenied:
      return 403;
    case absl::StatusCode::kNotFound:
      return 404;
    case absl::StatusCode::kFailedPrecondition:
    case absl::StatusCode::kAlreadyExists:
    case absl::StatusCode::kAborted:
      return 409;
    case absl::StatusCode::kResourceExhausted:
      return 429;
    case absl::StatusCode::kUnavailable:
      return 503;
    case absl::StatusCode::kDeadlineExceeded:
      return 504;
    default:
      return 500;
  }
}

// Sets `body` as the answer, sent as it is. cpp-httplib compresses a body given to
// set_content with Brotli at its slowest setting whenever the client accepts "br", as every
// browser does: with pages polling, that took over half the daemon's CPU for answers of a
// few kilobytes on a local network. A body of known length from a content provider is sent
// uncompressed (an empty one has nothing to compress).
void SetBody(httplib::Response& res, std::string body, const char* content_type) {
  res.headers.erase("Content-Type");
  res.body.clear();
  if (body.empty()) {
    res.set_content(body, content_type);
    return;
  }
  auto shared = std::make_shared<const std::string>(std::move(body));
  res.set_content_provider(shared->size(), content_type,
                           [shared](size_t offset, size_t length, httplib::DataSink& sink) {
                             return sink.write(shared->data() + offset, length);
                           });
}

// `status` as the API's error body: {"code", "message", "field"}.
std::string ErrorJson(const absl::Status& status) {
  google::protobuf::Struct error;
  auto& fields = *error.mutable_fields();
  fields["code"].set_string_value(absl::StatusCodeToString(status.code()));
  fields["message"].set_string_value(std::string(status.message()));
  const auto field = status.GetPayload(kFieldPayload);
  fields["field"].set_string_value(field ? std::string(*field) : "");
  std::string json;
  (void)google::protobuf::util::MessageToJsonString(error, &json);
  return json;
}

absl::Status WithField(absl::Status status, std::string_view field) {
  if (!status.ok()) status.SetPayload(kFieldPayload, absl::Cord(std::string(field)));
  return status;
}

std::string ToJson(const google::protobuf::Message& message) {
  std::string json;
  (void)google::protobuf::util::MessageToJsonString(message, &json);
  return json;
}

// `json` (protobuf's JSON mapping, unknown fields refused) into `message`.
absl::Status FromJson(const std::string& json, google::protobuf::Message* message,
                      std::string_view what) {
  return ParseJsonProto(json, absl::StrCat(std::string(what), ": malformed JSON"), message);
}

// The host and port of "host:port" or "[v6]:port".
absl::StatusOr<std::pair<std::string, int>> HostAndPort(const std::string& address) {
  const size_t colon = address.rfind(':');
  int port = 0;
  if (colon == std::string::npos || !absl::SimpleAtoi(address.substr(colon + 1), &port) ||
      port < 0 || port > 65535) {
    return absl::InvalidArgumentError(
        absl::StrCat("http_listen '", address, "': must be host:port"));
  }
  std::string host = address.substr(0, colon);
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']') {
    host = host.substr(1, host.size() - 2);
  }
  if (host == "localhost") host = "127.0.0.1";
  return std::pair{host, port};
}

// Requests per client address and minute, as a token bucket refilled continuously.
class RateLimiter {
 public:
  explicit RateLimiter(int per_minute) : per_minute_(per_minute) {}

  bool Allow(const std::string& client) {
    const auto now = std::chrono::steady_clock::now();
    std::lock_guard lock(mutex_);
    if (buckets_.size() >= kMaxTrackedClients && !buckets_.contains(client)) Forget(now);
    auto [it, made] = buckets_.try_emplace(client, Bucket{static_cast<double>(per_minute_), now});
    Bucket& b = it->second;
    b.tokens = std::min<double>(
        per_minute_,
        b.tokens + per_minute_ * std::chrono::duration<double>(now - b.refilled).count() / 60);
    b.refilled = now;
    if (b.tokens < 1) return false;
    b.tokens -= 1;
    return true;
  }

 private:
  struct Bucket {
    double tokens;
    std::chrono::steady_clock::time_point refilled;
  };
  // Drops the clients whose budget has refilled (they are as if new).
  void Forget(std::chrono::steady_clock::time_point now) {
    std::erase_if(buckets_, [&](const auto& entry) {
      return now - entry.second.refilled > std::chrono::minutes(1);
    });
  }

  const int per_minute_;
  std::mutex mutex_;
  std::unordered_map<std::string, Bucket> buckets_;
};

// The API's routes over the daemon's managers.
class Api {
 public:
  Api(const v1::DaemonConfig& config, HttpGateway::Services services)
      : config_(config),
        services_(services),
        limiter_(config.limits().max_http_requests_per_minute()),
        page_policy_(absl::StrCat(
            "default-src 'none'; script-src 'self'; style-src 'self' 'sha256-",
            absl::Base64Escape(Sha256(ReportStyleSheet())),
            "'; img-src 'self' data:; connect-src 'self'; base-uri 'none'; form-action 'none'; "
            "frame-ancestors 'none'")) {}

  void Route(httplib::Server& server);

 private:
  using Body =
      std::function<absl::Status(const Caller&, const httplib::Request&, httplib::Response&)>;

  // Checks every request before its route: its client's rate, and that a browser sent it
  // from the page's own origin. Sets the headers every answer carries.
  httplib::Server::HandlerResponse Screen(const httplib::Request& req, httplib::Response& res);
  // Serves an API call: authenticates the caller, runs `body`, answers an error as JSON
  // and logs one line.
  void Serve(const char* route, const httplib::Request& req, httplib::Response& res,
             const Body& body) const;
  absl::Status Submit(const Caller& caller, const httplib::Request& req,
                      httplib::Response& res) const;
  absl::Status Report(const Caller& caller, const std::string& id, httplib::Response& res) const;

  const v1::DaemonConfig& config_;
  HttpGateway::Services services_;
  RateLimiter limiter_;
  const std::string page_policy_;
};

httplib::Server::HandlerResponse Api::Screen(const httplib::Request& req, httplib::Response& res) {
  res.set_header("X-Content-Type-Options", "nosniff");
  res.set_header("Referrer-Policy", "no-referrer");
  res.set_header("Cache-Control", "no-store");
  res.set_header("X-Frame-Options", "DENY");
  res.set_header("Cross-Origin-Opener-Policy", "same-origin");
  res.set_header("Cross-Origin-Resource-Policy", "same-origin");
  res.set_header("Content-Security-Policy", page_policy_);
  const auto refuse = [&](absl::Status status) {
    res.status = HttpStatusOf(status.code());
    SetBody(res, ErrorJson(status), "application/json");
    spdlog::info("http {} {} {} -> {}: {}", LogSafe(req.method), LogSafe(req.path),
                 LogSafe(req.remote_addr), res.status, LogSafe(std::string(status.message())));
    return httplib::Server::HandlerResponse::Handled;
  };
  if (!limiter_.Allow(req.remote_addr)) {
    return refuse(absl::ResourceExhaustedError(
        absl::StrCat("more than ", config_.limits().max_http_requests_per_minute(),
                     " requests a minute from this address (max_http_requests_per_minute)")));
  }
  // No cross-origin use: a browser names the origin of a page that calls from elsewhere
  if (req.get_header_value("Sec-Fetch-Site") == "cross-site") {
    return refuse(absl::PermissionDeniedError("cross-origin requests are refused"));
  }
  if (req.has_header("Origin")) {
    const std::string scheme = config_.tls_cert_file().empty() ? "http://" : "https://";
    if (req.get_header_value("Origin") != scheme + req.get_header_value("Host")) {
      return refuse(absl::PermissionDeniedError("cross-origin requests are refused"));
    }
  }
  return httplib::Server::HandlerResponse::Unhandled;
}

void Api::Serve(const char* route, const httplib::Request& req, httplib::Response& res,
                const Body& body) const {
  const auto start = std::chrono::steady_clock::now();
  std::string user = "-";
  const absl::Status status = [&]() -> absl::Status {
    std::optional<std::string_view> authorization;
    const size_t sent = req.get_header_value_count("Authorization");
    if (sent > 1) return absl::UnauthenticatedError("send one Authorization header");
    const std::string& value = req.get_header_value("Authorization");
    if (sent == 1) authorization = value;
    FENESTRA_ASSIGN_OR_RETURN(caller, services_.auth.Authenticate(authorization));
    user = caller.name;
    return body(caller, req, res);
  }();
  if (!status.ok()) {
    res.status = HttpStatusOf(status.code());
    SetBody(res, ErrorJson(status), "application/json");
  }
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  const std::string target = req.matches.size() > 1 ? LogSafe(req.matches[1].str()) : "";
  const bool quiet = status.ok() && req.method == "GET";  // the pages poll
  spdlog::log(quiet ? spdlog::level::debug : spdlog::level::info,
              "http {} {} {} {} \"{}\" -> {}{} ({:.1f} ms)", req.method, route,
              LogSafe(req.remote_addr), LogSafe(user), target,
              status.ok() ? "OK" : absl::StatusCodeToString(status.code()),
              status.ok() ? "" : absl::StrCat(": ", LogSafe(std::string(status.message()))), ms);
}

absl::Status Api::Submit(const Caller& caller, const httplib::Request& req,
                         httplib::Response& res) const {
  FENESTRA_ASSIGN_OR_RETURN(request, ParseDashboardSubmission(req.body));
  if (request.job().has_scene()) {
    FENESTRA_RETURN_IF_ERROR(WithField(CheckInlineScene(request.job().scene()), "scene"));
    FENESTRA_RETURN_IF_ERROR(
        WithField(CheckSceneLimits(request.job().scene(), config_.limits()), "scene"));
  }
  if (!request.weather_epw().empty()) {
    FENESTRA_RETURN_IF_ERROR(
        WithField(CheckUploadedWeather(request.weather_epw(), request.weather_name()), "weather"));
  }
  // The rest as the gRPC port checks it
  absl::StatusOr<v1::JobInfo> info = services_.jobs.Submit(request, caller);
  if (!info.ok()) return WithField(info.status(), "job");
  SetBody(res, ToJson(*info), "application/json");
  return absl::OkStatus();
}

absl::Status Api::Report(const Caller& caller, const std::string& id,
                         httplib::Response& res) const {
  FENESTRA_ASSIGN_OR_RETURN(info, services_.jobs.Get(id, caller));
  if (!info.has_result()) {
    return absl::FailedPreconditionError(absl::StrCat("job ", id, " has no result yet"));
  }
  FENESTRA_ASSIGN_OR_RETURN(html, RenderReport(info.result(), {.source = id, .sensor = ""}));
  SetBody(res, std::move(html), "text/html; charset=utf-8");
  return absl::OkStatus();
}

void Api::Route(httplib::Server& server) {
  server.set_pre_routing_handler(
      [this](const httplib::Request& req, httplib::Response& res) { return Screen(req, res); });
  // Answers without a body of their own (unknown routes, oversized bodies) get one
  const httplib::Server::HandlerWithResponse with_body = [](const httplib::Request&,
                                                            httplib::Response& res) {
    if (res.has_header("Content-Type")) return httplib::Server::HandlerResponse::Unhandled;
    const absl::StatusCode code = res.status == 404   ? absl::StatusCode::kNotFound
                                  : res.status == 413 ? absl::StatusCode::kResourceExhausted
                                                      : absl::StatusCode::kInvalidArgument;
    const char* message = res.status == 404   ? "no such page or API route"
                          : res.status == 413 ? "the request is larger than max_message_bytes"
                                              : "the request is malformed";
    SetBody(res, ErrorJson(absl::Status(code, message)), "application/json");
    return httplib::Server::HandlerResponse::Handled;
  };
  server.set_error_handler(with_body);
  for (const WebFile& file : WebFiles()) {
    const auto serve = [file](const httplib::Request&, httplib::Response& res) {
      SetBody(res, std::string(file.content), file.content_type);
    };
    server.Get(std::string(file.path), serve);
    if (file.path == "/index.html") server.Get("/", serve);
  }
  const auto api = [this](const char* route, Body body) {
    return
        [this, route, body = std::move(body)](const httplib::Request& req, httplib::Response& res) {
          Serve(route, req, res, body);
        };
  };
  const auto json = [](httplib::Response& res, const google::protobuf::Message& message) {
    SetBody(res, ToJson(message), "application/json");
    return absl::OkStatus();
  };
  const std::string job = absl::StrCat("/api/v1/jobs/", kId);
  const std::string site = absl::StrCat("/api/v1/sites/", kId);
  server.Get("/api/v1/me", api("me", [](const Caller& caller, const auto&, auto& res) {
               google::protobuf::Struct me;
               (*me.mutable_fields())["name"].set_string_value(caller.name);
               (*me.mutable_fields())["admin"].set_bool_value(caller.admin);
               SetBody(res, ToJson(me), "application/json");
               return absl::OkStatus();
             }));
  server.Get(
      "/api/v1/jobs",
      api("jobs.list", [this, json](const Caller& caller, const auto&, auto& res) -> absl::Status {
        FENESTRA_ASSIGN_OR_RETURN(jobs, services_.jobs.List(v1::JOB_STATE_UNSPECIFIED, 0, caller));
        v1::ListJobsResponse response;
        for (v1::JobInfo& j : jobs) *response.add_jobs() = std::move(j);
        return json(res, response);
      }));
  server.Post("/api/v1/jobs",
              api("jobs.submit", [this](const Caller& caller, const auto& req, auto& res) {
                return Submit(caller, req, res);
              }));
  server.Get(job,
             api("jobs.get",
                 [this, json](const Caller& caller, const auto& req, auto& res) -> absl::Status {
                   FENESTRA_ASSIGN_OR_RETURN(info, services_.jobs.Get(req.matches[1], caller));
                   return json(res, info);
                 }));
  server.Post(job + "/cancel",
              api("jobs.cancel",
                  [this, json](const Caller& caller, const auto& req, auto& res) -> absl::Status {
                    FENESTRA_ASSIGN_OR_RETURN(info, services_.jobs.Cancel(req.matches[1], caller));
                    return json(res, info);
                  }));
  server.Delete(job,
                api("jobs.delete",
                    [this, json](const Caller& caller, const auto& req, auto& res) -> absl::Status {
                      FENESTRA_RETURN_IF_ERROR(services_.jobs.Delete(req.matches[1], caller));
                      return json(res, v1::DeleteJobResponse());
                    }));
  server.Get(job + "/report",
             api("jobs.report", [this](const Caller& caller, const auto& req, auto& res) {
               return Report(caller, req.matches[1], res);
             }));
  server.Get(
      "/api/v1/sites",
      api("sites.list", [this, json](const Caller& caller, const auto&, auto& res) -> absl::Status {
        FENESTRA_ASSIGN_OR_RETURN(sites, services_.sites.List(caller));
        v1::ListSitesResponse response;
        for (v1::SiteInfo& s : sites) *response.add_sites() = std::move(s);
        return json(res, response);
      }));
  server.Delete(site,
                api("sites.delete",
                    [this, json](const Caller& caller, const auto& req, auto& res) -> absl::Status {
                      FENESTRA_RETURN_IF_ERROR(services_.sites.Delete(req.matches[1], caller));
                      return json(res, v1::DeleteSiteResponse());
                    }));
}

}  // namespace

absl::StatusOr<v1::SubmitJobRequest> ParseDashboardSubmission(const std::string& body) {
  // Each part parsed by itself, so that an error names the file it is in
  google::protobuf::Struct parts;
  FENESTRA_RETURN_IF_ERROR(WithField(FromJson(body, &parts, "request"), "job"));
  v1::SubmitJobRequest request;
  v1::Scene scene;
  for (const auto& [key, value] : parts.fields()) {
    if (key == "job" || key == "scene") {
      if (!value.has_struct_value()) {
        return WithField(absl::InvalidArgumentError(absl::StrCat(key, ": must be an object")), key);
      }
      google::protobuf::Message* into =
          key == "job" ? static_cast<google::protobuf::Message*>(request.mutable_job()) : &scene;
      FENESTRA_RETURN_IF_ERROR(WithField(FromJson(ToJson(value.struct_value()), into, key), key));
    } else if (key == "weatherEpw" || key == "weatherName") {
      if (!value.has_string_value()) {
        return WithField(absl::InvalidArgumentError(absl::StrCat(key, ": must be a string")),
                         "weather");
      }
      if (key == "weatherName") {
        request.set_weather_name(value.string_value());
      } else if (!absl::Base64Unescape(value.string_value(), request.mutable_weather_epw())) {
        return WithField(absl::InvalidArgumentError("weatherEpw: not base64"), "weather");
      }
    } else {
      return WithField(
          absl::InvalidArgumentError(absl::StrCat("unknown field '", LogSafe(key, 64), "'")), "");
    }
  }
  if (parts.fields().contains("scene")) *request.mutable_job()->mutable_scene() = std::move(scene);
  return request;
}

absl::StatusOr<std::unique_ptr<HttpGateway>> HttpGateway::Start(const v1::DaemonConfig& config,
                                                                Services services) {
  FENESTRA_ASSIGN_OR_RETURN(address, HostAndPort(config.http_listen()));
  std::unique_ptr<HttpGateway> gateway(new HttpGateway());
  if (config.tls_cert_file().empty()) {
    gateway->server_ = std::make_unique<httplib::Server>();
  } else {
    auto tls = std::make_unique<httplib::SSLServer>(
        config.tls_cert_file().c_str(), config.tls_key_file().c_str(),
        config.tls_client_ca_file().empty() ? nullptr : config.tls_client_ca_file().c_str());
    if (!tls->is_valid()) {
      return absl::UnavailableError(
          "http_listen: the TLS certificate, key or client CA files do not load");
    }
    gateway->server_ = std::move(tls);
  }
  httplib::Server& server = *gateway->server_;
  server.new_task_queue = [] { return new httplib::ThreadPool(kHttpThreads); };
  server.set_payload_max_length(static_cast<size_t>(config.limits().max_message_bytes()));
  server.set_read_timeout(kHttpTimeoutSeconds);
  server.set_write_timeout(kHttpTimeoutSeconds);
  // One request per connection: httplib holds a thread for each open connection, and a page
  // that polls every second would keep its own for good, so that a few pages would take
  // every thread and stall the others' requests
  server.set_keep_alive_max_count(1);
  auto api = std::make_shared<Api>(config, services);
  api->Route(server);
  gateway->routes_ = api;
  const auto& [host, port] = address;
  gateway->port_ =
      port == 0 ? server.bind_to_any_port(host) : (server.bind_to_port(host, port) ? port : -1);
  if (gateway->port_ <= 0) {
    return absl::UnavailableError(
        absl::StrCat("cannot listen on ", config.http_listen(), " (address in use?)"));
  }
  gateway->thread_ = std::thread([&server] { server.listen_after_bind(); });
  spdlog::info("dashboard on {} (port {}, {})", config.http_listen(), gateway->port_,
               config.tls_cert_file().empty() ? "HTTP" : "HTTPS");
  return gateway;
}

HttpGateway::~HttpGateway() {
  if (server_) server_->stop();
  if (thread_.joinable()) thread_.join();
}

}  // namespace fenestra
