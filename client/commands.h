#pragma once

#include <CLI/CLI.hpp>

namespace fenestra {

// Each adds one subcommand (and its callback) to the CLI.
void AddSceneCommand(CLI::App& app);
void AddSkyCommand(CLI::App& app);
void AddDcCommand(CLI::App& app);
void AddOptimizeCommand(CLI::App& app);

}  // namespace fenestra
