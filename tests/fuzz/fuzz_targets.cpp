#include "tests/fuzz/fuzz_targets.h"

#include <google/protobuf/stubs/logging.h>
#include <google/protobuf/util/message_differencer.h>
#include <stdlib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/common/radiance_matrix.h"
#include "core/geometry/hbjson_import.h"
#include "core/geometry/obj_io.h"
#include "core/geometry/rad_import.h"
#include "core/geometry/scene.h"
#include "core/optimize/job.h"
#include "core/sky/epw.h"
#include "core/sky/sky_matrix.h"
#include "core/trace/room_check.h"
#include "fenestra/v1/service.pb.h"
#include "server/checksum.h"
#include "server/config.h"
#include "server/http_gateway.h"
#include "server/limits.h"
#include "server/outdoor_cache.h"

namespace fenestra::fuzz {
namespace {

namespace fs = std::filesystem;

// Stops the program when an accepted input breaks an invariant of its result.
void Require(bool condition, const char* what) {
  if (condition) return;
  std::fprintf(stderr, "fuzz invariant broken: %s\n", what);
  std::abort();
}

bool AllFinite(const std::vector<Vec3d>& points) {
  for (const Vec3d& p : points) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return false;
  }
  return true;
}

// A private temporary folder laid out like the repository's examples (city_office/,
// lightwell/, weather/, the OBJ seeds next to the scenes), where inputs that are read from
// files are written, so relative paths inside them resolve as they do for real files.
class Workspace {
 public:
  Workspace() {
    std::string pattern = (fs::temp_directory_path() / "fenestra-fuzz-XXXXXX").string();
    Require(mkdtemp(pattern.data()) != nullptr, "cannot create the fuzz workspace");
    dir_ = pattern;
    const fs::path source(FENESTRA_SOURCE_DIR);
    for (const char* sub : {"city_office", "lightwell", "weather"}) {
      fs::create_directories(dir_ / sub);
    }
    fs::create_symlink(source / "examples/city_office/scene.json", dir_ / "city_office/scene.json");
    fs::create_symlink(source / "examples/lightwell/scene.json", dir_ / "lightwell/scene.json");
    fs::create_symlink(source / "examples/weather/URY_Montevideo.865800_IWEC.epw",
                       dir_ / "weather/URY_Montevideo.865800_IWEC.epw");
    std::error_code error;
    for (const auto& obj : fs::directory_iterator(source / "tests/fuzz/corpus/obj", error)) {
      fs::create_symlink(obj.path(), dir_ / "city_office" / obj.path().filename());
    }
  }
  ~Workspace() {
    std::error_code error;
    fs::remove_all(dir_, error);
  }

  // Writes `bytes` to `relative` in the workspace; returns its path.
  std::string Write(const char* relative, std::string_view bytes) const {
    const std::string path = (dir_ / relative).string();
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    out.close();
    Require(static_cast<bool>(out), "cannot write to the fuzz workspace");
    return path;
  }

  std::string Path(const char* relative) const { return (dir_ / relative).string(); }

 private:
  fs::path dir_;
};

const Workspace& TheWorkspace() {
  static const Workspace workspace;
  return workspace;
}

// JobService.Submit's checks before anything is stored (CheckJobRequest, server/limits.h),
// and what an accepted job holds to.
absl::Status CheckSubmitJobRequest(const v1::SubmitJobRequest& request,
                                   const v1::DaemonConfig& config) {
  absl::StatusOr<CheckedJob> checked = CheckJobRequest(request, config);
  if (!checked.ok()) return checked.status();
  const PreparedJob& prepared = checked->prepared;
  const v1::Limits& limits = config.limits();
  OutdoorMatrixKey(prepared.scene, prepared.job.sampling());
  const TriangleMesh mesh = AssembleMesh(prepared.scene, DefaultDesign(prepared.scene));
  Require(static_cast<int64_t>(mesh.TriangleCount()) <= limits.max_triangles(),
          "an accepted job's scene has more triangles than max_triangles");
  Require(static_cast<int64_t>(prepared.scene.sensors.size()) <= limits.max_sensors(),
          "an accepted job's scene has more sensors than max_sensors");
  Require(prepared.job.sampling().indoor_paths_per_sensor() <= limits.max_indoor_paths_per_sensor(),
          "an accepted job has more indoor paths than max_indoor_paths_per_sensor");
  Require(prepared.job.budget().max_evaluations() <= limits.max_evaluations(),
          "an accepted job has more evaluations than max_evaluations");
  Require(prepared.job.sampling().candidates_at_once() <= limits.max_candidates_at_once(),
          "an accepted job asks for more designs at once than max_candidates_at_once");
  Require(AllFinite(mesh.vertices), "an accepted job's scene has non-finite vertices");
  return absl::OkStatus();
}

// SiteService.Register's checks before anything is stored (CheckSiteRequest), and what an
// accepted site holds to.
absl::Status CheckRegisterSiteRequest(const v1::RegisterSiteRequest& request,
                                      const v1::DaemonConfig& config) {
  absl::StatusOr<CheckedSite> checked = CheckSiteRequest(request, config);
  if (!checked.ok()) return checked.status();
  const v1::Limits& limits = config.limits();
  OutdoorMatrixKey(checked->scene, checked->sampling);
  Require(static_cast<int64_t>(checked->scene.fixed.TriangleCount()) <= limits.max_triangles(),
          "an accepted site's scene has more triangles than max_triangles");
  Require(checked->sampling.outdoor_paths() <= limits.max_outdoor_paths(),
          "an accepted site has more outdoor paths than max_outdoor_paths");
  return absl::OkStatus();
}

// The daemon's configuration when none is given, on the CPU.
const v1::DaemonConfig& DefaultConfig() {
  static const v1::DaemonConfig config = [] {
    v1::DaemonConfig given;
    given.set_backend("cpu");
    absl::StatusOr<v1::DaemonConfig> resolved = ResolveConfig(given);
    Require(resolved.ok(), "the default daemon configuration does not resolve");
    return *resolved;
  }();
  return config;
}

}  // namespace

absl::Status SceneJson(std::string_view bytes) {
  const std::string path = TheWorkspace().Write("city_office/fuzz_scene.json", bytes);
  absl::StatusOr<Scene> scene = LoadValidScene(path);
  if (!scene.ok()) return scene.status();
  const TriangleMesh mesh = AssembleMesh(*scene, DefaultDesign(*scene));
  Require(AllFinite(mesh.vertices), "a scene that loads has non-finite vertices");
  for (uint32_t m : mesh.material) Require(m < scene->materials.size(), "material out of range");
  for (const Sensor& s : scene->sensors) {
    Require(AllFinite({s.position, s.direction}), "a scene that loads has a non-finite sensor");
  }
  for (const ViewPoint& v : scene->views) {
    Require(AllFinite({v.position, v.direction, v.up}), "a scene that loads has a non-finite view");
    Require(std::abs(Length(v.direction) - 1) < 1e-9 && Length(Cross(v.direction, v.up)) > 0,
            "a view's direction is not a unit vector apart from its up");
  }
  return absl::OkStatus();
}

absl::Status JobJson(std::string_view bytes) {
  const Workspace& workspace = TheWorkspace();
  const std::string path = workspace.Write("city_office/fuzz_job.json", bytes);
  absl::StatusOr<v1::Job> job = ReadJobFile(path);
  if (!job.ok()) return job.status();
  absl::StatusOr<PreparedJob> prepared = PrepareJob(*job, workspace.Path("city_office"));
  if (!prepared.ok()) return prepared.status();
  const v1::Sampling& sampling = prepared->job.sampling();
  Require(sampling.batches() >= 2 && sampling.batches() <= 64, "batches out of range");
  Require(sampling.basis_cells() == 288 || sampling.basis_cells() == 1152, "basis out of range");
  Require(prepared->job.budget().max_evaluations() >= 1, "no evaluations");
  if (prepared->scene.blind()) {
    double narrowest = prepared->scene.blind()->slat_width_m.min;
    for (const v1::DesignVariable& v : prepared->job.variables()) {
      if (v.name() == "width") narrowest = std::min(narrowest, v.lower());
    }
    Require(MaxSlatCount(prepared->scene.window(), *prepared->scene.blind(), narrowest) <=
                kMaxBlindSlats,
            "a prepared job's blind may need more than kMaxBlindSlats slats");
  }
  OutdoorMatrixKey(prepared->scene, sampling);
  return absl::OkStatus();
}

absl::Status Epw(std::string_view bytes) {
  const absl::string_view text(bytes.data(), bytes.size());
  const absl::StatusOr<EpwData> strict = ParseEpw(text, "fuzz.epw");
  const absl::StatusOr<EpwData> lenient =
      ParseEpw(text, "fuzz.epw", {.treat_missing_as_zero = true});
  Require(!strict.ok() || lenient.ok(), "a file read strictly fails with missing values as 0");
  if (!lenient.ok()) return lenient.status();
  Require(!lenient->records.empty(), "a weather file without records parses");
  const absl::StatusOr<SkyMatrix> sky = BuildSkyMatrix(*lenient);
  if (!sky.ok()) return sky.status();
  Require(sky->radiance.allFinite(), "the sky matrix of a weather file that parses is not finite");
  Require(sky->radiance.cols() == static_cast<Eigen::Index>(lenient->records.size()),
          "one sky matrix column per record");
  return strict.status();
}

absl::Status Obj(std::string_view bytes) {
  absl::StatusOr<ObjTriangles> obj = ReadObj(TheWorkspace().Write("fuzz.obj", bytes));
  if (!obj.ok()) return obj.status();
  Require(obj->vertices.size() == 3 * obj->group.size(), "three vertices per triangle");
  Require(AllFinite(obj->vertices), "an OBJ that reads has non-finite vertices");
  return absl::OkStatus();
}

absl::Status RadianceMatrix(std::string_view bytes) {
  absl::StatusOr<Matrix> m = ReadRadianceMatrix(TheWorkspace().Write("fuzz.mtx", bytes));
  return m.status();
}

absl::Status OutdoorCache(std::string_view bytes) {
  const absl::StatusOr<OutdoorMatrix> as_given = DecodeOutdoorMatrix(bytes);

  // The header's payload size (bytes 16-23) and SHA-256 (24-55) made to match the payload
  constexpr size_t kHeaderBytes = 56;
  std::string repaired(bytes);
  if (repaired.size() >= kHeaderBytes) {
    const std::string_view payload = std::string_view(repaired).substr(kHeaderBytes);
    uint64_t size = payload.size();
    for (int i = 0; i < 8; ++i, size >>= 8) repaired[16 + i] = static_cast<char>(size & 0xff);
    const std::string digest = Sha256(payload);
    repaired.replace(24, 32, digest);
  }
  const absl::StatusOr<OutdoorMatrix> decoded = DecodeOutdoorMatrix(repaired);
  Require(!as_given.ok() || decoded.ok(), "a valid file fails once its header is rewritten");
  if (!decoded.ok()) return decoded.status();

  // What decodes has consistent sizes and encodes back to the same matrix
  const Matrix& o = decoded->coefficients;
  Require(o.rows() > 0 && o.cols() > 0, "an empty matrix decodes");
  Require(decoded->standard_error.size() == 0 || (decoded->standard_error.rows() == o.rows() &&
                                                  decoded->standard_error.cols() == o.cols()),
          "standard errors of another size than the matrix");
  const absl::StatusOr<OutdoorMatrix> again = DecodeOutdoorMatrix(EncodeOutdoorMatrix(*decoded));
  Require(again.ok(), "a decoded matrix does not decode after encoding");
  Require(again->coefficients.rows() == o.rows() && again->coefficients.cols() == o.cols() &&
              std::memcmp(again->coefficients.data(), o.data(), sizeof(double) * o.size()) == 0 &&
              again->key == decoded->key,
          "a decoded matrix changes when encoded and decoded again");
  return as_given.status();
}

absl::Status DaemonRequest(std::string_view bytes) {
  if (bytes.empty()) return absl::InvalidArgumentError("empty input");
  const bool site = (static_cast<unsigned char>(bytes[0]) & 1) != 0;
  bytes.remove_prefix(1);
  if (site) {
    v1::RegisterSiteRequest request;
    if (!request.ParseFromArray(bytes.data(), static_cast<int>(bytes.size()))) {
      return absl::InvalidArgumentError("not a RegisterSiteRequest");
    }
    return CheckRegisterSiteRequest(request, DefaultConfig());
  }
  v1::SubmitJobRequest request;
  if (!request.ParseFromArray(bytes.data(), static_cast<int>(bytes.size()))) {
    return absl::InvalidArgumentError("not a SubmitJobRequest");
  }
  return CheckSubmitJobRequest(request, DefaultConfig());
}

absl::Status DashboardSubmission(std::string_view bytes) {
  absl::StatusOr<v1::SubmitJobRequest> request = ParseDashboardSubmission(std::string(bytes));
  if (!request.ok()) return request.status();
  return CheckSubmitJobRequest(*request, DefaultConfig());
}

absl::Status RadImport(std::string_view bytes) {
  const size_t nul = bytes.find('\0');
  const std::string rad(bytes.substr(0, nul));
  const std::string pts(nul == std::string_view::npos ? "" : bytes.substr(nul + 1));
  const absl::StatusOr<v1::Scene> scene = ImportRadiance({{"fuzz.rad", rad}}, {"fuzz.pts", pts});
  if (!scene.ok()) return scene.status();
  // A blind of very many slats costs the export time, and the fuzzer no new code
  for (const v1::Window& w : scene->windows()) {
    const v1::VenetianBlind& b = w.blind();
    const double extent =
        b.orientation() == v1::VenetianBlind::VERTICAL ? w.width_m() : w.height_m();
    const double pitch = b.slat_width_m().value() + b.slat_spacing_m().value();
    if (w.has_blind() && !(extent <= 1000 * pitch)) return absl::OkStatus();
  }
  std::string points;
  const absl::StatusOr<std::string> written = ExportRadiance(*scene, &points);
  Require(written.ok(), "an imported Radiance model cannot be exported");
  const absl::StatusOr<v1::Scene> again =
      ImportRadiance({{"fuzz.rad", *written}}, {"fuzz.pts", points});
  Require(again.ok(), "an exported Radiance model does not import");
  // The same scene; a field at its default counts as unset (protobuf's JSON leaves out -0)
  google::protobuf::util::MessageDifferencer same;
  same.set_message_field_comparison(google::protobuf::util::MessageDifferencer::EQUIVALENT);
  Require(same.Compare(*scene, *again), "an exported Radiance model reads back changed");
  return absl::OkStatus();
}

absl::Status HbjsonImport(std::string_view bytes) {
  const absl::StatusOr<v1::Scene> scene = ImportHoneybee(bytes, "fuzz.hbjson", {});
  if (!scene.ok()) {
    Require(scene.status().code() == absl::StatusCode::kInvalidArgument,
            "a Honeybee model is refused otherwise than as bad input");
    return scene.status();
  }
  const auto finite = [](const v1::Vec3& v) {
    return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z());
  };
  for (const v1::Surface& s : scene->surfaces()) {
    for (const v1::Vec3& v : s.polygon().vertices()) {
      Require(finite(v), "an imported surface has a non-finite vertex");
    }
  }
  for (const v1::Window& w : scene->windows()) {
    Require(finite(w.center()) && finite(w.outward_normal()) && finite(w.up()) &&
                std::isfinite(w.width_m()) && std::isfinite(w.height_m()),
            "an imported window is not finite");
  }
  for (const v1::Sensor& s : scene->sensors()) {
    Require(finite(s.position()) && finite(s.direction()), "an imported sensor is not finite");
  }
  Require(scene->surfaces_size() <= static_cast<int>(kMaxHoneybeeSurfaces),
          "an import makes more surfaces than kMaxHoneybeeSurfaces");
  Require(scene->sensors_size() <= kMaxSceneSensors,
          "an import makes more sensors than a scene takes");
  const absl::StatusOr<Scene> built = BuildScene(*scene, "fuzz.hbjson");
  if (!built.ok()) {
    Require(built.status().code() == absl::StatusCode::kInvalidArgument,
            "an imported scene is refused otherwise than as bad input");
    return built.status();
  }
  Require(AllFinite(AssembleMesh(*built, DefaultDesign(*built)).vertices),
          "an imported scene has non-finite vertices");
  return absl::OkStatus();
}

std::span<const Target> Targets() {
  static constexpr Target kTargets[] = {
      {"scene_json", &SceneJson},
      {"job_json", &JobJson},
      {"epw", &Epw},
      {"obj", &Obj},
      {"radiance_matrix", &RadianceMatrix},
      {"outdoor_cache", &OutdoorCache},
      {"daemon_request", &DaemonRequest},
      {"rad_import", &RadImport},
      {"hbjson_import", &HbjsonImport},
      {"dashboard_submission", &DashboardSubmission},
  };
  return kTargets;
}

void QuietLibraries() { google::protobuf::SetLogHandler(nullptr); }

}  // namespace fenestra::fuzz
