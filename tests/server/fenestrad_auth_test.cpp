// fenestrad with users end to end: a real daemon on loopback with TLS (certificates made by
// the openssl command) or plaintext, users and tokens made by `fenestrad user`, called
// through gRPC stubs as different users.
#include <grpcpp/generic/generic_stub.h>

#include <future>

#include "tests/certificates.h"
#include "tests/server/fenestrad_harness.h"

namespace fenestra {
namespace {

using namespace testing_fenestrad;
using ::testing::HasSubstr;

// One user's view of a daemon: stub calls with the user's token ("" = none).
class User {
 public:
  User(std::shared_ptr<grpc::Channel> channel, std::string token)
      : jobs_(v1::JobService::NewStub(channel)),
        sites_(v1::SiteService::NewStub(channel)),
        token_(std::move(token)) {}

  grpc::Status Submit(const v1::SubmitJobRequest& request, v1::JobInfo* job = nullptr) {
    v1::JobInfo info;
    return jobs_->Submit(Context().get(), request, job ? job : &info);
  }
  grpc::Status GetJob(const std::string& id, v1::JobInfo* job = nullptr) {
    v1::GetJobRequest request;
    request.set_id(id);
    v1::JobInfo info;
    return jobs_->Get(Context().get(), request, job ? job : &info);
  }
  grpc::Status CancelJob(const std::string& id) {
    v1::CancelJobRequest request;
    request.set_id(id);
    v1::JobInfo info;
    return jobs_->Cancel(Context().get(), request, &info);
  }
  // Reads the whole stream; its status.
  grpc::Status WatchJob(const std::string& id) {
    v1::WatchJobRequest request;
    request.set_id(id);
    auto context = Context();
    auto reader = jobs_->Watch(context.get(), request);
    v1::JobEvent event;
    while (reader->Read(&event)) {
    }
    return reader->Finish();
  }
  std::vector<v1::JobInfo> ListJobs(grpc::Status* status = nullptr) {
    v1::ListJobsResponse response;
    const grpc::Status s = jobs_->List(Context().get(), v1::ListJobsRequest(), &response);
    if (status) *status = s;
    return {response.jobs().begin(), response.jobs().end()};
  }
  grpc::Status Register(const v1::RegisterSiteRequest& request, v1::SiteInfo* site = nullptr) {
    v1::SiteInfo info;
    return sites_->Register(Context().get(), request, site ? site : &info);
  }
  grpc::Status GetSite(const std::string& id, v1::SiteInfo* site = nullptr) {
    v1::GetSiteRequest request;
    request.set_id(id);
    v1::SiteInfo info;
    return sites_->Get(Context().get(), request, site ? site : &info);
  }
  grpc::Status DeleteSite(const std::string& id) {
    v1::DeleteSiteRequest request;
    request.set_id(id);
    v1::DeleteSiteResponse response;
    return sites_->Delete(Context().get(), request, &response);
  }
  std::vector<v1::SiteInfo> ListSites(grpc::Status* status = nullptr) {
    v1::ListSitesResponse response;
    const grpc::Status s = sites_->List(Context().get(), v1::ListSitesRequest(), &response);
    if (status) *status = s;
    return {response.sites().begin(), response.sites().end()};
  }
  // Polls the job until `done` or 60 s.
  v1::JobInfo WaitJob(const std::string& id, const std::function<bool(const v1::JobInfo&)>& done) {
    const auto deadline = Clock::now() + std::chrono::seconds(60);
    v1::JobInfo info;
    while (GetJob(id, &info).ok() && !done(info) && Clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    EXPECT_TRUE(done(info)) << info.DebugString();
    return info;
  }

 private:
  std::unique_ptr<grpc::ClientContext> Context() const {
    auto context = std::make_unique<grpc::ClientContext>();
    context->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
    if (!token_.empty()) context->AddMetadata("authorization", "Bearer " + token_);
    return context;
  }

  std::unique_ptr<v1::JobService::Stub> jobs_;
  std::unique_ptr<v1::SiteService::Stub> sites_;
  std::string token_;
};

bool IsTerminal(v1::JobState s) {
  return s == v1::JOB_STATE_SUCCEEDED || s == v1::JOB_STATE_FAILED ||
         s == v1::JOB_STATE_CANCELLED || s == v1::JOB_STATE_INTERRUPTED;
}

class FenestradAuthTest : public FenestradTest {
 protected:
  // A daemon with token auth and TLS (server certificate for 127.0.0.1), and channels that
  // trust its CA.
  std::unique_ptr<Daemon> StartTls(std::vector<std::string> flags = {}) {
    flags.insert(flags.end(), {"--tls-cert", Certs().server_cert, "--tls-key", Certs().server_key});
    auto daemon = std::make_unique<Daemon>(dir_ + "/data", std::move(flags), TlsCredentials());
    daemon->Start();
    return daemon;
  }
  // A daemon with token auth on plaintext loopback.
  std::unique_ptr<Daemon> StartPlaintext(std::vector<std::string> flags = {}) {
    auto daemon = std::make_unique<Daemon>(dir_ + "/data", std::move(flags));
    daemon->Start();
    return daemon;
  }
  static std::shared_ptr<grpc::ChannelCredentials> TlsCredentials(bool client_certificate = false) {
    grpc::SslCredentialsOptions options;
    options.pem_root_certs = ReadFile(Certs().ca_cert);
    if (client_certificate) {
      options.pem_cert_chain = ReadFile(Certs().client_cert);
      options.pem_private_key = ReadFile(Certs().client_key);
    }
    return grpc::SslCredentials(options);
  }
  // The site the tiny job runs on, with or without its weather file.
  v1::RegisterSiteRequest SiteRequest(bool with_weather = true) const {
    const v1::SubmitJobRequest job = InlineRequest(TinyJob());
    v1::RegisterSiteRequest request;
    request.set_name("montevideo");
    *request.mutable_scene() = job.job().scene();
    *request.mutable_sampling() = job.job().sampling();
    if (with_weather) request.set_weather_epw(job.weather_epw());
    return request;
  }
  // A job on `site_id`, using the site's weather file.
  v1::SubmitJobRequest OnSite(const v1::Job& job, const std::string& site_id) const {
    v1::SubmitJobRequest request = InlineRequest(job);
    request.clear_weather_epw();
    request.set_site_id(site_id);
    return request;
  }
};

void ExpectStatus(const grpc::Status& status, grpc::StatusCode code, const std::string& text) {
  EXPECT_EQ(status.error_code(), code) << status.error_message();
  EXPECT_THAT(status.error_message(), HasSubstr(text));
}

// A call to `method` with an empty request through a generic stub, without a token.
grpc::Status CallWithoutToken(const std::shared_ptr<grpc::Channel>& channel,
                              const std::string& method, std::string* response_bytes) {
  grpc::GenericStub stub(channel);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
  grpc::Slice empty(std::string{});
  grpc::ByteBuffer request(&empty, 1), response;
  std::promise<grpc::Status> done;
  stub.UnaryCall(&context, method, grpc::StubOptions(), &request, &response,
                 [&](grpc::Status status) { done.set_value(std::move(status)); });
  const grpc::Status status = done.get_future().get();
  std::vector<grpc::Slice> slices;
  if (status.ok() && response.Dump(&slices).ok()) {
    for (const grpc::Slice& s : slices) {
      response_bytes->append(reinterpret_cast<const char*>(s.begin()), s.size());
    }
  }
  return status;
}

TEST_F(FenestradAuthTest, EveryCallNeedsAValidTokenButTheHealthCheck) {
  const std::string ann = AddUser("ann");
  auto d = StartTls();
  std::string wrong = ann;
  wrong[0] = wrong[0] == 'a' ? 'b' : 'a';
  for (const std::string& token : {std::string(), wrong, std::string(64, '0')}) {
    User caller(d->channel(), token);
    grpc::Status status;
    caller.ListJobs(&status);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAUTHENTICATED) << token;
    caller.ListSites(&status);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAUTHENTICATED) << token;
    EXPECT_EQ(caller.GetJob("job-1").error_code(), grpc::StatusCode::UNAUTHENTICATED);
    EXPECT_EQ(caller.Submit(InlineRequest(TinyJob())).error_code(),
              grpc::StatusCode::UNAUTHENTICATED);
    EXPECT_EQ(caller.WatchJob("job-1").error_code(), grpc::StatusCode::UNAUTHENTICATED);
  }
  ExpectStatus(User(d->channel(), "").GetJob("job-1"), grpc::StatusCode::UNAUTHENTICATED,
               "authorization: Bearer <token>");
  // A wrong token and an unknown one read the same
  EXPECT_EQ(User(d->channel(), wrong).GetJob("job-1").error_message(),
            User(d->channel(), std::string(64, '0')).GetJob("job-1").error_message());
  grpc::Status status;
  User(d->channel(), ann).ListJobs(&status);
  EXPECT_TRUE(status.ok()) << status.error_message();

  // gRPC's own call credentials send the same metadata
  auto channel = grpc::CreateChannel(
      d->address(),
      grpc::CompositeChannelCredentials(TlsCredentials(), grpc::AccessTokenCredentials(ann)));
  v1::ListSitesResponse sites;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
  EXPECT_TRUE(
      v1::SiteService::NewStub(channel)->List(&context, v1::ListSitesRequest(), &sites).ok());

  // Probes need no token; reflection, which would need none either, is not served
  std::string health;
  ASSERT_TRUE(CallWithoutToken(d->channel(), "/grpc.health.v1.Health/Check", &health).ok());
  EXPECT_EQ(health, std::string("\x08\x01", 2));  // SERVING
  EXPECT_EQ(
      CallWithoutToken(d->channel(),
                       "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo", &health)
          .error_code(),
      grpc::StatusCode::UNIMPLEMENTED);

  // A revoked token fails at once on the running daemon
  const CliResult r =
      Daemon::RunCli({FENESTRAD, "user", "revoke", "ann", "--data-dir", dir_ + "/data"});
  ASSERT_EQ(r.code, 0) << r.err;
  ExpectStatus(User(d->channel(), ann).GetJob("job-1"), grpc::StatusCode::UNAUTHENTICATED,
               "not valid");
  // The log names callers, never tokens
  EXPECT_THAT(d->Log(), HasSubstr("UNAUTHENTICATED"));
  EXPECT_EQ(d->Log().find(ann), std::string::npos);
}

TEST_F(FenestradAuthTest, UsersSeeAndActOnTheirOwnJobsAndSitesOnly) {
  const std::string ann_token = AddUser("ann"), bob_token = AddUser("bob"),
                    root_token = AddUser("root", /*admin=*/true);
  auto d = StartTls({"--workers", "1"});
  User ann(d->channel(), ann_token), bob(d->channel(), bob_token), root(d->channel(), root_token);

  v1::SiteInfo site;
  ASSERT_TRUE(ann.Register(SiteRequest(), &site).ok());
  EXPECT_TRUE(site.owner().empty());  // owners are shown to administrators only
  v1::JobInfo job;
  ASSERT_TRUE(ann.Submit(OnSite(LongJob(), site.id()), &job).ok());
  const std::string& id = job.id();

  // To bob, ann's job and site are unknown ids
  auto same_as_unknown = [](const grpc::Status& status, const grpc::Status& unknown,
                            const std::string& id, const std::string& unknown_id) {
    EXPECT_EQ(status.error_code(), grpc::StatusCode::NOT_FOUND) << status.error_message();
    std::string message = unknown.error_message();
    message.replace(message.find(unknown_id), unknown_id.size(), id);
    EXPECT_EQ(status.error_message(), message);
  };
  same_as_unknown(bob.GetJob(id), bob.GetJob("job-99"), id, "job-99");
  same_as_unknown(bob.WatchJob(id), bob.WatchJob("job-99"), id, "job-99");
  same_as_unknown(bob.CancelJob(id), bob.CancelJob("job-99"), id, "job-99");
  same_as_unknown(bob.GetSite(site.id()), bob.GetSite("site-99"), site.id(), "site-99");
  same_as_unknown(bob.DeleteSite(site.id()), bob.DeleteSite("site-99"), site.id(), "site-99");
  same_as_unknown(bob.Submit(OnSite(TinyJob(), site.id())),
                  bob.Submit(OnSite(TinyJob(), "site-99")), site.id(), "site-99");
  EXPECT_TRUE(bob.ListJobs().empty());
  EXPECT_TRUE(bob.ListSites().empty());
  // ... and nothing happened to them
  v1::JobInfo seen;
  ASSERT_TRUE(ann.GetJob(id, &seen).ok());
  EXPECT_FALSE(seen.cancel_requested());
  EXPECT_FALSE(IsTerminal(seen.state()));
  v1::SiteInfo own;
  ASSERT_TRUE(ann.GetSite(site.id(), &own).ok());
  EXPECT_TRUE(own.has_scene());
  ASSERT_EQ(ann.ListJobs().size(), 1u);
  EXPECT_TRUE(ann.ListJobs()[0].owner().empty());

  // bob's own work, on his own site, shares ann's cached matrix by content
  v1::SiteInfo bob_site;
  ASSERT_TRUE(bob.Register(SiteRequest(), &bob_site).ok());
  EXPECT_EQ(bob_site.outdoor_key(), site.outdoor_key());
  v1::JobInfo bob_job;
  ASSERT_TRUE(bob.Submit(OnSite(TinyJob(2), bob_site.id()), &bob_job).ok());
  EXPECT_EQ(ann.GetJob(bob_job.id()).error_code(), grpc::StatusCode::NOT_FOUND);

  // The administrator sees all, with owners, and acts on all
  const std::vector<v1::JobInfo> jobs = root.ListJobs();
  ASSERT_EQ(jobs.size(), 2u);
  EXPECT_EQ(jobs[0].id(), bob_job.id());  // newest first
  EXPECT_EQ(jobs[0].owner(), "bob");
  EXPECT_EQ(jobs[1].owner(), "ann");
  const std::vector<v1::SiteInfo> sites = root.ListSites();
  ASSERT_EQ(sites.size(), 2u);
  EXPECT_EQ(sites[0].owner(), "ann");
  EXPECT_EQ(sites[1].owner(), "bob");
  v1::SiteInfo full;
  ASSERT_TRUE(root.GetSite(site.id(), &full).ok());
  EXPECT_TRUE(full.has_scene());
  EXPECT_EQ(full.owner(), "ann");
  ASSERT_TRUE(root.CancelJob(id).ok());
  EXPECT_EQ(ann.WaitJob(id, Ended).state(), v1::JOB_STATE_CANCELLED);
  EXPECT_TRUE(ann.WatchJob(id).ok());
  EXPECT_EQ(bob.WaitJob(bob_job.id(), Ended).state(), v1::JOB_STATE_SUCCEEDED);
  EXPECT_TRUE(root.DeleteSite(bob_site.id()).ok());
  EXPECT_TRUE(bob.ListSites().empty());
  EXPECT_THAT(d->Log(), HasSubstr("site " + bob_site.id() + " deleted by root"));
}

TEST_F(FenestradAuthTest, TlsPortRefusesPlaintextAndMutualTlsRefusesClientsWithoutACertificate) {
  const std::string ann = AddUser("ann");
  auto d = StartTls({"--tls-client-ca", Certs().ca_cert});
  auto deadline = [] { return std::chrono::system_clock::now() + std::chrono::seconds(10); };
  auto list = [&](std::shared_ptr<grpc::ChannelCredentials> credentials) {
    auto channel = grpc::CreateChannel(d->address(), credentials);
    grpc::ClientContext context;
    context.set_deadline(deadline());
    context.AddMetadata("authorization", "Bearer " + ann);
    v1::ListJobsResponse response;
    return v1::JobService::NewStub(channel)->List(&context, v1::ListJobsRequest(), &response);
  };
  EXPECT_TRUE(list(TlsCredentials(/*client_certificate=*/true)).ok());
  EXPECT_EQ(list(TlsCredentials(/*client_certificate=*/false)).error_code(),
            grpc::StatusCode::UNAVAILABLE);
  EXPECT_EQ(list(grpc::InsecureChannelCredentials()).error_code(), grpc::StatusCode::UNAVAILABLE);
  // A TLS client that does not trust the server's CA gets nowhere either
  grpc::SslCredentialsOptions stranger;
  stranger.pem_root_certs = ReadFile(Certs().client_cert);
  stranger.pem_cert_chain = ReadFile(Certs().client_cert);
  stranger.pem_private_key = ReadFile(Certs().client_key);
  EXPECT_EQ(list(grpc::SslCredentials(stranger)).error_code(), grpc::StatusCode::UNAVAILABLE);
  EXPECT_THAT(d->Log(), HasSubstr("TLS with client certificates, auth token"));
}

TEST_F(FenestradAuthTest, StartIsRefusedWhenItWouldExposeTheDaemon) {
  const std::string data = dir_ + "/data";
  auto start = [&](std::vector<std::string> flags) {
    flags.insert(flags.begin(), {FENESTRAD, "--data-dir", data});
    return Daemon::RunCli(flags);
  };
  CliResult r = start({"--listen", "0.0.0.0:0", "--auth", "none"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("auth none makes every caller an administrator"));
  EXPECT_THAT(r.err, HasSubstr("not on '0.0.0.0:0'"));
  r = start({"--listen", "0.0.0.0:0"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("--tls-cert, --tls-key"));
  EXPECT_THAT(r.err, HasSubstr("--allow-plaintext"));
  r = start({"--listen", "[::]:0", "--auth", "none", "--tls-cert", Certs().server_cert, "--tls-key",
             Certs().server_key});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("auth none"));
  // Files that do not belong together stop the start before anything is served
  r = start({"--tls-cert", Certs().server_cert, "--tls-key", Certs().client_key});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("is not the key of the certificate"));
  EXPECT_FALSE(fs::exists(data + "/fenestra.db"));
}

TEST_F(FenestradAuthTest, QueuedJobsTakeTurnsAcrossUsers) {
  const std::string ann_token = AddUser("ann"), bob_token = AddUser("bob");
  auto d = StartPlaintext({"--workers", "1"});  // tokens over loopback plaintext
  User ann(d->channel(), ann_token), bob(d->channel(), bob_token);

  // ann's first job holds the worker while ann queues two more, then bob one
  v1::JobInfo a1, a2, a3, b1;
  ASSERT_TRUE(ann.Submit(InlineRequest(LongJob()), &a1).ok());
  ann.WaitJob(a1.id(), Running);
  ASSERT_TRUE(ann.Submit(InlineRequest(TinyJob(2)), &a2).ok());
  ASSERT_TRUE(ann.Submit(InlineRequest(TinyJob(2)), &a3).ok());
  ASSERT_TRUE(bob.Submit(InlineRequest(TinyJob(2)), &b1).ok());
  // bob was never served: his job goes next, then ann's in their order
  EXPECT_EQ(b1.queue_position(), 0);
  ASSERT_TRUE(ann.GetJob(a2.id(), &a2).ok());
  ASSERT_TRUE(ann.GetJob(a3.id(), &a3).ok());
  EXPECT_EQ(a2.queue_position(), 1);
  EXPECT_EQ(a3.queue_position(), 2);

  ASSERT_TRUE(ann.CancelJob(a1.id()).ok());
  b1 = bob.WaitJob(b1.id(), Ended);
  a2 = ann.WaitJob(a2.id(), Ended);
  a3 = ann.WaitJob(a3.id(), Ended);
  for (const v1::JobInfo* j : {&b1, &a2, &a3}) EXPECT_EQ(j->state(), v1::JOB_STATE_SUCCEEDED);
  EXPECT_LT(b1.started_unix_ms(), a2.started_unix_ms());
  EXPECT_LT(a2.started_unix_ms(), a3.started_unix_ms());
  EXPECT_GE(b1.started_unix_ms(), ann.WaitJob(a1.id(), Ended).finished_unix_ms());
}

TEST_F(FenestradAuthTest, PerUserLimitsAreRefusedNamingTheLimit) {
  const std::string ann_token = AddUser("ann"), bob_token = AddUser("bob");
  const int64_t epw = static_cast<int64_t>(SiteRequest().weather_epw().size());
  const int64_t limit = epw * 5 / 2;  // two weather files, not three
  auto d =
      StartPlaintext({"--workers", "1", "--max-queued-jobs-per-user", "1", "--max-sites-per-user",
                      "1", "--max-upload-bytes-per-user", std::to_string(limit)});
  User ann(d->channel(), ann_token), bob(d->channel(), bob_token);

  v1::SiteInfo site;
  ASSERT_TRUE(ann.Register(SiteRequest(), &site).ok());
  EXPECT_EQ(site.upload_bytes(), epw);
  ExpectStatus(ann.Register(SiteRequest(/*with_weather=*/false)),
               grpc::StatusCode::RESOURCE_EXHAUSTED, "limits.max_sites_per_user (1) reached");
  v1::JobInfo running;
  ASSERT_TRUE(ann.Submit(InlineRequest(LongJob()), &running).ok());  // its own weather file
  EXPECT_EQ(running.upload_bytes(), epw);
  ann.WaitJob(running.id(), Running);
  ExpectStatus(ann.Submit(InlineRequest(TinyJob())), grpc::StatusCode::RESOURCE_EXHAUSTED,
               "limits.max_upload_bytes_per_user (" + std::to_string(limit) + ") reached");
  v1::JobInfo queued;
  ASSERT_TRUE(ann.Submit(OnSite(TinyJob(), site.id()), &queued).ok());  // no upload
  EXPECT_EQ(queued.upload_bytes(), 0);
  ExpectStatus(ann.Submit(OnSite(TinyJob(), site.id())), grpc::StatusCode::RESOURCE_EXHAUSTED,
               "limits.max_queued_jobs_per_user (1) reached");
  // Another user's limits are their own
  ASSERT_TRUE(bob.Register(SiteRequest()).ok());
  ASSERT_TRUE(bob.Submit(InlineRequest(TinyJob())).ok());

  // An ended job frees its upload and its place in the queue
  ASSERT_TRUE(ann.CancelJob(queued.id()).ok());
  ASSERT_TRUE(ann.CancelJob(running.id()).ok());
  ann.WaitJob(running.id(), Ended);
  EXPECT_TRUE(ann.Submit(InlineRequest(TinyJob())).ok());
  // ... as a deleted site frees its own
  ASSERT_TRUE(ann.DeleteSite(site.id()).ok());
  EXPECT_TRUE(ann.Register(SiteRequest()).ok());
}

TEST_F(FenestradAuthTest, PythonClientWithTlsAndAToken) {
  if (Daemon::RunCli({"/usr/bin/python3", "-c", "import grpc, google.protobuf"}).code != 0) {
    GTEST_SKIP() << "/usr/bin/python3 has no grpc module (python3-grpcio)";
  }
  const std::string token_file = dir_ + "/ann.token";
  std::ofstream(token_file) << AddUser("ann") << "\n";
  auto d = StartTls();
  const std::vector<std::string> run = {"/usr/bin/python3",
                                        FENESTRA_SOURCE_DIR "/examples/python_client.py",
                                        "--server",
                                        d->address(),
                                        "--outdoor-paths",
                                        "40000",
                                        "--indoor-paths",
                                        "2000",
                                        "--evaluations",
                                        "3",
                                        FENESTRA_SOURCE_DIR
                                        "/examples/city_office/alpha_max_quick.json"};
  std::vector<std::string> args = run;
  args.insert(args.end(), {"--tls-ca", Certs().ca_cert, "--token-file", token_file});
  CliResult r = Daemon::RunCli(args);
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr("best design: alpha="));
  // Without the token
  args = run;
  args.insert(args.end(), {"--tls-ca", Certs().ca_cert});
  r = Daemon::RunCli(args);
  EXPECT_NE(r.code, 0);
  EXPECT_THAT(r.out + r.err, HasSubstr("fenestrad wants a token"));
}

}  // namespace
}  // namespace fenestra
