#include "client/grpc_client.h"

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdlib>
#include <iostream>
#include <utility>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/strip.h"
#include "client/cli_util.h"
#include "core/common/status_macros.h"

namespace fenestra {
namespace {

constexpr int kMaxMessageBytes = 256 << 20;
constexpr int kKeepaliveMs = 30'000;
constexpr int kKeepaliveTimeoutMs = 10'000;

// A PEM file named by `flag`; an error names the flag and the file.
absl::StatusOr<std::string> ReadPemFile(const char* flag, const std::string& path) {
  absl::StatusOr<std::string> pem = ReadFileBytes(path);
  if (!pem.ok()) return absl::InvalidArgumentError(absl::StrCat(flag, " ", pem.status().message()));
  if (!absl::StrContains(*pem, "-----BEGIN ")) {
    return absl::InvalidArgumentError(
        absl::StrCat(flag, " ", path, ": not a PEM file (no \"-----BEGIN\" line)"));
  }
  return pem;
}

// Insecure credentials without --tls-ca; TLS verified with that CA, with the client
// certificate when one is given.
absl::StatusOr<std::shared_ptr<grpc::ChannelCredentials>> ChannelCredentials(
    const ServerOptions& options) {
  const bool has_cert = !options.tls_cert_file.empty(), has_key = !options.tls_key_file.empty();
  if (has_cert != has_key) {
    return absl::InvalidArgumentError(
        "--tls-cert and --tls-key go together (the client certificate and its private key)");
  }
  if (options.tls_ca_file.empty()) {
    if (has_cert) {
      return absl::InvalidArgumentError(
          "--tls-cert needs --tls-ca (the CA that signed fenestrad's certificate)");
    }
    return grpc::InsecureChannelCredentials();
  }
  grpc::SslCredentialsOptions tls;
  FENESTRA_ASSIGN_OR_RETURN(ca, ReadPemFile("--tls-ca", options.tls_ca_file));
  tls.pem_root_certs = std::move(ca);
  if (has_cert) {
    FENESTRA_ASSIGN_OR_RETURN(cert, ReadPemFile("--tls-cert", options.tls_cert_file));
    FENESTRA_ASSIGN_OR_RETURN(key, ReadPemFile("--tls-key", options.tls_key_file));
    tls.pem_cert_chain = std::move(cert);
    tls.pem_private_key = std::move(key);
  }
  return grpc::SslCredentials(tls);
}

// The server's text with control characters shown as \xNN, so that it cannot rewrite the
// user's terminal.
std::string Printable(absl::string_view text) {
  std::string out;
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte < 0x20 || byte == 0x7f) {
      absl::StrAppendFormat(&out, "\\x%02x", byte);
    } else {
      out += c;
    }
  }
  return out;
}

// The host of a gRPC target ("dns:///host:port", "host:port", "[::1]:port", "unix:path").
bool IsLocalTarget(absl::string_view target) {
  if (absl::StartsWith(target, "unix:")) return true;
  for (const absl::string_view scheme : {"dns:///", "ipv4:", "ipv6:"}) {
    absl::ConsumePrefix(&target, scheme);
  }
  const size_t colon = target.rfind(':');
  const absl::string_view host =
      colon == absl::string_view::npos ? target : target.substr(0, colon);
  return host == "localhost" || absl::StartsWith(host, "127.") || host == "[::1]";
}

}  // namespace

void AddServerOptions(CLI::App* command, ServerOptions& options) {
  CLI::Option_group* group = command->add_option_group("fenestrad", "How to reach fenestrad");
  group->add_option("--server", options.address, "fenestrad address")
      ->type_name("HOST:PORT")
      ->capture_default_str();
  group->add_option("--timeout", options.timeout_seconds, "Deadline of each request [s]")
      ->type_name("SECONDS")
      ->capture_default_str();
  group
      ->add_option("--tls-ca", options.tls_ca_file,
                   "Use TLS and verify fenestrad's certificate with this CA (PEM)")
      ->type_name("FILE");
  group
      ->add_option("--tls-cert", options.tls_cert_file,
                   "Client certificate (PEM) for a fenestrad that asks for one; with --tls-key")
      ->type_name("FILE");
  group->add_option("--tls-key", options.tls_key_file, "The client certificate's private key (PEM)")
      ->type_name("FILE");
  group
      ->add_option("--token-file", options.token_file,
                   absl::StrCat("Bearer token sent with every request; default: the ",
                                kTokenEnvironmentVariable, " environment variable"))
      ->type_name("FILE");
}

absl::StatusOr<std::optional<std::string>> LoadToken(const std::string& token_file,
                                                     const char* environment_token) {
  std::string source, token;
  if (!token_file.empty()) {
    source = absl::StrCat("--token-file ", token_file);
    absl::StatusOr<std::string> bytes = ReadFileBytes(token_file);
    if (!bytes.ok()) {
      return absl::InvalidArgumentError(absl::StrCat("--token-file ", bytes.status().message()));
    }
    token = *std::move(bytes);
  } else if (environment_token != nullptr) {
    source = kTokenEnvironmentVariable;
    token = environment_token;
  } else {
    return std::nullopt;
  }
  absl::StripAsciiWhitespace(&token);
  if (token.empty())
    return absl::InvalidArgumentError(absl::StrCat(source, ": the token is empty"));
  // A metadata value is visible ASCII; a space would split "Bearer <token>"
  for (size_t i = 0; i < token.size(); ++i) {
    const auto byte = static_cast<unsigned char>(token[i]);
    if (byte <= 0x20 || byte >= 0x7f) {
      return absl::InvalidArgumentError(
          absl::StrCat(source, ": the token's character ", i + 1,
                       " cannot go in a request header (only visible ASCII, no spaces)"));
    }
  }
  return token;
}

absl::StatusOr<FenestraClient> FenestraClient::Connect(const ServerOptions& options) {
  if (!(options.timeout_seconds > 0)) {
    return absl::InvalidArgumentError("--timeout must be more than 0 s");
  }
  FENESTRA_ASSIGN_OR_RETURN(credentials, ChannelCredentials(options));
  FENESTRA_ASSIGN_OR_RETURN(token,
                            LoadToken(options.token_file, std::getenv(kTokenEnvironmentVariable)));
  return FenestraClient(options, std::move(credentials), std::move(token));
}

FenestraClient::FenestraClient(const ServerOptions& options,
                               std::shared_ptr<grpc::ChannelCredentials> credentials,
                               std::optional<std::string> token)
    : options_(options), token_(std::move(token)) {
  grpc::ChannelArguments args;
  args.SetInt(GRPC_ARG_KEEPALIVE_TIME_MS, kKeepaliveMs);
  args.SetInt(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, kKeepaliveTimeoutMs);
  args.SetInt(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
  args.SetMaxReceiveMessageSize(kMaxMessageBytes);
  args.SetMaxSendMessageSize(kMaxMessageBytes);
  channel_ = grpc::CreateCustomChannel(options.address, credentials, args);
  sites_ = v1::SiteService::NewStub(channel_);
  jobs_ = v1::JobService::NewStub(channel_);
}

bool FenestraClient::SendsTokenInClear() const {
  return token_.has_value() && options_.tls_ca_file.empty() && !IsLocalTarget(options_.address);
}

std::unique_ptr<grpc::ClientContext> FenestraClient::NewContext(bool with_deadline) const {
  auto context = std::make_unique<grpc::ClientContext>();
  if (with_deadline) {
    context->set_deadline(std::chrono::system_clock::now() +
                          std::chrono::duration_cast<std::chrono::system_clock::duration>(
                              std::chrono::duration<double>(options_.timeout_seconds)));
  }
  if (token_) context->AddMetadata("authorization", absl::StrCat("Bearer ", *token_));
  return context;
}

template <typename Stub, typename Request, typename Response>
absl::StatusOr<Response> FenestraClient::Call(
    Stub& stub, grpc::Status (Stub::*method)(grpc::ClientContext*, const Request&, Response*),
    const Request& request) const {
  Response response;
  const std::unique_ptr<grpc::ClientContext> context = NewContext(/*with_deadline=*/true);
  FENESTRA_RETURN_IF_ERROR(ToStatus((stub.*method)(context.get(), request, &response)));
  return response;
}

absl::Status FenestraClient::ToStatus(const grpc::Status& status) const {
  if (status.ok()) return absl::OkStatus();
  const std::string message = Printable(status.error_message());
  const std::string& address = options_.address;
  switch (status.error_code()) {
    case grpc::StatusCode::UNAVAILABLE:
      // fenestrad's own UNAVAILABLE (shutting down) comes over a connection that stands
      if (channel_->GetState(/*try_to_connect=*/false) == GRPC_CHANNEL_READY) break;
      if (!options_.tls_ca_file.empty()) {
        return absl::UnavailableError(absl::StrCat(
            "cannot reach fenestrad at ", address, " over TLS (", message,
            "); is it running, and does it serve TLS with a certificate signed by the --tls-ca "
            "CA?"));
      }
      return absl::UnavailableError(
          absl::StrCat("cannot reach fenestrad at ", address, " (", message, "); is it running?"));
    case grpc::StatusCode::DEADLINE_EXCEEDED:
      return absl::DeadlineExceededError(absl::StrCat("fenestrad at ", address,
                                                      " did not answer within ",
                                                      options_.timeout_seconds, " s (--timeout)"));
    case grpc::StatusCode::UNAUTHENTICATED:
      return absl::UnauthenticatedError(
          absl::StrCat(token_ ? "fenestrad refused the token (" : "fenestrad wants a token (",
                       message, "): set --token-file or ", kTokenEnvironmentVariable));
    default:
      break;
  }
  const auto code = static_cast<absl::StatusCode>(status.error_code());
  return absl::Status(code, absl::StrCat(absl::StatusCodeToString(code), ": ", message));
}

absl::StatusOr<v1::SiteInfo> FenestraClient::RegisterSite(const v1::RegisterSiteRequest& request) {
  return Call(*sites_, &v1::SiteService::Stub::Register, request);
}

absl::StatusOr<v1::SiteInfo> FenestraClient::GetSite(const std::string& id) {
  v1::GetSiteRequest request;
  request.set_id(id);
  return Call(*sites_, &v1::SiteService::Stub::Get, request);
}

absl::StatusOr<v1::ListSitesResponse> FenestraClient::ListSites() {
  return Call(*sites_, &v1::SiteService::Stub::List, v1::ListSitesRequest());
}

absl::Status FenestraClient::DeleteSite(const std::string& id) {
  v1::DeleteSiteRequest request;
  request.set_id(id);
  return Call(*sites_, &v1::SiteService::Stub::Delete, request).status();
}

absl::StatusOr<v1::JobInfo> FenestraClient::SubmitJob(const v1::SubmitJobRequest& request) {
  return Call(*jobs_, &v1::JobService::Stub::Submit, request);
}

absl::StatusOr<v1::JobInfo> FenestraClient::GetJob(const std::string& id) {
  v1::GetJobRequest request;
  request.set_id(id);
  return Call(*jobs_, &v1::JobService::Stub::Get, request);
}

absl::StatusOr<v1::ListJobsResponse> FenestraClient::ListJobs(const v1::ListJobsRequest& request) {
  return Call(*jobs_, &v1::JobService::Stub::List, request);
}

absl::StatusOr<v1::JobInfo> FenestraClient::CancelJob(const std::string& id) {
  v1::CancelJobRequest request;
  request.set_id(id);
  return Call(*jobs_, &v1::JobService::Stub::Cancel, request);
}

absl::Status FenestraClient::DeleteJob(const std::string& id) {
  v1::DeleteJobRequest request;
  request.set_id(id);
  return Call(*jobs_, &v1::JobService::Stub::Delete, request).status();
}

absl::Status FenestraClient::WatchJob(const std::string& id,
                                      absl::FunctionRef<void(const v1::JobEvent&)> on_event) {
  const std::unique_ptr<grpc::ClientContext> context = NewContext(/*with_deadline=*/false);
  v1::WatchJobRequest request;
  request.set_id(id);
  const std::unique_ptr<grpc::ClientReader<v1::JobEvent>> reader =
      jobs_->Watch(context.get(), request);
  v1::JobEvent event;
  while (reader->Read(&event)) on_event(event);
  return ToStatus(reader->Finish());
}

FenestraClient ConnectOrFail(const ServerOptions& options) {
  FenestraClient client = ValueOrFail(FenestraClient::Connect(options));
  if (client.SendsTokenInClear()) {
    std::cerr << "warning: the token goes to " << options.address
              << " unencrypted; give --tls-ca to use TLS" << std::endl;
  }
  return client;
}

}  // namespace fenestra
