// fenestra scene import, run as a user would: a public Radiance model and a public Honeybee
// model (tests/data/models/, sources in their READMEs) become scenes that export and import
// back unchanged, that `fenestra dc` traces and that, given a blind, run an optimization; a
// Honeybee model of two windows exports, imports back and traces too.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <tuple>

#include "client/cli_util.h"
#include "core/geometry/scene.h"
#include "tests/client/cli_run.h"
#include "tests/core/geometry/hbjson_test_models.h"

namespace fenestra {
namespace {

using SceneImportTest = CliTest;

const std::string kModels = FENESTRA_SOURCE_DIR "/tests/data/models";
const std::string kWeather = kExamples + "/weather/URY_Montevideo.865800_IWEC.epw";

// The tutorial room's files, materials first, and its outdoor context.
std::string TutorialRoomArgs() {
  const std::string m = kModels + "/matrix_tutorial_room/";
  std::string args = m + "materials.rad";
  for (const char* o : {"Ceiling", "Floor", "InteriorWall", "Glazing"}) {
    args += " " + m + "objects/" + o + ".rad";
  }
  for (const char* o : {"ExteriorWalls", "Ground"})
    args += " --context " + m + "objects/" + o + ".rad";
  return args + " --pts " + m + "points.txt";
}

// Imports the model `import_args` name into DIR/scene.json, which must be a room; exports it as
// a Radiance model and imports that again (the same scene file expected); traces it by the
// one-stage method with `paths` paths per sensor. Returns the scene file and the import's and
// the trace's output.
struct Imported {
  std::string scene, import_output, dc_output;
};
Imported ImportExportAndTrace(const std::filesystem::path& dir, const std::string& import_args,
                              int paths) {
  Imported r{(dir / "scene.json").string(), "", ""};
  const CliRun imported =
      Fenestra("scene import " + import_args + " --weather " + kWeather + " -o " + r.scene);
  r.import_output = imported.output;
  EXPECT_EQ(imported.exit_code, 0) << imported.output;
  EXPECT_NE(imported.output.find("the scene is a room"), std::string::npos) << imported.output;
  const std::string model = (dir / "back.rad").string(), pts = (dir / "back.pts").string();
  const std::string again = (dir / "again.json").string();
  const CliRun exported =
      Fenestra("scene export " + r.scene + " --model " + model + " --pts " + pts);
  EXPECT_EQ(exported.exit_code, 0) << exported.output;
  const CliRun reimported = Fenestra("scene import " + model + " --pts " + pts + " -o " + again);
  EXPECT_EQ(reimported.exit_code, 0) << reimported.output;
  absl::StatusOr<v1::Scene> first = ReadSceneProto(r.scene), second = ReadSceneProto(again);
  EXPECT_TRUE(first.ok() && second.ok());
  if (first.ok() && second.ok()) {
    EXPECT_EQ(first->DebugString(), second->DebugString());
  }
  const CliRun dc = Fenestra("dc " + r.scene + " --method one-stage --paths " +
                             std::to_string(paths) + " -o " + (dir / "D.txt").string());
  r.dc_output = dc.output;
  EXPECT_EQ(dc.exit_code, 0) << dc.output;
  return r;
}

// Gives every window of `scene` a blind whose tilt is free, all of one group (one design),
// and runs a short tilt optimization on it.
void ExpectShortJobRuns(const std::filesystem::path& dir, const std::string& scene) {
  absl::StatusOr<v1::Scene> proto = ReadSceneProto(scene);
  ASSERT_TRUE(proto.ok()) << proto.status();
  v1::Material& slat = *proto->add_materials();
  slat.set_name("slat");
  slat.set_reflectance(0.7);
  for (v1::Window& w : *proto->mutable_windows()) {
    v1::VenetianBlind& blind = *w.mutable_blind();
    blind.set_material("slat");
    blind.set_group("blinds");
    for (const auto& [p, value, lo, hi] :
         {std::tuple{blind.mutable_tilt_rad(), 0.0, 0.0, 1.5},
          std::tuple{blind.mutable_slat_width_m(), 0.08, 0.08, 0.08},
          std::tuple{blind.mutable_slat_spacing_m(), 0.0, 0.0, 0.0},
          std::tuple{blind.mutable_slat_thickness_m(), 0.005, 0.005, 0.005}}) {
      p->set_value(value), p->set_min(lo), p->set_max(hi);
    }
  }
  ASSERT_TRUE(WriteJsonFile((dir / "room_blind.json").string(), *proto).ok());
  const std::string job = (dir / "job.json").string();
  {
    std::ofstream out(job);
    out << R"({"sceneFile": "room_blind.json",
      "sampling": {"outdoorPaths": 40000, "indoorPathsPerSensor": 1000, "batches": 4,
                   "windowColumns": 1, "windowRows": 1, "backend": "cpu"},
      "variables": [{"name": "alpha", "lower": 0, "upper": 1.5, "start": 0}],
      "objective": {"metric": "METRIC_UDI", "goal": "GOAL_MAXIMIZE"},
      "budget": {"maxEvaluations": 4}})";
  }
  const CliRun optimized = Fenestra("optimize --local " + job);
  ASSERT_EQ(optimized.exit_code, 0) << optimized.output;
  EXPECT_NE(optimized.output.find("best design: alpha="), std::string::npos) << optimized.output;
}

TEST_F(SceneImportTest, RadianceModelRunsADcAndAJob) {
  const Imported r = ImportExportAndTrace(dir_, TutorialRoomArgs(), 2000);
  EXPECT_NE(r.import_output.find("1 windows, 100 sensors"), std::string::npos) << r.import_output;
  EXPECT_NE(r.dc_output.find("sensor_99"), std::string::npos) << r.dc_output;
  ExpectShortJobRuns(dir_, r.scene);
}

// honeybee-schema's sample patient room (tests/data/models/patient_room), with a grid of 9
// sensors over its floor added to the file: it has none of its own.
TEST_F(SceneImportTest, HoneybeeSchemaSampleRunsADcAndAJob) {
  std::ifstream in(kModels + "/patient_room/model_complete_patient_room.hbjson");
  std::string json((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<std::pair<double, double>> desks;
  for (double x : {1.0, 2.5, 4.0}) {
    for (double y : {1.0, 5.0, 9.0}) desks.push_back({x, y});
  }
  const std::string none = R"("modifiers": [])";
  const size_t at = json.find(none);
  ASSERT_NE(at, std::string::npos);
  json.replace(at, none.size(),
               none + R"(, "sensor_grids": [)" + hbjson_test::Grid("beds", desks, 0.8) + "]");
  const std::string model = (dir_ / "patient_room.hbjson").string();
  std::ofstream(model) << json;
  ExpectShortJobRuns(dir_, ImportExportAndTrace(dir_, model, 500).scene);
}

// A Honeybee model of two windows and 640 sensors (tests/data/models/end_windows_hall).
TEST_F(SceneImportTest, HoneybeeModelOfTwoWindowsRunsADc) {
  const Imported r = ImportExportAndTrace(
      dir_, kModels + "/end_windows_hall/end_windows_hall.hbjson --grid core", 500);
  EXPECT_NE(r.import_output.find("2 windows, 640 sensors"), std::string::npos) << r.import_output;
}

TEST_F(SceneImportTest, BadArgumentsAndModelsAreRefusedWithNothingWritten) {
  const std::string scene = (dir_ / "x.json").string();
  for (const std::string& args :
       {kModels + "/matrix_tutorial_room/materials.rad -o " + scene,  // no --pts
        kModels + "/end_windows_hall/end_windows_hall.hbjson --pts p.txt -o " + scene,
        kModels + "/matrix_tutorial_room/room.rad --pts " + kModels +
            "/matrix_tutorial_room/points.txt -o " + scene}) {  // !xform
    const CliRun run = Fenestra("scene import " + args);
    EXPECT_NE(run.exit_code, 0) << run.output;
    EXPECT_NE(run.output.find("error:"), std::string::npos) << run.output;
    EXPECT_FALSE(std::filesystem::exists(scene)) << args;
  }
}

}  // namespace
}  // namespace fenestra
