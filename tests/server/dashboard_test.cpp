// The web dashboard (fenestrad --http; server/http_gateway.h, server/web/) end to end: a real
// daemon on loopback with token auth and users made by `fenestrad user`, driven by headless
// Chromium (Debian's chromium, tests/headless_chromium.h) as its users would, and by an HTTP
// client sending what a browser would not.
#include <arpa/inet.h>
#include <httplib.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <map>

#include "absl/strings/match.h"
#include "absl/strings/str_split.h"
#include "tests/certificates.h"
#include "tests/headless_chromium.h"
#include "tests/server/fenestrad_harness.h"

namespace fenestra {
namespace {

using namespace testing_fenestrad;
using ::testing::HasSubstr;

class DashboardTest : public FenestradTest {
 protected:
  // A daemon with token auth and the dashboard on a free loopback port.
  std::unique_ptr<Daemon> StartDashboard(std::vector<std::string> flags = {}) {
    flags.insert(flags.end(), {"--http", "127.0.0.1:0", "--workers", "1"});
    auto daemon = std::make_unique<Daemon>(dir_ + "/data", std::move(flags));
    daemon->Start();
    // The port file: the gRPC port, then the dashboard's
    std::ifstream ports(dir_ + "/data.port");
    int grpc_port = 0;
    ports >> grpc_port >> http_port_;
    EXPECT_GT(http_port_, 0) << daemon->Log();
    return daemon;
  }
  std::string Origin() const { return "http://127.0.0.1:" + std::to_string(http_port_); }
  httplib::Client Client() const {
    httplib::Client client("127.0.0.1", http_port_);
    client.set_read_timeout(30);
    return client;
  }

  // The tiny job as the dashboard's job file (scene and weather chosen beside it) and
  // request, running for `evaluations` evaluations.
  std::string WriteDashboardJob(const std::string& name, int evaluations) const {
    v1::Job job = TinyJob(evaluations);
    job.clear_scene_file();
    job.set_name(name);
    return WriteJob(name, job);
  }

  int http_port_ = 0;
};

// Polls `expression` in the page until it is true, or 60 s.
void WaitFor(HeadlessChromium& page, const std::string& expression) {
  const auto deadline = Clock::now() + std::chrono::seconds(60);
  while (Clock::now() < deadline) {
    absl::StatusOr<google::protobuf::Value> v = page.Evaluate(expression);
    if (v.ok() && v->bool_value()) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  ADD_FAILURE() << "never true: " << expression;
}

std::string Text(HeadlessChromium& page, const std::string& expression) {
  absl::StatusOr<google::protobuf::Value> v = page.Evaluate(expression);
  EXPECT_TRUE(v.ok()) << v.status();
  return v.ok() ? v->string_value() : "";
}

void SignIn(HeadlessChromium& page, const std::string& token) {
  ASSERT_TRUE(page.Evaluate("document.querySelector('#token').value = '" + token +
                            "'; document.querySelector('#sign-in-button').click(); true")
                  .ok());
}

// The problems Chromium reported other than the failed loads of the answers the test asked
// for on purpose (a wrong token's 401, another user's job's 404): Chromium logs each non-2xx
// answer as a network error the page cannot silence.
std::vector<std::string> UnexpectedProblems(const HeadlessChromium& page) {
  std::vector<std::string> out;
  for (const std::string& p : page.problems()) {
    const bool expected =
        p.find("Failed to load resource") != std::string::npos &&
        (p.find("401") != std::string::npos || p.find("404") != std::string::npos);
    if (!expected) out.push_back(p);
  }
  return out;
}

TEST_F(DashboardTest, UsersSignInSubmitWatchOpenTheReportAndCancelInABrowser) {
  const std::string ann = AddUser("ann"), bob = AddUser("bob");
  auto d = StartDashboard();
  const std::string profile = dir_ + "/chromium";
  absl::StatusOr<std::unique_ptr<HeadlessChromium>> browser =
      HeadlessChromium::Start(CHROMIUM_EXECUTABLE, profile);
  ASSERT_TRUE(browser.ok()) << browser.status();
  HeadlessChromium& page = **browser;
  ASSERT_TRUE(page.Load(Origin() + "/", 1280, 800).ok());

  // A wrong token is refused and nothing of the list shows
  SignIn(page, std::string(64, '0'));
  WaitFor(page, "document.querySelector('#sign-in-error').textContent.length > 0");
  EXPECT_EQ(Text(page, "document.querySelector('#user').textContent"), "");

  // Ann signs in and submits the quick job by choosing its files
  SignIn(page, ann);
  WaitFor(page, "document.querySelector('#user').textContent.includes('ann')");
  ASSERT_TRUE(page.Evaluate("location.hash = '#/submit'; true").ok());
  WaitFor(page, "!document.querySelector('#submit-view').hidden");
  ASSERT_TRUE(page.SetInputFiles("#job-file", {WriteDashboardJob("dashboard quick", 120)}).ok());
  ASSERT_TRUE(
      page.SetInputFiles("#scene-file", {FENESTRA_SOURCE_DIR "/examples/city_office/scene.json"})
          .ok());
  ASSERT_TRUE(
      page.SetInputFiles("#weather-file",
                         {FENESTRA_SOURCE_DIR "/examples/weather/URY_Montevideo.865800_IWEC.epw"})
          .ok());
  ASSERT_TRUE(page.Evaluate("document.querySelector('#submit').click(); true").ok());
  WaitFor(page, "location.hash.startsWith('#/jobs/job-')");
  const std::string id = Text(page, "location.hash.substring(7)");
  ASSERT_FALSE(id.empty());

  // Its progress moves while it runs, and its report shows when it ends
  WaitFor(page, "document.querySelector('#job-progress').value > 0");
  const double first =
      page.Evaluate("document.querySelector('#job-progress').value")->number_value();
  WaitFor(page, "document.querySelector('#job-progress').value > " + std::to_string(first));
  WaitFor(page,
          "(document.querySelector('#job-report iframe') || {}).srcdoc?.includes('Fenestra "
          "report') === true");
  EXPECT_THAT(Text(page, "document.querySelector('#job-plot').innerHTML"), HasSubstr("<svg"));

  // A second job, long, cancelled from the list
  d->set_token(ann);
  v1::JobInfo long_job;
  ASSERT_TRUE(d->jobs().Submit(d->Context().get(), InlineRequest(LongJob()), &long_job).ok());
  ASSERT_TRUE(page.Evaluate("location.hash = '#/'; true").ok());
  const std::string row = "document.querySelector('tr[data-job-id=\"" + long_job.id() + "\"]')";
  WaitFor(page, row + " !== null && " + row + ".querySelector('button.cancel') !== null");
  const std::string finished = "document.querySelector('tr[data-job-id=\"" + id + "\"] .state')";
  WaitFor(page, finished + ".textContent.includes('succeeded')");
  if (const char* shot = std::getenv("FENESTRA_DASHBOARD_SCREENSHOT")) {
    WaitFor(page, row + ".querySelector('progress').value > 1");
    absl::StatusOr<std::string> png = page.Screenshot();
    ASSERT_TRUE(png.ok()) << png.status();
    std::ofstream(shot, std::ios::binary) << *png;
  }
  ASSERT_TRUE(page.Evaluate(row + ".querySelector('button.cancel').click(); true").ok());
  WaitFor(page, row + ".querySelector('.state').textContent.includes('cancel')");
  WaitJob(*d, long_job.id(), Ended);

  // Bob sees neither of ann's jobs, in the list or by the URL
  ASSERT_TRUE(page.Evaluate("document.querySelector('#sign-out').click(); true").ok());
  SignIn(page, bob);
  WaitFor(page, "document.querySelector('#user').textContent.includes('bob')");
  WaitFor(page,
          "document.querySelector('#jobs-empty') !== null && "
          "!document.querySelector('#jobs-empty').hidden");
  EXPECT_EQ(page.Evaluate("document.querySelectorAll('tr[data-job-id]').length")->number_value(),
            0);
  ASSERT_TRUE(page.Evaluate("location.hash = '#/jobs/" + id + "'; true").ok());
  WaitFor(page, "document.querySelector('#job-error').textContent.includes('No such job')");

  // No console errors; every request to the daemon's own origin
  EXPECT_THAT(UnexpectedProblems(page), testing::IsEmpty());
  for (const std::string& url : page.requests()) {
    const bool own = url.rfind(Origin() + "/", 0) == 0 || url.rfind("data:", 0) == 0 ||
                     url.rfind("about:", 0) == 0 || url.rfind("blob:" + Origin(), 0) == 0;
    EXPECT_TRUE(own) << url;
  }
  browser->reset();
  fs::remove_all(profile);
}

// Sends `raw` on a fresh connection; what came back, up to the connection's end.
std::string RawRequest(int port, const std::string& raw) {
  const int s = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (connect(s, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0) return "";
  timeval timeout{10, 0};
  setsockopt(s, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  (void)send(s, raw.data(), raw.size(), MSG_NOSIGNAL);
  shutdown(s, SHUT_WR);
  std::string answer;
  char buffer[4096];
  for (ssize_t n; (n = recv(s, buffer, sizeof buffer, 0)) > 0;) answer.append(buffer, n);
  close(s);
  return answer;
}

TEST_F(DashboardTest, HostileRequestsAreRefusedWith4xxAndTheDaemonServesOn) {
  const std::string ann = AddUser("ann");
  auto d = StartDashboard({"--max-message-bytes", "1000000"});
  httplib::Client client = Client();
  const httplib::Headers auth = {{"Authorization", "Bearer " + ann}};
  const auto status = [](const httplib::Result& r) { return r ? r->status : -1; };

  // No token, a wrong one, two of them
  EXPECT_EQ(status(client.Get("/api/v1/jobs")), 401);
  EXPECT_EQ(status(client.Get("/api/v1/jobs", {{"Authorization", "Bearer nope"}})), 401);
  EXPECT_EQ(status(client.Get("/api/v1/jobs", {{"Authorization", "Bearer " + ann},
                                               {"Authorization", "Bearer " + ann}})),
            401);
  // Bodies too large, not JSON, JSON of the wrong shape, unknown fields
  const std::string big(2'000'000, 'x');
  EXPECT_EQ(status(client.Post("/api/v1/jobs", auth, big, "application/json")), 413);
  httplib::Result bad = client.Post("/api/v1/jobs", auth, "{\"job\": ", "application/json");
  ASSERT_TRUE(bad);
  EXPECT_EQ(bad->status, 400);
  EXPECT_THAT(bad->body, HasSubstr("\"code\":\"INVALID_ARGUMENT\""));
  EXPECT_EQ(status(client.Post("/api/v1/jobs", auth, "[1, 2]", "application/json")), 400);
  httplib::Result unknown =
      client.Post("/api/v1/jobs", auth, R"({"job": {"noSuchField": 1}})", "application/json");
  ASSERT_TRUE(unknown);
  EXPECT_EQ(unknown->status, 400);
  EXPECT_THAT(unknown->body, HasSubstr("\"field\":\"job\""));
  httplib::Result weather = client.Post(
      "/api/v1/jobs", auth, R"({"job": {}, "weatherEpw": "bm90IGFuIEVQVw=="})", "application/json");
  ASSERT_TRUE(weather);
  EXPECT_EQ(weather->status, 400);
  EXPECT_THAT(weather->body, HasSubstr("\"field\":\"weather\""));
  // Paths that climb out, or name what is not there
  for (const std::string path :
       {"/../../etc/passwd", "/%2e%2e/%2e%2e/etc/passwd", "/api/v1/jobs/..%2f..%2fetc%2fpasswd",
        "/api/v1/jobs/job-1/../../../etc/passwd", "/web/index.html", "/app.js/../../server"}) {
    httplib::Result r = client.Get(path, auth);
    ASSERT_TRUE(r) << path;
    EXPECT_GE(r->status, 400) << path;
    EXPECT_LT(r->status, 500) << path;
    EXPECT_THAT(r->body, testing::Not(HasSubstr("root:"))) << path;
  }
  // Another origin's page, and a header that tries to end its line early
  EXPECT_EQ(
      status(client.Post("/api/v1/jobs",
                         {{"Authorization", "Bearer " + ann}, {"Origin", "https://evil.example"}},
                         "{}", "application/json")),
      403);
  const std::string injected =
      RawRequest(http_port_,
                 "GET /api/v1/jobs/job-1%0d%0aforged-log-line HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                 "Authorization: Bearer " +
                     ann + "\rX-Injected: yes\r\nConnection: close\r\n\r\n");
  // httplib drops a request whose header line holds a bare CR: no answer, or a 4xx
  EXPECT_TRUE(injected.empty() || injected.rfind("HTTP/1.1 4", 0) == 0) << injected;
  const std::string garbage = RawRequest(
      http_port_, std::string("\x16\x03\x01\x02\x00", 5) + std::string(20000, 'A') + "\r\n\r\n");
  EXPECT_EQ(garbage.find("HTTP/1.1 2"), std::string::npos);
  // The log names what clients sent only escaped
  for (const absl::string_view line : absl::StrSplit(d->Log(), '\n')) {
    EXPECT_FALSE(absl::StartsWith(line, "forged-log-line")) << line;
  }
  EXPECT_EQ(d->Log().find("X-Injected"), std::string::npos);

  // And it serves on: the page, and the API for a token
  httplib::Result me = client.Get("/api/v1/me", auth);
  ASSERT_TRUE(me);
  EXPECT_EQ(me->status, 200);
  EXPECT_THAT(me->body, HasSubstr(R"("name":"ann")"));
  EXPECT_THAT(me->body, HasSubstr(R"("admin":false)"));
  httplib::Result index = client.Get("/");
  ASSERT_TRUE(index);
  EXPECT_EQ(index->status, 200);
  EXPECT_THAT(index->get_header_value("Content-Security-Policy"),
              HasSubstr("default-src 'none'; script-src 'self'"));
  EXPECT_EQ(index->get_header_value("Access-Control-Allow-Origin"), "");

  // Answers travel uncompressed whatever the client accepts, as a browser asks
  client.set_decompress(false);
  httplib::Headers accepting = auth;
  accepting.emplace("Accept-Encoding", "gzip, deflate, br");
  for (const char* path : {"/api/v1/me", "/", "/api/v1/nothing-here"}) {
    httplib::Result raw = client.Get(path, accepting);
    ASSERT_TRUE(raw) << path;
    EXPECT_EQ(raw->get_header_value("Content-Encoding"), "") << path;
    EXPECT_EQ(raw->get_header_value_count("Content-Type"), 1u) << path;
    EXPECT_EQ(raw->get_header_value("Content-Length"), std::to_string(raw->body.size())) << path;
  }
  EXPECT_THAT(client.Get("/api/v1/me", accepting)->body, HasSubstr(R"("name":"ann")"));
  EXPECT_THAT(client.Get("/api/v1/nothing-here", accepting)->body,
              HasSubstr("no such page or API route"));
}

TEST_F(DashboardTest, RequestsBeyondTheRateAreRefusedWith429) {
  const std::string ann = AddUser("ann");
  auto d = StartDashboard({"--max-http-requests-per-minute", "20"});
  httplib::Client client = Client();
  std::map<int, int> answers;  // status -> count
  for (int i = 0; i < 40; ++i) {
    httplib::Result r = client.Get("/api/v1/me", {{"Authorization", "Bearer " + ann}});
    ASSERT_TRUE(r);
    ++answers[r->status];
  }
  // The budget refills by one request every 3 s: one more may pass while the loop runs
  EXPECT_GE(answers[200], 20);
  EXPECT_LE(answers[200], 21);
  EXPECT_EQ(answers[200] + answers[429], 40);
}

TEST_F(DashboardTest, OwnersApplyAsOnTheGrpcPortAndEndedJobsCanBeDeleted) {
  const std::string ann = AddUser("ann"), bob = AddUser("bob"), root = AddUser("root", true);
  auto d = StartDashboard();
  d->set_token(ann);
  v1::JobInfo job;
  ASSERT_TRUE(d->jobs().Submit(d->Context().get(), InlineRequest(TinyJob()), &job).ok());
  httplib::Client client = Client();
  const auto as = [](const std::string& token) {
    return httplib::Headers{{"Authorization", "Bearer " + token}};
  };
  const std::string path = "/api/v1/jobs/" + job.id();
  EXPECT_EQ(client.Get(path, as(bob))->status, 404);
  EXPECT_EQ(client.Get(path + "/report", as(bob))->status, 404);
  EXPECT_EQ(client.Post(path + "/cancel", as(bob), "", "application/json")->status, 404);
  EXPECT_EQ(client.Delete(path, as(bob))->status, 404);
  EXPECT_EQ(client.Get("/api/v1/jobs", as(bob))->body, "{}");
  EXPECT_THAT(client.Get("/api/v1/jobs", as(root))->body, HasSubstr("\"owner\":\"ann\""));
  // Not deleted while it runs; once it has ended, gone for good
  WaitJob(*d, job.id(), Ended);
  httplib::Result report = client.Get(path + "/report", as(ann));
  ASSERT_TRUE(report);
  EXPECT_EQ(report->status, 200);
  EXPECT_THAT(report->body, HasSubstr("Fenestra report"));
  EXPECT_EQ(client.Delete(path, as(ann))->status, 200);
  EXPECT_EQ(client.Get(path, as(ann))->status, 404);
  v1::GetJobRequest get;
  get.set_id(job.id());
  v1::JobInfo gone;
  EXPECT_EQ(d->jobs().Get(d->Context().get(), get, &gone).error_code(),
            grpc::StatusCode::NOT_FOUND);
  // A running job is refused with 409
  v1::JobInfo running;
  ASSERT_TRUE(d->jobs().Submit(d->Context().get(), InlineRequest(LongJob()), &running).ok());
  EXPECT_EQ(client.Delete("/api/v1/jobs/" + running.id(), as(ann))->status, 409);
  EXPECT_EQ(
      client.Post("/api/v1/jobs/" + running.id() + "/cancel", as(ann), "", "application/json")
          ->status,
      200);
  WaitJob(*d, running.id(), Ended);
}

TEST_F(DashboardTest, HttpsWithTheDaemonsCertificate) {
  const std::string ann = AddUser("ann");
  grpc::SslCredentialsOptions trust;
  trust.pem_root_certs = ReadFile(Certs().ca_cert);
  auto d = std::make_unique<Daemon>(
      dir_ + "/data",
      std::vector<std::string>{"--http", "127.0.0.1:0", "--tls-cert", Certs().server_cert,
                               "--tls-key", Certs().server_key},
      grpc::SslCredentials(trust));
  d->Start();
  std::ifstream ports(dir_ + "/data.port");
  int grpc_port = 0;
  ports >> grpc_port >> http_port_;
  httplib::SSLClient tls("127.0.0.1", http_port_);
  tls.set_ca_cert_path(Certs().ca_cert.c_str());
  tls.enable_server_certificate_verification(true);
  httplib::Result me = tls.Get("/api/v1/me", {{"Authorization", "Bearer " + ann}});
  ASSERT_TRUE(me) << httplib::to_string(me.error());
  EXPECT_EQ(me->status, 200);
  // Plain HTTP to the TLS port gets no answer
  httplib::Client plain("127.0.0.1", http_port_);
  plain.set_read_timeout(5);
  httplib::Result clear = plain.Get("/api/v1/me", {{"Authorization", "Bearer " + ann}});
  EXPECT_TRUE(!clear || clear->status >= 400);
}

}  // namespace
}  // namespace fenestra
