#include "server/data_dir.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace fenestra {
namespace {

using ::testing::HasSubstr;
namespace fs = std::filesystem;

fs::path FreshDataDir(const std::string& name) {
  const fs::path dir = fs::path(testing::TempDir()) / ("data_dir_test_" + name);
  fs::remove_all(dir);
  return dir;
}

TEST(DataDirTest, OpenCreatesTheFoldersAndRemovesTemporaries) {
  const fs::path root = FreshDataDir("open");
  fs::create_directories(root / "weather");
  std::ofstream(root / "weather" / "a.epw.tmp.12.3") << "partial";
  std::ofstream(root / "weather" / "b.epw") << "whole";
  absl::StatusOr<std::unique_ptr<DataDir>> dir = DataDir::Open(root, 1 << 20);
  ASSERT_TRUE(dir.ok()) << dir.status();
  EXPECT_TRUE(fs::is_directory(root / "outdoor"));
  EXPECT_EQ((*dir)->temporaries_removed(), 1);
  EXPECT_FALSE(fs::exists(root / "weather" / "a.epw.tmp.12.3"));
  EXPECT_TRUE(fs::exists(root / "weather" / "b.epw"));
  EXPECT_FALSE((*dir)->full_at_start());
  EXPECT_EQ((*dir)->UsedBytes(), 5);
}

TEST(DataDirTest, OneDaemonPerFolder) {
  const fs::path root = FreshDataDir("lock");
  {
    absl::StatusOr<std::unique_ptr<DataDir>> first = DataDir::Open(root, 1 << 20);
    ASSERT_TRUE(first.ok()) << first.status();
    absl::StatusOr<std::unique_ptr<DataDir>> second = DataDir::Open(root, 1 << 20);
    EXPECT_EQ(second.status().code(), absl::StatusCode::kFailedPrecondition);
    EXPECT_THAT(second.status().message(),
                HasSubstr("the data directory " + root.string() + " is in use by another process"));
  }
  // Released with the first
  EXPECT_TRUE(DataDir::Open(root, 1 << 20).ok());
}

TEST(DataDirTest, MakeRoomEvictsThenRefusesNamingTheLimit) {
  const fs::path root = FreshDataDir("room");
  std::unique_ptr<DataDir> dir = *DataDir::Open(root, 1000);
  std::ofstream(root / "outdoor" / "old.omx") << std::string(600, 'x');
  EXPECT_TRUE(dir->MakeRoom(400).ok());
  // Over the limit with nothing to evict
  absl::Status refused = dir->MakeRoom(401);
  EXPECT_EQ(refused.code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(refused.message(), HasSubstr("holds 600 bytes and this needs 401 more, above its "
                                           "limit max_data_dir_bytes = 1000"));
  EXPECT_THAT(refused.message(), testing::Not(HasSubstr(root.string())));
  // The evictor frees what it may
  int evictions = 0;
  dir->SetEvictor([&] {
    ++evictions;
    return fs::remove(root / "outdoor" / "old.omx");
  });
  EXPECT_TRUE(dir->MakeRoom(401).ok());
  EXPECT_EQ(evictions, 1);
  EXPECT_FALSE(dir->MakeRoom(1001).ok());
  EXPECT_EQ(evictions, 2);
}

TEST(DataDirTest, WriteFileDurablyLeavesNoTemporary) {
  const fs::path root = FreshDataDir("write");
  fs::create_directories(root);
  ASSERT_TRUE(WriteFileDurably(root / "f", "content").ok());
  std::ifstream in(root / "f");
  std::string content;
  in >> content;
  EXPECT_EQ(content, "content");
  EXPECT_EQ(std::distance(fs::directory_iterator(root), fs::directory_iterator()), 1);
  // A folder that does not exist: an error without its path
  absl::Status failed = WriteFileDurably(root / "missing" / "f", "content");
  EXPECT_EQ(failed.code(), absl::StatusCode::kInternal);
  EXPECT_THAT(failed.message(), testing::Not(HasSubstr(root.string())));
  EXPECT_EQ(StorageFullError().code(), absl::StatusCode::kResourceExhausted);
}

TEST(UploadStoreTest, AFileIsStoredOnceAndRemovedWithItsLastReference) {
  const fs::path root = FreshDataDir("uploads");
  std::unique_ptr<DataDir> dir = *DataDir::Open(root, 1 << 20);
  UploadStore uploads(*dir, dir->weather_dir(), "epw");
  absl::StatusOr<std::string> a = uploads.Add("weather a");
  absl::StatusOr<std::string> again = uploads.Add("weather a");
  absl::StatusOr<std::string> b = uploads.Add("weather b");
  ASSERT_TRUE(a.ok() && again.ok() && b.ok());
  EXPECT_EQ(*a, *again);
  EXPECT_NE(*a, *b);
  EXPECT_EQ(fs::path(*a).parent_path(), dir->weather_dir());
  EXPECT_EQ(fs::path(*a).extension(), ".epw");
  EXPECT_EQ(uploads.References(*a), 2);
  uploads.Ref(*a);
  uploads.Unref(*a);
  uploads.Unref(*a);
  EXPECT_TRUE(fs::exists(*a));
  uploads.Unref(*a);
  EXPECT_FALSE(fs::exists(*a));
  EXPECT_TRUE(fs::exists(*b));

  // At start: references counted from what the store holds, the rest removed
  UploadStore restarted(*dir, dir->weather_dir(), "epw");
  std::ofstream(dir->weather_dir() / "stray.epw") << "stray";
  restarted.Ref(*b);
  EXPECT_EQ(restarted.RemoveUnreferenced(), 1);
  EXPECT_TRUE(fs::exists(*b));
  EXPECT_FALSE(fs::exists(dir->weather_dir() / "stray.epw"));
}

TEST(UploadStoreTest, AnUploadOverTheLimitIsRefused) {
  const fs::path root = FreshDataDir("upload_limit");
  std::unique_ptr<DataDir> dir = *DataDir::Open(root, 100);
  UploadStore uploads(*dir, dir->weather_dir(), "epw");
  EXPECT_TRUE(uploads.Add(std::string(100, 'a')).ok());
  absl::StatusOr<std::string> refused = uploads.Add(std::string(10, 'b'));
  EXPECT_EQ(refused.status().code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(refused.status().message(), HasSubstr("max_data_dir_bytes = 100"));
  // Content already stored takes no room
  EXPECT_TRUE(uploads.Add(std::string(100, 'a')).ok());
}

}  // namespace
}  // namespace fenestra
