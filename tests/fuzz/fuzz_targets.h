// The parsers that read outside input, each behind one function taking raw bytes: the
// libFuzzer targets (fuzz_main.cpp) and the regression test (fuzz_regression_test.cpp)
// call the same functions. Each returns the parser's status; an input that breaks an
// invariant of an accepted result (a non-finite number, a limit exceeded after the check)
// aborts with a message, so the fuzzer reports it as a crash.
#pragma once

#include <cstddef>
#include <span>
#include <string_view>

#include "absl/status/status.h"

namespace fenestra::fuzz {

// A scene file as `fenestra scene check` reads it: JSON of fenestra.v1.Scene, built into
// the core scene and checked as a room (LoadValidScene). Relative OBJ paths resolve next to
// the examples' scenes.
absl::Status SceneJson(std::string_view bytes);

// A job file as `fenestra optimize --local` reads it: JSON of fenestra.v1.Job, validated
// with defaults filled in (ReadJobFile + PrepareJob) next to the city office example.
absl::Status JobJson(std::string_view bytes);

// An EPW weather file (ParseEpw, strict and with missing values read as 0), and the sky
// matrix of what parses (BuildSkyMatrix).
absl::Status Epw(std::string_view bytes);

// An OBJ mesh file (ReadObj).
absl::Status Obj(std::string_view bytes);

// A Radiance matrix file or whitespace-separated table (ReadRadianceMatrix).
absl::Status RadianceMatrix(std::string_view bytes);

// An outdoor-matrix cache file (DecodeOutdoorMatrix): the bytes as given, then with the
// header's size and checksum made to match, so the payload's parsing is reached too.
absl::Status OutdoorCache(std::string_view bytes);

// A request to fenestrad: the first byte picks SubmitJobRequest (even) or
// RegisterSiteRequest (odd), the rest is the message in protobuf's binary form, checked by
// the doors of JobService.Submit and SiteService.Register (CheckJobRequest,
// CheckSiteRequest) under the default configuration.
absl::Status DaemonRequest(std::string_view bytes);

// Radiance scene descriptions (ImportRadiance): the bytes before the first NUL are a .rad
// text, those after it a points file (none without a NUL). An accepted scene is written back
// (ExportRadiance) and must read back as the same scene.
absl::Status RadImport(std::string_view bytes);

// A Honeybee model (HBJSON, ImportHoneybee with the default options), refused only as bad
// input (InvalidArgument). An accepted model's scene has finite coordinates and is built
// (BuildScene), which may refuse it only as bad input too.
absl::Status HbjsonImport(std::string_view bytes);

// The body of a dashboard submission (POST /api/v1/jobs: ParseDashboardSubmission), then the
// door of JobService.Submit on the request it stands for (CheckJobRequest).
absl::Status DashboardSubmission(std::string_view bytes);

struct Target {
  const char* name;  // folder under tests/fuzz/corpus and tests/fuzz/regressions
  absl::Status (*run)(std::string_view bytes);
};

// Every target, by name.
std::span<const Target> Targets();

// Silences protobuf's own logging (its parsers log malformed input to stderr).
void QuietLibraries();

}  // namespace fenestra::fuzz
