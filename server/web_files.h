#pragma once

// The dashboard's static files (server/web/), built into the daemon by server/web/embed.cmake
// so that it serves them without reading its disk.
#include <span>
#include <string_view>

namespace fenestra {

struct WebFile {
  std::string_view path;     // the URL path, e.g. "/app.js"
  const char* content_type;  // with its charset
  std::string_view content;
};

std::span<const WebFile> WebFiles();

}  // namespace fenestra
