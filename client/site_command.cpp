// fenestra site add/list/show/rm: sites registered with fenestrad, whose outdoor matrices
// the daemon computes once and caches.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>
#include <thread>

#include "absl/strings/str_cat.h"
#include "client/cli_util.h"
#include "client/commands.h"
#include "client/grpc_client.h"
#include "client/job_request.h"
#include "core/dc/two_stage.h"
#include "core/geometry/scene.h"

namespace fenestra {
namespace {

namespace fs = std::filesystem;

// How long `site add --wait` waits between two looks at the site.
constexpr auto kSitePollInterval = std::chrono::milliseconds(250);

void PrintSite(const v1::SiteInfo& s) {
  fmt::print("{} ({}): {}\n", s.id(), s.name(), StateName(s.state()));
  fmt::print("  location: {}; weather: {}\n", FormatLocation(s.latitude_deg(), s.longitude_deg()),
             s.has_weather() ? s.weather_name() : "none");
  const v1::Sampling& sampling = s.sampling();
  const std::string parts =
      sampling.window_columns() > 0 || sampling.window_rows() > 0
          ? fmt::format("{}x{}", sampling.window_columns(), sampling.window_rows())
          : std::string("automatic");
  fmt::print(
      "  outdoor: {} triangles, {} paths, {} bounces, seed {}, {} direction cells, window parts "
      "{}\n",
      s.outdoor_triangles(), sampling.outdoor_paths(), sampling.outdoor_bounces(), sampling.seed(),
      sampling.basis_cells(), parts);
  fmt::print("  outdoor matrix key: {}\n", s.outdoor_key());
  if (s.state() == v1::SITE_STATE_READY) {
    fmt::print(
        "  matrix: traced {} time(s), last in {:.2f} s on {}{}; mean relative standard error "
        "{:.4f}; reused by {} job(s)\n",
        s.computations(), s.compute_seconds(), s.backend(),
        s.loaded_from_disk() ? ", loaded from the disk cache at start" : "",
        s.mean_relative_standard_error(), s.jobs_reused());
  }
  if (s.state() == v1::SITE_STATE_FAILED) fmt::print("  error: {}\n", s.error());
}

// The arguments of `fenestra site add`.
struct SiteAddArgs {
  ServerOptions server;
  std::string scene, job, name, backend, window_parts;
  int64_t outdoor_paths = 0;
  std::optional<int> outdoor_bounces;  // unset: the job's or the default
  int basis_cells = 0;
  uint64_t seed = 0;
  bool wait = false, json = false;
};

// The registration `fenestra site add` sends: the scene (with its OBJ meshes) and weather
// file of a scene file or a job file, and the sampling options given.
v1::RegisterSiteRequest SiteAddRequest(const SiteAddArgs& args) {
  if (args.scene.empty() == args.job.empty()) {
    Fail(absl::InvalidArgumentError("give a scene file or --job JOB.json (one of them)"));
  }
  v1::RegisterSiteRequest request;
  if (!args.job.empty()) {
    v1::SubmitJobRequest job = ValueOrFail(SubmitRequestFromJobFile(args.job));
    *request.mutable_scene() = job.job().scene();
    *request.mutable_sampling() = job.job().sampling();
    request.set_weather_epw(job.weather_epw());
    request.set_weather_name(job.weather_name());
  } else {
    const v1::Scene scene = ValueOrFail(ReadSceneProto(args.scene));
    const fs::path dir = fs::path(args.scene).parent_path();
    *request.mutable_scene() = ValueOrFail(InlineObjMeshes(scene, dir.string()));
    if (!scene.site().weather_file().empty()) {
      const fs::path weather = dir / scene.site().weather_file();
      request.set_weather_epw(ValueOrFail(ReadFileBytes(weather.string())));
      request.set_weather_name(weather.filename().string());
    }
  }
  request.mutable_scene()->mutable_site()->clear_weather_file();
  if (!args.name.empty()) request.set_name(args.name);
  v1::Sampling& s = *request.mutable_sampling();
  if (args.outdoor_paths) s.set_outdoor_paths(args.outdoor_paths);
  if (args.outdoor_bounces) s.set_outdoor_bounces(*args.outdoor_bounces);
  if (args.seed) s.set_seed(args.seed);
  if (args.basis_cells) s.set_basis_cells(args.basis_cells);
  if (!args.window_parts.empty()) {
    const WindowParts parts = ValueOrFail(ParseWindowParts(args.window_parts));
    s.set_window_columns(parts.columns);
    s.set_window_rows(parts.rows);
  }
  if (!args.backend.empty()) s.set_backend(args.backend);
  return request;
}

// fenestra site add
void AddSiteAdd(CLI::App* site) {
  auto add = std::make_shared<SiteAddArgs>();
  CLI::App* add_cmd = site->add_subcommand(
      "add", "Register a site: its outdoor matrix is computed in the background and cached");
  add_cmd->add_option("SCENE", add->scene, "Scene file (JSON)");
  add_cmd->add_option("--job", add->job,
                      "Job file: take its scene and outdoor sampling (so its jobs match)");
  add_cmd->add_option("--name", add->name, "Label; default: the scene's name");
  add_cmd->add_option("--outdoor-paths", add->outdoor_paths,
                      absl::StrCat("Outdoor paths [default ", kDefaultOutdoorPaths, "]"));
  add_cmd->add_option(
      "--outdoor-bounces", add->outdoor_bounces,
      absl::StrCat("Outdoor reflections: 0 = none (the sky seen straight from the window), "
                   "-1 = unlimited [default ",
                   kDefaultOutdoorBounces, "]"));
  add_cmd->add_option("--seed", add->seed,
                      absl::StrCat("Random seed [default ", kDefaultSeed, "]"));
  add_cmd->add_option("--basis-cells", add->basis_cells,
                      "Direction cells of each window part: 288 or 1152");
  add_cmd->add_option("--window-parts", add->window_parts,
                      "The window split into COLUMNSxROWS parts [default: parts of at most 0.5 m]");
  add_cmd->add_option("--backend", add->backend, "cpu, cuda or auto; default: the daemon's");
  add_cmd->add_flag("--wait", add->wait, "Wait until the outdoor matrix is ready");
  add_cmd->add_flag("--json", add->json, "Print the site as JSON");
  AddServerOptions(add_cmd, add->server);
  add_cmd->callback([add] {
    const v1::RegisterSiteRequest request = SiteAddRequest(*add);
    FenestraClient client = ConnectOrFail(add->server);
    v1::SiteInfo info = ValueOrFail(client.RegisterSite(request));
    if (!add->json) {
      fmt::print("{} registered: {}\n", info.id(),
                 info.state() == v1::SITE_STATE_READY ? "outdoor matrix already cached"
                                                      : "computing its outdoor matrix");
      std::fflush(stdout);
    }
    while (add->wait && info.state() == v1::SITE_STATE_COMPUTING) {
      std::this_thread::sleep_for(kSitePollInterval);
      info = ValueOrFail(client.GetSite(info.id()));
    }
    info.clear_scene();
    if (add->json) {
      fmt::print("{}\n", ToJson(info, JsonLayout::kIndented));
    } else if (add->wait) {
      PrintSite(info);
    }
    if (info.state() == v1::SITE_STATE_FAILED) {
      Fail(absl::InternalError(absl::StrCat(info.id(), " failed: ", info.error())));
    }
  });
}

// fenestra site list
void AddSiteList(CLI::App* site) {
  auto list_server = std::make_shared<ServerOptions>();
  CLI::App* list_cmd = site->add_subcommand("list", "List the sites");
  AddServerOptions(list_cmd, *list_server);
  list_cmd->callback([list_server] {
    const v1::ListSitesResponse response = ValueOrFail(ConnectOrFail(*list_server).ListSites());
    fmt::print("{:<10} {:<10} {:>13} {:>12} {:>5}  {}\n", "ID", "STATE", "OUTDOOR PATHS",
               "COMPUTE [s]", "JOBS", "NAME");
    for (const v1::SiteInfo& s : response.sites()) {
      fmt::print("{:<10} {:<10} {:>13} {:>12.2f} {:>5}  {}\n", s.id(), StateName(s.state()),
                 s.sampling().outdoor_paths(), s.compute_seconds(), s.jobs_reused(), s.name());
    }
  });
}

// fenestra site show
void AddSiteShow(CLI::App* site) {
  struct ShowArgs {
    ServerOptions server;
    std::string id;
    bool json = false;
  };
  auto show = std::make_shared<ShowArgs>();
  CLI::App* show_cmd = site->add_subcommand("show", "Show one site");
  show_cmd->add_option("ID", show->id, "Site id")->required();
  show_cmd->add_flag("--json", show->json, "Print the site as JSON (its scene left out)");
  AddServerOptions(show_cmd, show->server);
  show_cmd->callback([show] {
    v1::SiteInfo info = ValueOrFail(ConnectOrFail(show->server).GetSite(show->id));
    info.clear_scene();
    if (show->json) {
      fmt::print("{}\n", ToJson(info, JsonLayout::kIndented));
    } else {
      PrintSite(info);
    }
  });
}

// fenestra site rm
void AddSiteRm(CLI::App* site) {
  struct RmArgs {
    ServerOptions server;
    std::string id;
  };
  auto rm = std::make_shared<RmArgs>();
  CLI::App* rm_cmd = site->add_subcommand("rm", "Delete a site");
  rm_cmd->add_option("ID", rm->id, "Site id")->required();
  AddServerOptions(rm_cmd, rm->server);
  rm_cmd->callback([rm] {
    if (absl::Status st = ConnectOrFail(rm->server).DeleteSite(rm->id); !st.ok()) Fail(st);
    fmt::print("{} deleted\n", rm->id);
  });
}

}  // namespace

void AddSiteCommand(CLI::App& app) {
  CLI::App* site = app.add_subcommand("site", "Sites registered with fenestrad (outdoor matrices)");
  site->require_subcommand(1);
  AddSiteAdd(site);
  AddSiteList(site);
  AddSiteShow(site);
  AddSiteRm(site);
}

}  // namespace fenestra
