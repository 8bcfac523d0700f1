#pragma once

#include <string>

namespace CLI {
class App;
}  // namespace CLI

namespace fenestra {

// Each adds one subcommand (and its callback) to the CLI.
void AddSceneCommand(CLI::App& app);
// fenestra scene import (client/scene_import_command.cpp), under `scene`.
void AddSceneImportCommand(CLI::App& scene);
void AddSkyCommand(CLI::App& app);
void AddDcCommand(CLI::App& app);
// fenestra glare (client/glare_command.cpp).
void AddGlareCommand(CLI::App& app);
void AddConvergenceCommand(CLI::App& app);
void AddOptimizeCommand(CLI::App& app);
// fenestra report (client/report_command.cpp).
void AddReportCommand(CLI::App& app);
// --sensor of `report` and `job report`: the temporal map's sensor.
void AddReportSensorOption(CLI::App* command, std::string& sensor);
// Clients of fenestrad (client/site_command.cpp, client/job_command.cpp).
void AddSiteCommand(CLI::App& app);
void AddJobCommand(CLI::App& app);

}  // namespace fenestra
