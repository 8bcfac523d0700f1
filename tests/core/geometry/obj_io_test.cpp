#include "core/geometry/obj_io.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "core/geometry/scene.h"

namespace fenestra {
namespace {

TEST(ObjIoTest, ExportRoundTripsWithOneGroupPerMaterial) {
  absl::StatusOr<Scene> scene = LoadScene(FENESTRA_SOURCE_DIR "/examples/city_office/scene.json");
  ASSERT_TRUE(scene.ok()) << scene.status();
  const TriangleMesh mesh = AssembleMesh(*scene, DefaultDesign(*scene));
  const std::string path =
      (std::filesystem::temp_directory_path() / "fenestra_obj_io_test.obj").string();
  ASSERT_TRUE(WriteObj(path, mesh, scene->materials).ok());
  absl::StatusOr<ObjTriangles> read = ReadObj(path);
  std::filesystem::remove(path);
  ASSERT_TRUE(read.ok()) << read.status();
  ASSERT_EQ(read->group.size(), mesh.TriangleCount());
  // Groups come out in material order; each triangle keeps its vertices
  std::map<std::string, size_t> per_group;
  for (const std::string& g : read->group) ++per_group[g];
  std::map<std::string, size_t> per_material;
  for (uint32_t m : mesh.material) ++per_material[scene->materials[m].name];
  EXPECT_EQ(per_group, per_material);
  EXPECT_EQ(per_group.size(), 4u);
}

TEST(ObjIoTest, FailedWriteLeavesNoFile) {
  TriangleMesh mesh;
  const absl::Status status = WriteObj("/nonexistent-dir/x.obj", mesh, {});
  EXPECT_FALSE(status.ok());
  EXPECT_FALSE(std::filesystem::exists("/nonexistent-dir/x.obj"));
}

}  // namespace
}  // namespace fenestra
