// fenestra: command-line client for scenes, sky matrices, daylight coefficients and jobs.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>

#include "client/commands.h"

int main(int argc, char** argv) {
  CLI::App app{"fenestra: daylight simulation and Venetian blind design"};
  app.require_subcommand(1);
  fenestra::AddSceneCommand(app);
  fenestra::AddSkyCommand(app);
  fenestra::AddDcCommand(app);
  fenestra::AddGlareCommand(app);
  fenestra::AddConvergenceCommand(app);
  fenestra::AddOptimizeCommand(app);
  fenestra::AddReportCommand(app);
  fenestra::AddSiteCommand(app);
  fenestra::AddJobCommand(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  return 0;
}
