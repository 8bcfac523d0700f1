// fenestra sky: the annual sky matrix of a weather file (gendaymtx's Perez sky).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <iostream>
#include <memory>
#include <string>

#include "client/cli_util.h"
#include "client/commands.h"
#include "core/common/radiance_matrix.h"
#include "core/common/seconds.h"
#include "core/sky/epw.h"
#include "core/sky/sky_matrix.h"

namespace fenestra {

void AddSkyCommand(CLI::App& app) {
  struct SkyArgs {
    std::string epw, output, format = "ascii";
    int mf = 1;
    bool solar = false;
    bool treat_missing_as_zero = false;
    double ground_reflectance = 0.2;
  };
  auto args = std::make_shared<SkyArgs>();
  CLI::App* command = app.add_subcommand(
      "sky", "Build the sky matrix (rows = sky bins, 0 = ground; columns = time steps)");
  command->add_option("--epw", args->epw, "EnergyPlus weather file")->required();
  command->add_option("-o,--output", args->output, "Output matrix file")->required();
  command->add_option("--mf", args->mf, "Reinhart subdivision (1 = Tregenza, 146 bins)")
      ->capture_default_str();
  command->add_flag("--solar", args->solar,
                    "Broadband solar radiance instead of visible radiance (gendaymtx -O1)");
  command->add_option("--ground-reflectance", args->ground_reflectance, "Ground reflectance")
      ->capture_default_str();
  command->add_flag("--treat-missing-as-zero", args->treat_missing_as_zero,
                    "Read missing or negative direct/diffuse radiation as 0 instead of failing");
  command->add_option("--format", args->format, "Matrix format")
      ->check(CLI::IsMember({"ascii", "float"}))
      ->capture_default_str();
  command->callback([args] {
    const auto start = std::chrono::steady_clock::now();
    const EpwData weather =
        ValueOrFail(ReadEpw(args->epw, {.treat_missing_as_zero = args->treat_missing_as_zero}));
    if (weather.replaced_radiation_values > 0) {
      std::cerr << fmt::format("warning: {}: {} missing or negative radiation values read as 0\n",
                               args->epw, weather.replaced_radiation_values);
    }
    const SkyMatrixOptions options{
        .mf = args->mf,
        .quantity = args->solar ? SkyQuantity::kSolar : SkyQuantity::kVisible,
        .ground_reflectance = args->ground_reflectance};
    const SkyMatrix sky = ValueOrFail(BuildSkyMatrix(weather, options));
    if (sky.direct_with_sun_down_steps > 0) {
      std::cerr << fmt::format(
          "warning: {}: {} steps have direct radiation while the sun is below the horizon\n",
          args->epw, sky.direct_with_sun_down_steps);
    }
    const absl::Status written =
        WriteRadianceMatrix(args->output, sky.radiance,
                            args->format == "float" ? MatrixFormat::kFloat : MatrixFormat::kAscii);
    if (!written.ok()) Fail(written);
    const double seconds = SecondsSince(start);
    fmt::print("sky: {} steps ({} daytime), {} bins (MF {}, {}), wrote {} in {:.2f} s\n",
               sky.steps.size(), sky.daytime_steps, sky.radiance.rows(), args->mf,
               args->solar ? "solar" : "visible", args->output, seconds);
  });
}

}  // namespace fenestra
