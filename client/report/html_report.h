#pragma once

// The report of a job result: one self-contained HTML page (inline SVG figures, an inline
// stylesheet with a print layout; no scripts, fonts or other resources) with the best
// design's metrics and constraints, the search, the design space, the floor plans with the
// sensors' metrics and sunlit hours, temporal maps of one sensor's illuminance, the direct
// sun and an operated blind, the blind in section, and the settings, timings and versions.
#include <string>
#include <string_view>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "fenestra/v1/job.pb.h"

namespace fenestra {

struct ReportOptions {
  // Names the result on the page and in errors: its file, or the job's id.
  std::string source;
  // The temporal map's sensor: a name, or an index from 0; empty = the lowest UDI.
  std::string sensor;
};

// The page. InvalidArgument naming the field when the result is inconsistent, or naming
// --sensor when there is no such sensor.
absl::StatusOr<std::string> RenderReport(const v1::JobResult& result, const ReportOptions& options);

// The page's one stylesheet, the text of its <style> element (a page that shows the report
// in a frame allows it by its hash).
std::string_view ReportStyleSheet();

// RenderReport written to `path` (atomically: nothing is left at `path` on failure).
absl::Status WriteReport(const v1::JobResult& result, const ReportOptions& options,
                         const std::string& path);

}  // namespace fenestra
