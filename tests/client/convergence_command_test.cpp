// fenestra convergence, run as a user would.
#include <expat.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "tests/client/cli_run.h"

namespace fenestra {
namespace {

namespace fs = std::filesystem;

using ConvergenceCommandTest = CliTest;

const std::string kLightwell = kExamples + "/lightwell/scene.json";
const std::string kRadiance =
    FENESTRA_SOURCE_DIR "/tests/data/reference/lightwell_dc_radiance_ab30_2e7.txt";

struct Csv {
  std::vector<std::string> header;
  std::vector<std::map<std::string, double>> rows;
};

Csv ReadCsv(const fs::path& path) {
  std::ifstream in(path);
  Csv csv;
  std::string line, field;
  std::getline(in, line);
  for (std::stringstream s(line); std::getline(s, field, ',');) csv.header.push_back(field);
  while (std::getline(in, line)) {
    std::map<std::string, double> row;
    size_t column = 0;
    for (std::stringstream s(line); std::getline(s, field, ','); ++column) {
      EXPECT_LT(column, csv.header.size()) << line;
      if (column < csv.header.size()) row[csv.header[column]] = std::stod(field);
    }
    EXPECT_EQ(column, csv.header.size()) << line;
    csv.rows.push_back(row);
  }
  return csv;
}

// What a parse of the SVG saw: element counts, the class of each element, the text.
struct Svg {
  bool well_formed = false;
  std::string root, xmlns;
  std::map<std::string, int> elements, classes;
  std::string text;
};

Svg ParseSvg(const fs::path& path) {
  std::ifstream in(path);
  const std::string xml{std::istreambuf_iterator<char>(in), {}};
  Svg svg;
  XML_Parser parser = XML_ParserCreate(nullptr);
  XML_SetUserData(parser, &svg);
  XML_SetElementHandler(
      parser,
      [](void* data, const XML_Char* name, const XML_Char** attributes) {
        Svg& s = *static_cast<Svg*>(data);
        if (s.root.empty()) s.root = name;
        ++s.elements[name];
        for (int a = 0; attributes[a] != nullptr; a += 2) {
          if (std::string(attributes[a]) == "class") ++s.classes[attributes[a + 1]];
          if (std::string(attributes[a]) == "xmlns") s.xmlns = attributes[a + 1];
        }
      },
      [](void*, const XML_Char*) {});
  XML_SetCharacterDataHandler(parser, [](void* data, const XML_Char* text, int length) {
    static_cast<Svg*>(data)->text.append(text, length);
  });
  svg.well_formed =
      XML_Parse(parser, xml.data(), static_cast<int>(xml.size()), /*isFinal=*/1) == XML_STATUS_OK;
  EXPECT_TRUE(svg.well_formed) << XML_ErrorString(XML_GetErrorCode(parser)) << " at line "
                               << XML_GetCurrentLineNumber(parser);
  XML_ParserFree(parser);
  return svg;
}

// How far the standard errors may stray from 1/sqrt(paths): they are estimated from the paths
// themselves, and in the light well rare paths carry much of the light, so at these small
// counts an estimate moves by up to about +-50% from seed to seed.
constexpr double kScalingFactor = 2;

// The relative standard error times sqrt(paths) of every row, divided by the first row's:
// 1 when the error falls exactly as 1/sqrt(paths).
std::vector<double> ScaledErrors(const Csv& csv) {
  std::vector<double> scaled;
  for (const auto& row : csv.rows) {
    scaled.push_back(
        row.at("max_rel_se") * std::sqrt(row.at("paths_per_sensor")) /
        (csv.rows[0].at("max_rel_se") * std::sqrt(csv.rows[0].at("paths_per_sensor"))));
  }
  return scaled;
}

TEST_F(ConvergenceCommandTest, TwoStageAgainstRadianceWritesTableAndPlot) {
  const fs::path prefix = dir_ / "lightwell";
  const CliRun run = Fenestra("convergence " + kLightwell +
                              " --method two-stage --outdoor-paths 500000 --indoor-paths 5000 "
                              "--max-runs 4 --reference " +
                              kRadiance + " -o " + prefix.string());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("max_rel_se"), std::string::npos) << run.output;  // the table

  // Doubling paths, errors falling as 1/sqrt(paths) within kScalingFactor
  const Csv csv = ReadCsv(prefix.string() + ".csv");
  EXPECT_EQ(csv.header, (std::vector<std::string>{"paths_per_sensor", "outdoor_paths", "rays",
                                                  "wall_seconds", "max_rel_se", "mean_rel_se",
                                                  "max_rel_diff", "mean_rel_diff", "flux_l1"}));
  ASSERT_EQ(csv.rows.size(), 4u);
  for (size_t k = 1; k < csv.rows.size(); ++k) {
    const auto &row = csv.rows[k], &previous = csv.rows[k - 1];
    EXPECT_EQ(row.at("paths_per_sensor"), 2 * previous.at("paths_per_sensor"));
    // The outdoor paths are a whole number per window cell (4 x 3 parts x 288 cells)
    EXPECT_NEAR(row.at("outdoor_paths"), 2 * previous.at("outdoor_paths"), 3456);
    EXPECT_GT(row.at("rays"), previous.at("rays"));
  }
  EXPECT_LT(csv.rows.back().at("max_rel_se"), csv.rows.front().at("max_rel_se") / 2);
  for (const double s : ScaledErrors(csv)) {
    EXPECT_GT(s, 1 / kScalingFactor);
    EXPECT_LT(s, kScalingFactor);
  }
  for (const auto& row : csv.rows) {
    EXPECT_GT(row.at("wall_seconds"), 0);
    EXPECT_LE(row.at("mean_rel_se"), row.at("max_rel_se"));
    EXPECT_LE(row.at("mean_rel_diff"), row.at("max_rel_diff"));
    EXPECT_GE(row.at("mean_rel_diff"), 0);
    EXPECT_GT(row.at("flux_l1"), 0);
    EXPECT_TRUE(std::isfinite(row.at("flux_l1")));
  }

  // A plot of the five series and the 1/sqrt(t) line
  Svg svg = ParseSvg(prefix.string() + ".svg");
  ASSERT_TRUE(svg.well_formed);
  EXPECT_EQ(svg.root, "svg");
  EXPECT_EQ(svg.xmlns, "http://www.w3.org/2000/svg");
  EXPECT_EQ(svg.elements.at("title"), 1);
  EXPECT_EQ(svg.classes["series-line"], 5);
  EXPECT_EQ(svg.elements.at("circle"), 5 * 4);
  EXPECT_EQ(svg.classes["sqrt-line"], 1);
  EXPECT_EQ(svg.classes["x-label"], 1);
  EXPECT_EQ(svg.classes["y-label"], 1);
  for (const char* text : {"wall time [s]", "relative error", "largest relative SE",
                           "flux-weighted L1 of D", "lightwell, two-stage"}) {
    EXPECT_NE(svg.text.find(text), std::string::npos) << text;
  }
}

TEST_F(ConvergenceCommandTest, OneStageWithoutReference) {
  const fs::path prefix = dir_ / "one";
  const CliRun run =
      Fenestra("convergence " + kLightwell + " --no-weight-windows --paths 4000 --max-runs 4 -o " +
               prefix.string());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const Csv csv = ReadCsv(prefix.string() + ".csv");
  EXPECT_EQ(csv.header.size(), 6u);
  ASSERT_EQ(csv.rows.size(), 4u);
  for (size_t k = 0; k < csv.rows.size(); ++k) {
    EXPECT_EQ(csv.rows[k].at("paths_per_sensor"), 4000 << k);
    EXPECT_EQ(csv.rows[k].at("outdoor_paths"), 0);
  }
  for (const double s : ScaledErrors(csv)) {
    EXPECT_GT(s, 1 / kScalingFactor);
    EXPECT_LT(s, kScalingFactor);
  }
  Svg svg = ParseSvg(prefix.string() + ".svg");
  EXPECT_EQ(svg.classes["series-line"], 2);
  EXPECT_EQ(svg.classes["sqrt-line"], 1);
}

TEST_F(ConvergenceCommandTest, TimeLimitEndsTheRuns) {
  const CliRun run = Fenestra("convergence " + kLightwell + " --paths 2000 --max-seconds 1e-6 -o " +
                              (dir_ / "x").string());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("stopped after 1 run,"), std::string::npos) << run.output;
  EXPECT_EQ(ReadCsv(dir_ / "x.csv").rows.size(), 1u);
}

TEST_F(ConvergenceCommandTest, ReferenceOfAnotherSceneIsRefused) {
  const CliRun run = Fenestra("convergence " + kExamples + "/city_office/scene.json --reference " +
                              kRadiance + " -o " + (dir_ / "x").string());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.output.find("--reference: " + kRadiance +
                            " has 3 x 146 entries, the scene needs 9 sensors x 146 bins"),
            std::string::npos)
      << run.output;
  EXPECT_TRUE(fs::is_empty(dir_));
}

}  // namespace
}  // namespace fenestra
