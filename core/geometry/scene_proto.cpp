#include "core/geometry/scene_proto.h"

#include "core/geometry/material.h"

namespace fenestra {
namespace {

void SetVec3(const Vec3d& v, v1::Vec3* out) {
  out->set_x(v.x);
  out->set_y(v.y);
  out->set_z(v.z);
}

void SetParameter(const ParameterRange& range, v1::Parameter* out) {
  out->set_value(range.value);
  out->set_min(range.min);
  out->set_max(range.max);
}

void AddSurfaces(const Scene& scene, v1::Scene& out) {
  const TriangleMesh& mesh = scene.fixed;
  for (size_t t = 0; t < mesh.TriangleCount(); ++t) {
    const Vec3d* v = &mesh.vertices[3 * t];
    // A sliver of a fanned polygon would fail the polygon check; it holds no area
    if (IsDegenerateTriangle(v[0], v[1], v[2])) continue;
    v1::Surface& surface = *out.add_surfaces();
    surface.set_name(mesh.part_names[mesh.part[t]]);
    surface.set_material(scene.materials[mesh.material[t]].name);
    surface.set_side(mesh.side[t] == Side::kIndoor ? v1::SIDE_INDOOR : v1::SIDE_OUTDOOR);
    for (int k = 0; k < 3; ++k) SetVec3(v[k], surface.mutable_polygon()->add_vertices());
  }
}

// The colour, specularity and roughness of a plastic, metal or trans.
template <typename Kind>
void SetLobe(const RadianceParameters& p, Kind* out) {
  out->set_reflectance(p.colour);
  out->set_specularity(p.specularity);
  out->set_roughness(p.roughness);
}

// Material `m` as the scene gave it: Lambertian fields, or its kind's parameters.
void SetMaterial(const Material& m, v1::Material* out) {
  out->set_name(m.name);
  const RadianceParameters p = ParametersOfKind(m);
  switch (m.kind) {
    case MaterialKind::kLambertian:
      if (m.reflectance != 0) out->set_reflectance(m.reflectance);
      if (m.transmittance >= 0) out->set_transmittance(m.transmittance);
      break;
    case MaterialKind::kPlastic:
      SetLobe(p, out->mutable_plastic());
      break;
    case MaterialKind::kMetal:
      SetLobe(p, out->mutable_metal());
      break;
    case MaterialKind::kTrans:
      SetLobe(p, out->mutable_trans());
      out->mutable_trans()->set_transmissivity(p.transmissivity);
      out->mutable_trans()->set_transmitted_specular(p.transmitted_specular);
      break;
    case MaterialKind::kGlass:
      out->mutable_glass()->set_transmittance(m.transmittance);
      break;
  }
}

void SetBlind(const Scene& scene, const BlindSpec& spec, v1::VenetianBlind& out) {
  out.set_material(scene.materials[spec.material].name);
  if (spec.outer_material) out.set_outer_material(scene.materials[*spec.outer_material].name);
  out.set_orientation(spec.vertical ? v1::VenetianBlind::VERTICAL : v1::VenetianBlind::HORIZONTAL);
  SetParameter(spec.tilt_rad, out.mutable_tilt_rad());
  SetParameter(spec.slat_width_m, out.mutable_slat_width_m());
  SetParameter(spec.slat_spacing_m, out.mutable_slat_spacing_m());
  SetParameter(spec.slat_thickness_m, out.mutable_slat_thickness_m());
  out.set_wall_gap_m(spec.wall_gap_m);
  out.set_side_margin_m(spec.side_margin_m);
  out.set_operation(spec.automated_sun ? v1::VenetianBlind::AUTOMATED_SUN
                                       : v1::VenetianBlind::STATIC);
  out.set_group(spec.group);
}

void SetWindow(const Window& w, v1::Window& window) {
  SetVec3(w.center, window.mutable_center());
  SetVec3(w.normal, window.mutable_outward_normal());
  SetVec3(w.up, window.mutable_up());
  window.set_width_m(w.width_m);
  window.set_height_m(w.height_m);
  window.set_depth_m(w.depth_m);
}

// The one-window form for a scene that came in it (one window named "window"), else the list.
void SetWindows(const Scene& scene, v1::Scene& out) {
  if (scene.windows.size() == 1 && scene.windows[0].name == kOneWindowName) {
    SetWindow(scene.window(), *out.mutable_window());
    if (scene.blind()) SetBlind(scene, *scene.blind(), *out.mutable_blind());
    return;
  }
  for (const SceneWindow& w : scene.windows) {
    v1::Window& window = *out.add_windows();
    window.set_name(w.name);
    SetWindow(w.window, window);
    if (w.blind) SetBlind(scene, *w.blind, *window.mutable_blind());
  }
}

}  // namespace

v1::Scene SelfContainedSceneProto(const Scene& scene) {
  v1::Scene out;
  out.set_name(scene.name);
  for (const Material& m : scene.materials) SetMaterial(m, out.add_materials());
  AddSurfaces(scene, out);

  SetWindows(scene, out);

  for (const Sensor& s : scene.sensors) {
    v1::Sensor& sensor = *out.add_sensors();
    sensor.set_name(s.name);
    SetVec3(s.position, sensor.mutable_position());
    SetVec3(s.direction, sensor.mutable_direction());
  }
  for (const ViewPoint& v : scene.views) {
    v1::ViewPoint& view = *out.add_views();
    view.set_name(v.name);
    SetVec3(v.position, view.mutable_position());
    SetVec3(v.direction, view.mutable_direction());
    SetVec3(v.up, view.mutable_up());
  }

  v1::Site& site = *out.mutable_site();
  site.set_latitude_deg(scene.site.latitude_deg);
  site.set_longitude_deg(scene.site.longitude_deg);
  site.set_time_zone_h(scene.site.time_zone_h);
  site.set_ground_reflectance(scene.site.ground_reflectance);
  return out;
}

}  // namespace fenestra
