#pragma once

#include <CLI/CLI.hpp>

namespace fenestra {

// Each adds one subcommand (and its callback) to the CLI.
void AddSceneCommand(CLI::App& app);
void AddSkyCommand(CLI::App& app);
void AddDcCommand(CLI::App& app);
void AddConvergenceCommand(CLI::App& app);
void AddOptimizeCommand(CLI::App& app);
// Clients of fenestrad (client/site_command.cpp, client/job_command.cpp).
void AddSiteCommand(CLI::App& app);
void AddJobCommand(CLI::App& app);

}  // namespace fenestra
