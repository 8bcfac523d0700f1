#include "tests/headless_chromium.h"

#include <fcntl.h>
#include <google/protobuf/util/json_util.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <thread>

#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"
#include "tests/child_process.h"

namespace fenestra {
namespace {

using google::protobuf::Struct;
using google::protobuf::Value;

constexpr auto kReplyTimeout = std::chrono::seconds(60);

Value String(const std::string& s) {
  Value v;
  v.set_string_value(s);
  return v;
}
Value Number(double x) {
  Value v;
  v.set_number_value(x);
  return v;
}
Value Bool(bool b) {
  Value v;
  v.set_bool_value(b);
  return v;
}

Struct Params(std::initializer_list<std::pair<std::string, Value>> fields) {
  Struct s;
  for (const auto& [name, value] : fields) (*s.mutable_fields())[name] = value;
  return s;
}

// fields[name] of a struct, or a null value.
const Value& Field(const Struct& s, const std::string& name) {
  static const Value* const kNull = new Value();
  const auto it = s.fields().find(name);
  return it == s.fields().end() ? *kNull : it->second;
}

std::string Text(const Value& v) {
  if (v.has_string_value()) return v.string_value();
  std::string json;
  (void)google::protobuf::util::MessageToJsonString(v, &json);
  return json;
}

}  // namespace

absl::StatusOr<std::unique_ptr<HeadlessChromium>> HeadlessChromium::Start(
    const std::string& executable, const std::string& profile_dir) {
  signal(SIGPIPE, SIG_IGN);  // a browser that died must not take the test with it
  int commands[2], replies[2];
  if (pipe2(commands, O_CLOEXEC) != 0 || pipe2(replies, O_CLOEXEC) != 0) {
    return absl::InternalError("pipe failed");
  }
  // The browser reads commands on fd 3 and writes replies on fd 4; the copies made here lie
  // above both, so that no redirect overwrites another's source
  const int in = fcntl(commands[0], F_DUPFD_CLOEXEC, 10),
            out = fcntl(replies[1], F_DUPFD_CLOEXEC, 10);
  const int opened = OpenForChild(profile_dir + ".log", /*append=*/false);
  const int log = fcntl(opened, F_DUPFD_CLOEXEC, 10);
  close(opened);
  const pid_t pid =
      Spawn({executable, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
             "--no-first-run", "--disable-background-networking", "--disable-component-update",
             "--disable-sync", "--hide-scrollbars", "--remote-debugging-pipe",
             "--user-data-dir=" + profile_dir, "about:blank"},
            {{in, 3}, {out, 4}, {log, STDOUT_FILENO}, {log, STDERR_FILENO}},
            /*die_with_parent=*/true, std::nullopt, /*close_from=*/5);
  for (const int fd : {in, out, log}) close(fd);
  close(commands[0]);
  close(replies[1]);
  std::unique_ptr<HeadlessChromium> browser(new HeadlessChromium(pid, commands[1], replies[0]));

  // A page of our own, attached in flat mode (its session id on every message)
  absl::StatusOr<Struct> target =
      browser->Call("Target.createTarget", Params({{"url", String("about:blank")}}), true);
  if (!target.ok()) return target.status();
  absl::StatusOr<Struct> attached = browser->Call(
      "Target.attachToTarget",
      Params({{"targetId", Field(*target, "targetId")}, {"flatten", Bool(true)}}), true);
  if (!attached.ok()) return attached.status();
  browser->session_ = Field(*attached, "sessionId").string_value();
  for (const char* domain : {"Page.enable", "Runtime.enable", "Log.enable", "Network.enable"}) {
    if (absl::StatusOr<Struct> r = browser->Call(domain, Struct()); !r.ok()) return r.status();
  }
  return browser;
}

HeadlessChromium::~HeadlessChromium() {
  (void)Call("Browser.close", Struct(), true);
  close(to_browser_);
  close(from_browser_);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (waitpid(pid_, nullptr, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() > deadline) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

absl::StatusOr<Struct> HeadlessChromium::Call(const std::string& method, const Struct& params,
                                              bool browser) {
  const int id = next_id_++;
  Struct message = Params({{"id", Number(id)}, {"method", String(method)}});
  *(*message.mutable_fields())["params"].mutable_struct_value() = params;
  if (!browser) (*message.mutable_fields())["sessionId"] = String(session_);
  std::string json;
  (void)google::protobuf::util::MessageToJsonString(message, &json);
  json.push_back('\0');
  for (size_t sent = 0; sent < json.size();) {
    const ssize_t n = write(to_browser_, json.data() + sent, json.size() - sent);
    if (n <= 0) return absl::UnavailableError(absl::StrCat(method, ": the browser is gone"));
    sent += static_cast<size_t>(n);
  }
  while (true) {
    absl::StatusOr<Struct> reply = Receive();
    if (!reply.ok())
      return absl::Status(reply.status().code(),
                          method + ": " + std::string(reply.status().message()));
    if (Field(*reply, "id").number_value() != id) {
      Record(*reply);
      continue;
    }
    if (reply->fields().contains("error")) {
      return absl::InternalError(absl::StrCat(method, ": ", Text(Field(*reply, "error"))));
    }
    return Field(*reply, "result").struct_value();
  }
}

absl::StatusOr<Struct> HeadlessChromium::Receive() {
  const auto deadline = std::chrono::steady_clock::now() + kReplyTimeout;
  size_t end;
  while ((end = buffer_.find('\0')) == std::string::npos) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    pollfd fd{from_browser_, POLLIN, 0};
    if (left.count() <= 0 || poll(&fd, 1, static_cast<int>(left.count())) <= 0) {
      return absl::DeadlineExceededError("no reply from the browser");
    }
    char chunk[65536];
    const ssize_t n = read(from_browser_, chunk, sizeof chunk);
    if (n <= 0) return absl::UnavailableError("the browser closed its pipe");
    buffer_.append(chunk, static_cast<size_t>(n));
  }
  Struct message;
  const auto parsed = google::protobuf::util::JsonStringToMessage(buffer_.substr(0, end), &message);
  buffer_.erase(0, end + 1);
  if (!parsed.ok()) return absl::InternalError("the browser sent malformed JSON");
  return message;
}

void HeadlessChromium::Record(const Struct& event) {
  const std::string method = Field(event, "method").string_value();
  const Struct& params = Field(event, "params").struct_value();
  if (method == "Runtime.consoleAPICalled") {
    const std::string type = Field(params, "type").string_value();
    if (type == "error" || type == "warning" || type == "assert") {
      std::string text;
      for (const Value& arg : Field(params, "args").list_value().values()) {
        text += Text(Field(arg.struct_value(), "value")) + " ";
      }
      problems_.push_back("console " + type + ": " + text);
    }
  } else if (method == "Runtime.exceptionThrown") {
    problems_.push_back("exception: " + Text(Field(params, "exceptionDetails")));
  } else if (method == "Log.entryAdded") {
    const Struct& entry = Field(params, "entry").struct_value();
    const std::string level = Field(entry, "level").string_value();
    if (level == "error" || level == "warning") {
      problems_.push_back("log " + level + ": " + Field(entry, "text").string_value());
    }
  } else if (method == "Network.requestWillBeSent") {
    requests_.push_back(Field(Field(params, "request").struct_value(), "url").string_value());
  }
  events_.push_back(method);
}

absl::Status HeadlessChromium::WaitForEvent(const std::string& method) {
  while (true) {
    for (auto it = events_.begin(); it != events_.end(); ++it) {
      if (*it == method) {
        events_.erase(events_.begin(), it + 1);
        return absl::OkStatus();
      }
    }
    absl::StatusOr<Struct> message = Receive();
    if (!message.ok()) return message.status();
    Record(*message);
  }
}

absl::Status HeadlessChromium::Load(const std::string& url, int width, int height) {
  absl::StatusOr<Struct> r =
      Call("Emulation.setDeviceMetricsOverride", Params({{"width", Number(width)},
                                                         {"height", Number(height)},
                                                         {"deviceScaleFactor", Number(1)},
                                                         {"mobile", Bool(false)}}));
  if (!r.ok()) return r.status();
  events_.clear();
  r = Call("Page.navigate", Params({{"url", String(url)}}));
  if (!r.ok()) return r.status();
  if (r->fields().contains("errorText")) {
    return absl::NotFoundError(absl::StrCat(url, ": ", Field(*r, "errorText").string_value()));
  }
  return WaitForEvent("Page.loadEventFired");
}

absl::StatusOr<Value> HeadlessChromium::Evaluate(const std::string& expression) {
  absl::StatusOr<Struct> r =
      Call("Runtime.evaluate",
           Params({{"expression", String(expression)}, {"returnByValue", Bool(true)}}));
  if (!r.ok()) return r.status();
  if (r->fields().contains("exceptionDetails")) {
    return absl::InvalidArgumentError(Text(Field(*r, "exceptionDetails")));
  }
  return Field(Field(*r, "result").struct_value(), "value");
}

absl::Status HeadlessChromium::SetInputFiles(const std::string& selector,
                                             const std::vector<std::string>& paths) {
  if (selector.find_first_of("'\\") != std::string::npos) {
    return absl::InvalidArgumentError("a selector without quotes or backslashes");
  }
  Struct query =
      Params({{"expression", String(absl::StrCat("document.querySelector('", selector, "')"))}});
  absl::StatusOr<Struct> found = Call("Runtime.evaluate", query);
  if (!found.ok()) return found.status();
  const Value& id = Field(Field(*found, "result").struct_value(), "objectId");
  if (id.string_value().empty()) return absl::NotFoundError(absl::StrCat("no element ", selector));
  Value files;
  for (const std::string& p : paths) *files.mutable_list_value()->add_values() = String(p);
  return Call("DOM.setFileInputFiles", Params({{"files", files}, {"objectId", id}})).status();
}

absl::Status HeadlessChromium::EmulateMedia(const std::string& media) {
  return Call("Emulation.setEmulatedMedia", Params({{"media", String(media)}})).status();
}

absl::StatusOr<std::string> HeadlessChromium::Screenshot() {
  absl::StatusOr<Struct> metrics = Call("Page.getLayoutMetrics", Struct());
  if (!metrics.ok()) return metrics.status();
  const Struct& size = Field(*metrics, "cssContentSize").struct_value();
  const Struct& view = Field(*metrics, "cssLayoutViewport").struct_value();
  absl::StatusOr<Struct> r =
      Call("Emulation.setDeviceMetricsOverride", Params({{"width", Field(view, "clientWidth")},
                                                         {"height", Field(size, "height")},
                                                         {"deviceScaleFactor", Number(1)},
                                                         {"mobile", Bool(false)}}));
  if (!r.ok()) return r.status();
  r = Call("Page.captureScreenshot", Params({{"format", String("png")}}));
  if (!r.ok()) return r.status();
  std::string png;
  if (!absl::Base64Unescape(Field(*r, "data").string_value(), &png)) {
    return absl::InternalError("the screenshot is not base64");
  }
  return png;
}

absl::StatusOr<std::string> HeadlessChromium::PrintToPdf() {
  absl::StatusOr<Struct> r = Call("Page.printToPDF", Params({{"paperWidth", Number(8.27)},
                                                             {"paperHeight", Number(11.69)},
                                                             {"printBackground", Bool(true)}}));
  if (!r.ok()) return r.status();
  std::string pdf;
  if (!absl::Base64Unescape(Field(*r, "data").string_value(), &pdf)) {
    return absl::InternalError("the PDF is not base64");
  }
  return pdf;
}

}  // namespace fenestra
