#include "core/trace/embree_scene.h"

#include "absl/strings/str_cat.h"

namespace fenestra {
namespace {

absl::Status EmbreeError(RTCDevice device, const char* what) {
  return absl::InternalError(
      absl::StrCat("Embree failed to ", what, " (error ", rtcGetDeviceError(device), ")"));
}

}  // namespace

absl::StatusOr<std::unique_ptr<EmbreeScene>> EmbreeScene::Build(const TraceGeometry& geometry) {
  std::unique_ptr<EmbreeScene> result(new EmbreeScene);
  result->device_ = rtcNewDevice(nullptr);
  if (result->device_ == nullptr) return EmbreeError(nullptr, "create a device");
  RTCDevice device = result->device_;

  // Keep the triangles with area
  for (size_t t = 0; t < geometry.TriangleCount(); ++t) {
    if (!HasArea(geometry, t)) continue;
    result->primitive_triangle_.push_back(static_cast<uint32_t>(t));
    for (int k = 0; k < 3; ++k) result->vertices_.push_back(geometry.vertices[3 * t + k]);
  }

  result->scene_ = rtcNewScene(device);
  if (result->scene_ == nullptr) return EmbreeError(device, "create a scene");
  rtcSetSceneFlags(result->scene_, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(result->scene_, RTC_BUILD_QUALITY_HIGH);

  // One triangle geometry holding every primitive
  const size_t count = result->primitive_triangle_.size();
  if (count > 0) {
    RTCGeometry mesh = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    if (mesh == nullptr) return EmbreeError(device, "create a triangle geometry");
    rtcSetGeometryBuildQuality(mesh, RTC_BUILD_QUALITY_HIGH);
    auto* positions = static_cast<float*>(rtcSetNewGeometryBuffer(
        mesh, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 3 * count));
    auto* indices = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
        mesh, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), count));
    if (positions == nullptr || indices == nullptr) {
      rtcReleaseGeometry(mesh);
      return EmbreeError(device, "allocate the triangle buffers");
    }
    for (size_t i = 0; i < 3 * count; ++i) {
      positions[3 * i] = result->vertices_[i].x;
      positions[3 * i + 1] = result->vertices_[i].y;
      positions[3 * i + 2] = result->vertices_[i].z;
      indices[i] = static_cast<uint32_t>(i);
    }
    rtcCommitGeometry(mesh);
    rtcAttachGeometry(result->scene_, mesh);
    rtcReleaseGeometry(mesh);
  }
  rtcCommitScene(result->scene_);
  if (rtcGetDeviceError(device) != RTC_ERROR_NONE) return EmbreeError(device, "build the scene");
  return result;
}

EmbreeScene::~EmbreeScene() {
  if (scene_ != nullptr) rtcReleaseScene(scene_);
  if (device_ != nullptr) rtcReleaseDevice(device_);
}

}  // namespace fenestra
