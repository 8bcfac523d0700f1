#pragma once

// Headless Chromium (Debian's chromium package) for tests of HTML pages, driven through its
// DevTools protocol over a pipe (--remote-debugging-pipe: commands on the browser's fd 3,
// replies and events on its fd 4, each a JSON message ended by a NUL byte). It loads a page,
// records the console's errors and warnings, uncaught exceptions and every request the
// page makes, evaluates expressions in it, prints it and takes screenshots.
#include <google/protobuf/struct.pb.h>
#include <sys/types.h>

#include <memory>
#include <string>
#include <vector>

#include "absl/status/statusor.h"

namespace fenestra {

class HeadlessChromium {
 public:
  // Starts `executable` with a fresh profile in `profile_dir` (created; removed by the
  // caller), no network services, no sandbox (tests run as root), and opens a page.
  static absl::StatusOr<std::unique_ptr<HeadlessChromium>> Start(const std::string& executable,
                                                                 const std::string& profile_dir);
  // Closes the browser (killed if it does not end within a few seconds).
  ~HeadlessChromium();
  HeadlessChromium(const HeadlessChromium&) = delete;
  HeadlessChromium& operator=(const HeadlessChromium&) = delete;

  // Sets the page's viewport to `width` x `height` CSS px, loads `url` and waits for its
  // load event.
  absl::Status Load(const std::string& url, int width, int height);
  // The value of a JavaScript expression evaluated in the page (returned by value).
  absl::StatusOr<google::protobuf::Value> Evaluate(const std::string& expression);
  // Chooses `paths` (files on this machine) in the file input `selector` names, as a user
  // would in the browser's file dialog (its change event fires).
  absl::Status SetInputFiles(const std::string& selector, const std::vector<std::string>& paths);
  // Media the page's CSS sees: "print" or "screen".
  absl::Status EmulateMedia(const std::string& media);
  // A PNG of the whole page (the viewport grown to the page's height).
  absl::StatusOr<std::string> Screenshot();
  // The page printed to PDF (A4), its bytes.
  absl::StatusOr<std::string> PrintToPdf();

  // What the page reported: console errors and warnings, uncaught exceptions, log entries
  // of level error or warning (failed loads, blocked requests), as "kind: text".
  const std::vector<std::string>& problems() const { return problems_; }
  // Every URL the page requested, the page itself included.
  const std::vector<std::string>& requests() const { return requests_; }

 private:
  HeadlessChromium(pid_t pid, int to_browser, int from_browser)
      : pid_(pid), to_browser_(to_browser), from_browser_(from_browser) {}

  // Sends a command (to the page's session unless `browser`) and waits for its reply's
  // "result"; events that arrive meanwhile are recorded.
  absl::StatusOr<google::protobuf::Struct> Call(const std::string& method,
                                                const google::protobuf::Struct& params,
                                                bool browser = false);
  // The next message, within the deadline.
  absl::StatusOr<google::protobuf::Struct> Receive();
  // Waits for an event of the page's session.
  absl::Status WaitForEvent(const std::string& method);
  void Record(const google::protobuf::Struct& event);

  pid_t pid_;
  int to_browser_, from_browser_;
  int next_id_ = 1;
  std::string session_;
  std::string buffer_;
  std::vector<std::string> problems_, requests_, events_;
};

}  // namespace fenestra
