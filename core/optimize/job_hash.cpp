// The content hashes of job.h: OutdoorMatrixKey, what an outdoor matrix is made from (the key
// of a cached one), and JobContentHash, the job a search checkpoint belongs to.
#include <optional>
#include <string>

#include "core/common/content_hash.h"
#include "core/geometry/scene_proto.h"
#include "core/optimize/job.h"
#include "core/sky/epw.h"
#include "google/protobuf/io/coded_stream.h"
#include "google/protobuf/io/zero_copy_stream_impl_lite.h"

namespace fenestra {

std::string OutdoorMatrixKey(const Scene& scene, const v1::Sampling& sampling) {
  ContentHash hash;
  hash.String("fenestra outdoor matrix v4");
  const TriangleMesh& mesh = scene.fixed;
  for (size_t t = 0; t < mesh.TriangleCount(); ++t) {
    if (mesh.side[t] != Side::kOutdoor) continue;
    for (int k = 0; k < 3; ++k) {
      const Vec3d v = mesh.vertices[3 * t + k];
      hash.Value(v.x), hash.Value(v.y), hash.Value(v.z);
    }
    const Material& m = scene.materials[mesh.material[t]];
    hash.Value(m.reflectance), hash.Value(m.transmittance), hash.Value(m.specular);
    hash.Value(m.roughness), hash.Value(m.through), hash.Value(static_cast<int>(m.kind));
  }
  for (const SceneWindow& scene_window : scene.windows) {
    const Window& w = scene_window.window;
    for (const Vec3d& v : {w.center, w.normal, w.up})
      hash.Value(v.x), hash.Value(v.y), hash.Value(v.z);
    hash.Value(w.width_m), hash.Value(w.height_m);
  }
  hash.Value(sampling.outdoor_paths()), hash.Value(sampling.outdoor_bounces());
  hash.Value(sampling.seed()), hash.Value(sampling.basis_cells());
  hash.Value(sampling.batches());
  // (a cache of the pseudo-random draws keeps its key)
  if (sampling.sequence() == v1::SEQUENCE_SOBOL) hash.String("sobol");
  const WindowParts parts = SamplingWindowParts(sampling, scene);
  hash.Value(parts.columns), hash.Value(parts.rows);
  return hash.Hex();
}

std::string JobContentHash(const PreparedJob& job) {
  // The job with its scene inline (a scene_file, or the scene left out, says nothing of the
  // scene's content), serialized deterministically
  v1::Job content = job.job;
  content.clear_scene_file();
  *content.mutable_scene() = SelfContainedSceneProto(job.scene);
  // How many designs are evaluated at once changes the time, not the steps
  content.mutable_sampling()->clear_candidates_at_once();
  std::string bytes;
  {
    google::protobuf::io::StringOutputStream stream(&bytes);
    google::protobuf::io::CodedOutputStream coded(&stream);
    coded.SetSerializationDeterministic(true);
    content.SerializeToCodedStream(&coded);
  }
  ContentHash hash;
  hash.String("fenestra job v1");
  hash.String(bytes);

  // The weather: the site and every record
  const EpwLocation& site = job.weather.location;
  hash.Value(site.latitude_deg), hash.Value(site.longitude_deg);
  hash.Value(site.time_zone_hours), hash.Value(site.elevation_m);
  hash.Value(job.weather.records_per_hour);
  for (const EpwRecord& r : job.weather.records) {
    for (const int v : {r.year, r.month, r.day, r.hour, r.minute}) hash.Value(v);
    hash.Value(r.direct_normal_wm2), hash.Value(r.diffuse_horizontal_wm2);
    for (const std::optional<double>& v :
         {r.dry_bulb_c, r.dew_point_c, r.global_horizontal_wm2, r.global_horizontal_lux,
          r.direct_normal_lux, r.diffuse_horizontal_lux}) {
      hash.Value(v.has_value());
      hash.Value(v.value_or(0.0));
    }
  }
  return hash.Hex();
}

}  // namespace fenestra
