// fenestra scene check|export
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <iostream>
#include <limits>
#include <memory>
#include <vector>

#include "client/cli_util.h"
#include "client/commands.h"
#include "core/common/atomic_file.h"
#include "core/geometry/obj_io.h"
#include "core/geometry/rad_import.h"
#include "core/geometry/rad_io.h"
#include "core/geometry/scene.h"
#include "core/trace/room_check.h"

namespace fenestra {
namespace {

void PrintSummary(const Scene& scene, const BlindDesign& design) {
  const TriangleMesh mesh = AssembleMesh(scene, design);
  std::vector<size_t> per_part(mesh.part_names.size(), 0);
  Vec3d lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
           std::numeric_limits<double>::infinity()};
  Vec3d hi = -lo;
  for (size_t t = 0; t < mesh.TriangleCount(); ++t) ++per_part[mesh.part[t]];
  for (const Vec3d& v : mesh.vertices) {
    lo = {std::min(lo.x, v.x), std::min(lo.y, v.y), std::min(lo.z, v.z)};
    hi = {std::max(hi.x, v.x), std::max(hi.y, v.y), std::max(hi.z, v.z)};
  }
  fmt::print("scene '{}' ({}): {} triangles, {} materials\n", scene.name, scene.source_path,
             mesh.TriangleCount(), scene.materials.size());
  size_t width = 0;
  for (const std::string& name : mesh.part_names) width = std::max(width, name.size());
  for (size_t p = 0; p < mesh.part_names.size(); ++p) {
    fmt::print("  {:<{}} {:>6} triangles\n", mesh.part_names[p], width, per_part[p]);
  }
  if (scene.dropped_degenerate > 0) {
    fmt::print("  ({} zero-area OBJ triangles left out)\n", scene.dropped_degenerate);
  }
  fmt::print("bounding box: ({:.3f}, {:.3f}, {:.3f}) .. ({:.3f}, {:.3f}, {:.3f}) m\n", lo.x, lo.y,
             lo.z, hi.x, hi.y, hi.z);
  for (const SceneWindow& sw : scene.windows) {
    const Window& w = sw.window;
    fmt::print(
        "{}: {:.3f} x {:.3f} m at ({:.3f}, {:.3f}, {:.3f}), outward ({:.3f}, {:.3f}, "
        "{:.3f}), depth {:.3f} m{}\n",
        sw.name, w.width_m, w.height_m, w.center.x, w.center.y, w.center.z, w.normal.x, w.normal.y,
        w.normal.z, w.depth_m, sw.blind ? ", with a blind" : "");
  }
  fmt::print("sensors: {}\n", scene.sensors.size());
  for (const Sensor& s : scene.sensors) {
    fmt::print("  {:<10} ({:.3f}, {:.3f}, {:.3f}) facing ({:.3f}, {:.3f}, {:.3f})\n", s.name,
               s.position.x, s.position.y, s.position.z, s.direction.x, s.direction.y,
               s.direction.z);
  }
  for (const SceneWindow& sw : scene.windows) {
    if (!design.has_blind || !sw.blind) continue;
    const BlindLayout layout = LayoutBlind(sw.window, *sw.blind, design);
    fmt::print(
        "blind{}: alpha {:.4f} rad, width {:.4f} m, spacing {:.4f} m, thickness {:.4f} m: "
        "{} slats at pitch {:.4f} m, axes {:.4f} m behind the wall\n",
        scene.windows.size() == 1 ? "" : " " + sw.name, design.tilt_rad, design.slat_width_m,
        design.slat_spacing_m, design.slat_thickness_m, layout.slat_count, layout.pitch_m,
        layout.axis_depth_m);
  }
  if (!scene.site.weather_file.empty()) {
    fmt::print("site: {}, UTC{:+g}, weather {}\n",
               FormatLocation(scene.site.latitude_deg, scene.site.longitude_deg),
               scene.site.time_zone_h, scene.site.weather_file);
  }
}

// `fenestra scene export --model`: the scene file as a Radiance model (ExportRadiance), the
// blind's parameters at the design `set` gives, and its sensors as a points file.
void ExportModel(const std::string& file, const std::string& set, const std::string& model,
                 const std::string& pts) {
  v1::Scene proto = ValueOrFail(ReadSceneProto(file));
  const Scene built = ValueOrFail(LoadScene(file));
  const BlindDesign design =
      ValueOrFail(DesignWithOverrides(built, ValueOrFail(ParseDesignValues(set))));
  const auto at_design = [&](v1::VenetianBlind& b) {
    b.mutable_tilt_rad()->set_value(design.tilt_rad);
    b.mutable_slat_width_m()->set_value(design.slat_width_m);
    b.mutable_slat_spacing_m()->set_value(design.slat_spacing_m);
    b.mutable_slat_thickness_m()->set_value(design.slat_thickness_m);
  };
  if (design.has_blind) {
    if (proto.has_blind()) at_design(*proto.mutable_blind());
    for (v1::Window& w : *proto.mutable_windows()) {
      if (w.has_blind()) at_design(*w.mutable_blind());
    }
  }
  std::string points;
  const std::string text = ValueOrFail(ExportRadiance(proto, &points));
  const std::pair<std::string, const std::string*> outputs[] = {{model, &text}, {pts, &points}};
  for (const auto& output : outputs) {
    const std::string& path = output.first;
    const std::string* content = output.second;
    if (path.empty()) continue;
    const absl::Status written = WriteFileAtomically(path, [content](std::ostream& out) {
      out << *content;
      return absl::OkStatus();
    });
    if (!written.ok()) Fail(written);
    fmt::print("wrote {}\n", path);
  }
}

}  // namespace

void AddSceneCommand(CLI::App& app) {
  CLI::App* scene = app.add_subcommand("scene", "Check, export or import a scene file");
  AddSceneImportCommand(*scene);
  scene->require_subcommand(1);

  auto check_file = std::make_shared<std::string>();
  CLI::App* check = scene->add_subcommand("check", "Validate a scene and print a summary");
  check->add_option("FILE", *check_file, "Scene file (JSON)")->required();
  check->callback([check_file] {
    const Scene s = ValueOrFail(LoadValidScene(*check_file));
    PrintSummary(s, DefaultDesign(s));
  });

  struct ExportArgs {
    std::string file, obj, rad, model, pts, set;
  };
  auto args = std::make_shared<ExportArgs>();
  CLI::App* exp = scene->add_subcommand(
      "export", "Write the assembled geometry as OBJ, or as a Radiance scene with its sensors");
  exp->add_option("FILE", args->file, "Scene file (JSON)")->required();
  CLI::Option* obj = exp->add_option("--obj", args->obj, "Output OBJ file");
  CLI::Option* rad = exp->add_option(
      "--rad", args->rad, "Output Radiance scene: the materials as Radiance reads them, polygons");
  CLI::Option* model = exp->add_option(
      "--model", args->model,
      "Output the scene as a Radiance model that `fenestra scene import` reads back into the "
      "same scene (surfaces, windows and blinds as they are given, the slats at the design)");
  exp->add_option("--pts", args->pts,
                  "Output sensors as a Radiance points file (with --rad or --model)");
  obj->excludes(rad);
  model->excludes(obj);
  model->excludes(rad);
  exp->add_option("--set", args->set, "Design values, e.g. alpha=0.5,width=0.12");
  exp->callback([args] {
    if (args->obj.empty() && args->rad.empty() && args->model.empty()) {
      Fail(absl::InvalidArgumentError("scene export needs --obj, --rad or --model"));
    }
    if (!args->pts.empty() && args->rad.empty() && args->model.empty()) {
      Fail(absl::InvalidArgumentError("--pts goes with --rad or --model"));
    }
    if (!args->model.empty()) {
      ExportModel(args->file, args->set, args->model, args->pts);
      return;
    }
    const Scene s = ValueOrFail(LoadScene(args->file));
    const BlindDesign design =
        ValueOrFail(DesignWithOverrides(s, ValueOrFail(ParseDesignValues(args->set))));
    if (!args->obj.empty()) {
      const size_t triangles = ValueOrFail(WriteSceneObj(args->obj, s, design));
      fmt::print("wrote {} triangles to {}\n", triangles, args->obj);
      return;
    }
    const size_t polygons = ValueOrFail(WriteSceneRad(args->rad, s, design));
    fmt::print("wrote {} materials and {} polygons to {}\n", s.materials.size(), polygons,
               args->rad);
    if (!args->pts.empty()) {
      if (absl::Status written = WriteScenePoints(args->pts, s); !written.ok()) Fail(written);
      fmt::print("wrote {} sensors to {}\n", s.sensors.size(), args->pts);
    }
  });
}

}  // namespace fenestra
