// fenestra scene import: a Radiance (.rad, with a .pts points file) or Honeybee (.hbjson)
// model as a scene file (core/README.md, "Radiance models", "Honeybee models").
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "client/cli_util.h"
#include "client/commands.h"
#include "core/common/status_macros.h"
#include "core/geometry/hbjson_import.h"
#include "core/geometry/rad_import.h"
#include "core/geometry/scene.h"
#include "core/sky/epw.h"
#include "core/trace/room_check.h"

namespace fenestra {
namespace {

namespace fs = std::filesystem;

struct ImportArgs {
  std::vector<std::string> models, context;
  std::string output, points, room, grid, weather;
};

bool IsHoneybee(const std::string& path) {
  const std::string extension = fs::path(path).extension().string();
  return extension == ".hbjson" || extension == ".json";
}

// The model's scene, and a line saying what was taken.
absl::StatusOr<v1::Scene> Import(const ImportArgs& a, std::string* taken) {
  if (IsHoneybee(a.models[0])) {
    if (a.models.size() > 1) {
      return absl::InvalidArgumentError("a Honeybee model is one file; got " +
                                        std::to_string(a.models.size()));
    }
    FENESTRA_ASSIGN_OR_RETURN(text, ReadFileBytes(a.models[0]));
    const std::string name = fs::path(a.models[0]).filename().string();
    if (!a.points.empty() || !a.context.empty()) {
      return absl::InvalidArgumentError(
          "--pts and --context are for Radiance models; a Honeybee model has its sensor grids "
          "and shades");
    }
    HoneybeeImportOptions options;
    options.room = a.room;
    options.sensor_grid = a.grid;
    HoneybeeImportSummary summary;
    FENESTRA_ASSIGN_OR_RETURN(scene, ImportHoneybee(text, name, options, &summary));
    *taken = fmt::format(
        "room '{}' of {}: {} faces, {} apertures and {} doors ({} windows), {} shades, {} faces "
        "of other rooms, {} sensors",
        summary.room, summary.rooms, summary.faces, summary.apertures, summary.doors,
        summary.windows, summary.shades, summary.context_faces, summary.sensors);
    return scene;
  }
  if (!a.room.empty() || !a.grid.empty()) {
    return absl::InvalidArgumentError("--room and --grid are for Honeybee models");
  }
  if (a.points.empty()) {
    return absl::InvalidArgumentError("a Radiance model needs its sensors: --pts FILE");
  }
  std::vector<RadSource> sources;
  for (const std::string& m : a.models) {
    FENESTRA_ASSIGN_OR_RETURN(text, ReadFileBytes(m));
    sources.push_back({fs::path(m).filename().string(), std::move(text), false});
  }
  for (const std::string& c : a.context) {
    FENESTRA_ASSIGN_OR_RETURN(context, ReadFileBytes(c));
    sources.push_back({fs::path(c).filename().string(), std::move(context), true});
  }
  FENESTRA_ASSIGN_OR_RETURN(points, ReadFileBytes(a.points));
  RadImportSummary summary;
  FENESTRA_ASSIGN_OR_RETURN(
      scene, ImportRadiance(sources, {fs::path(a.points).filename().string(), points, false}, {},
                            &summary));
  *taken = DescribeRadImport(summary, scene.surfaces_size());
  return scene;
}

// The site from an EPW file's header; its path as given (relative to the scene file's
// folder when it is relative: the scene is written next to where it is read).
absl::Status AddSite(const std::string& weather, const std::string& output, v1::Scene& scene) {
  FENESTRA_ASSIGN_OR_RETURN(epw, ReadEpw(weather));
  v1::Site& site = *scene.mutable_site();
  site.set_latitude_deg(epw.location.latitude_deg);
  site.set_longitude_deg(epw.location.longitude_deg);
  site.set_time_zone_h(epw.location.time_zone_hours);
  const fs::path folder = fs::absolute(output).parent_path();
  site.set_weather_file(fs::proximate(fs::absolute(weather), folder).string());
  return absl::OkStatus();
}

}  // namespace

void AddSceneImportCommand(CLI::App& scene) {
  auto args = std::make_shared<ImportArgs>();
  CLI::App* import = scene.add_subcommand(
      "import", "Make a scene file of a Radiance (.rad) or Honeybee (.hbjson) model");
  import
      ->add_option("MODEL", args->models,
                   "Radiance scene descriptions (materials first, as oconv reads them) or one "
                   "Honeybee model JSON")
      ->required();
  import->add_option("-o,--output", args->output, "Scene file to write (JSON)")->required();
  import->add_option("--pts", args->points,
                     "Radiance: the sensors, a points file (x y z dx dy dz per line)");
  import->add_option("--context", args->context,
                     "Radiance: a file of outdoor surfaces (neighbours, ground); repeatable");
  import->add_option("--room", args->room, "Honeybee: the room to simulate (its identifier)");
  import->add_option("--grid", args->grid, "Honeybee: the sensor grid (its identifier)");
  import->add_option("--weather", args->weather,
                     "EPW weather file: the site (location, time zone) from its header");
  import->callback([args] {
    std::string taken;
  v1::Scene scene = ValueOrFail(Import(*args, &taken));
  if (!args->weather.empty()) {
    if (absl::Status site = AddSite(args->weather, args->output, scene); !site.ok()) {
      Fail(site);
    }
  }
  if (absl::Status written = WriteJsonFile(args->output, scene); !written.ok()) Fail(written);
  fmt::print("{}\nwrote {} ({} surfaces, {} windows, {} sensors)\n", taken, args->output,
             scene.surfaces_size(), scene.windows_size(), scene.sensors_size());
  // The room check, as `fenestra scene check` makes it: the file stays for editing
  if (absl::StatusOr<Scene> valid = LoadValidScene(args->output); !valid.ok()) Fail(valid.status());
  fmt::print("the scene is a room: fenestra scene check {} shows it\n", args->output);
});
}  // namespace fenestra

}  // namespace fenestra
