// Writes the seeds that are binary files made by Fenestra's own writers: outdoor-matrix
// cache files (EncodeOutdoorMatrix) and fenestrad requests built as `fenestra job submit` and
// `fenestra site add --job` build them (the weather cut to the corpus's EPW excerpt).
// Usage: make_fuzz_seeds CORPUS_DIR   (tests/fuzz/corpus)
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "client/cli_util.h"
#include "client/job_request.h"
#include "core/geometry/rad_import.h"
#include "server/outdoor_cache.h"

namespace fenestra {
namespace {

namespace fs = std::filesystem;

void WriteSeed(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
  std::printf("%s: %zu bytes\n", path.string().c_str(), bytes.size());
}

OutdoorMatrix ExampleMatrix(int rows, int cols, bool with_errors) {
  OutdoorMatrix m;
  m.coefficients = Matrix(rows, cols);
  for (Eigen::Index i = 0; i < m.coefficients.size(); ++i) {
    m.coefficients.data()[i] = 0.5 + 0.5 * std::sin(0.37 * static_cast<double>(i));
  }
  if (with_errors) m.standard_error = 0.01 * m.coefficients;
  m.batches = {0.9 * m.coefficients, 1.1 * m.coefficients};
  m.basis_cells = 288;
  m.parts = {1, 1};
  m.paths = 576000;
  m.bounces = 10;
  m.seed = 1;
  m.wall_seconds = 1.25;
  m.backend = "cpu";
  m.key = "c0ffee";
  return m;
}

// A small room read from Radiance, given a blind, as ExportRadiance writes it, then a NUL and
// its points file (fuzz_targets.h).
bool WriteRadSeed(const fs::path& path) {
  const std::string room =
      "void plastic wall 0 0 5 0.6 0.6 0.6 0 0\n"
      "void glass pane 0 0 3 0.9 0.9 0.9\n"
      "wall polygon floor 0 0 12 0 0 0 3 0 0 3 3 0 0 3 0\n"
      "wall polygon ceiling 0 0 12 0 0 2.5 0 3 2.5 3 3 2.5 3 0 2.5\n"
      "wall polygon north 0 0 12 0 3 0 3 3 0 3 3 2.5 0 3 2.5\n"
      "wall polygon west 0 0 12 0 0 0 0 3 0 0 3 2.5 0 0 2.5\n"
      "wall polygon east 0 0 12 3 0 0 3 0 2.5 3 3 2.5 3 3 0\n"
      "wall polygon south 0 0 30 0 0 0 3 0 0 3 0 2.5 0 0 2.5 0 0 0\n"
      "  1 0 1 1 0 1.6 2 0 1.6 2 0 1 1 0 1\n"
      "pane polygon window 0 0 12 1 0 1 2 0 1 2 0 1.6 1 0 1.6\n";
  absl::StatusOr<v1::Scene> scene =
      ImportRadiance({{"room.rad", room}}, {"room.pts", "1.5 1.5 0.8 0 0 1\n"});
  if (!scene.ok() || scene->windows_size() != 1) {
    std::fprintf(stderr, "the seed room does not import: %s\n", scene.status().ToString().c_str());
    return false;
  }
  v1::VenetianBlind* blind = scene->mutable_windows(0)->mutable_blind();
  blind->set_material("wall");
  const auto set = [](v1::Parameter* p, double value, double min, double max) {
    p->set_value(value);
    p->set_min(min);
    p->set_max(max);
  };
  set(blind->mutable_tilt_rad(), 0.4, 0, 1.5);
  set(blind->mutable_slat_width_m(), 0.1, 0.05, 0.1);
  set(blind->mutable_slat_spacing_m(), 0.1, 0, 0.1);
  set(blind->mutable_slat_thickness_m(), 0.005, 0.002, 0.01);
  std::string points;
  absl::StatusOr<std::string> rad = ExportRadiance(*scene, &points);
  if (!rad.ok()) {
    std::fprintf(stderr, "the seed room does not export: %s\n", rad.status().ToString().c_str());
    return false;
  }
  WriteSeed(path, *rad + '\0' + points);
  return true;
}

int Main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_fuzz_seeds CORPUS_DIR\n");
    return 2;
  }
  const fs::path corpus = argv[1];
  const fs::path examples = fs::path(FENESTRA_SOURCE_DIR) / "examples/city_office";

  WriteSeed(corpus / "outdoor_cache/small.omx", EncodeOutdoorMatrix(ExampleMatrix(2, 3, false)));
  WriteSeed(corpus / "outdoor_cache/four_cells.omx",
            EncodeOutdoorMatrix(ExampleMatrix(4, 146, true)));

  const absl::StatusOr<std::string> weather = ReadFileBytes((corpus / "epw/two_days.epw").string());
  if (!weather.ok()) {
    std::fprintf(stderr, "%s\n", weather.status().ToString().c_str());
    return 1;
  }
  for (const char* job : {"alpha_max_quick", "four_variables"}) {
    absl::StatusOr<v1::SubmitJobRequest> request =
        SubmitRequestFromJobFile((examples / (std::string(job) + ".json")).string());
    if (!request.ok()) {
      std::fprintf(stderr, "%s\n", request.status().ToString().c_str());
      return 1;
    }
    request->set_weather_epw(*weather);
    // The first byte picks the message (fuzz_targets.h): even = SubmitJobRequest
    WriteSeed(corpus / "daemon_request" / (std::string("submit_") + job),
              '\0' + request->SerializeAsString());
    if (std::string(job) == "alpha_max_quick") {
      v1::RegisterSiteRequest site;
      *site.mutable_scene() = request->job().scene();
      *site.mutable_sampling() = request->job().sampling();
      site.set_weather_epw(*weather);
      site.set_weather_name("two_days.epw");
      site.set_name("city office");
      WriteSeed(corpus / "daemon_request/register_city_office", '\1' + site.SerializeAsString());
      v1::SubmitJobRequest with_path = *request;
      with_path.mutable_job()->set_scene_file("scene.json");
      WriteSeed(corpus / "daemon_request/bad_submit_scene_file",
                '\0' + with_path.SerializeAsString());
    }
  }
  if (!WriteRadSeed(corpus / "rad_import/export_room_with_blind")) return 1;
  return 0;
}

}  // namespace
}  // namespace fenestra

int main(int argc, char** argv) { return fenestra::Main(argc, argv); }
