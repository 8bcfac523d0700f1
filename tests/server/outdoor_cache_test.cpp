#include "server/outdoor_cache.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "server/store/store.h"

namespace fenestra {
namespace {

using ::testing::HasSubstr;
namespace fs = std::filesystem;

OutdoorMatrix TestMatrix(const std::string& key) {
  OutdoorMatrix m;
  m.key = key;
  m.coefficients = Matrix::Random(288 + 146, 146).cwiseAbs();
  m.standard_error = 0.01 * m.coefficients;
  for (int b = 0; b < 4; ++b) m.batches.push_back(Matrix::Random(288 + 146, 146).cwiseAbs());
  m.basis_cells = 288;
  m.paths = 20000;
  m.bounces = 30;
  m.seed = 7;
  m.wall_seconds = 1.5;
  m.backend = "embree-cpu";
  return m;
}

std::string FreshDir(const std::string& name) {
  const std::string dir = testing::TempDir() + "/outdoor_cache_test_" + name;
  fs::remove_all(dir);
  return dir;
}

std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(OutdoorCacheTest, EncodeDecodeRoundTrip) {
  const OutdoorMatrix m = TestMatrix("abc");
  absl::StatusOr<OutdoorMatrix> back = DecodeOutdoorMatrix(EncodeOutdoorMatrix(m));
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(back->key, "abc");
  EXPECT_TRUE(back->coefficients == m.coefficients);
  EXPECT_TRUE(back->standard_error == m.standard_error);
  ASSERT_EQ(back->batches.size(), 4u);
  for (int b = 0; b < 4; ++b) EXPECT_TRUE(back->batches[b] == m.batches[b]);
  EXPECT_EQ(back->paths, 20000);
  EXPECT_EQ(back->seed, 7u);
  EXPECT_EQ(back->backend, "embree-cpu");
  EXPECT_EQ(back->parts, (WindowParts{1, 1}));
  // A window in parts keeps them
  OutdoorMatrix split = TestMatrix("def");
  split.coefficients = Matrix::Random(288 * 6 + 146, 146).cwiseAbs();
  split.standard_error = 0.01 * split.coefficients;
  for (Matrix& b : split.batches) b = Matrix::Random(288 * 6 + 146, 146).cwiseAbs();
  split.parts = {3, 2};
  absl::StatusOr<OutdoorMatrix> split_back = DecodeOutdoorMatrix(EncodeOutdoorMatrix(split));
  ASSERT_TRUE(split_back.ok()) << split_back.status();
  EXPECT_EQ(split_back->parts, (WindowParts{3, 2}));
  EXPECT_TRUE(split_back->coefficients == split.coefficients);
  // Several windows, each split automatically (parts 0 x 0), keep that: the job's indoor
  // stage asks for the same
  OutdoorMatrix several = TestMatrix("ghi");
  several.coefficients = Matrix::Random(2 * 288 * 12 + 292, 146).cwiseAbs();
  several.standard_error = 0.01 * several.coefficients;
  for (Matrix& b : several.batches) b = Matrix::Random(2 * 288 * 12 + 292, 146).cwiseAbs();
  several.parts = {0, 0};
  absl::StatusOr<OutdoorMatrix> several_back = DecodeOutdoorMatrix(EncodeOutdoorMatrix(several));
  ASSERT_TRUE(several_back.ok()) << several_back.status();
  EXPECT_EQ(several_back->parts, (WindowParts{0, 0}));
}

TEST(OutdoorCacheTest, FlippedByteOrTruncationIsDataLoss) {
  std::string bytes = EncodeOutdoorMatrix(TestMatrix("abc"));
  std::string flipped = bytes;
  flipped[bytes.size() / 2] ^= 0x40;
  absl::Status status = DecodeOutdoorMatrix(flipped).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(status.message(), HasSubstr("checksum"));
  EXPECT_EQ(DecodeOutdoorMatrix(bytes.substr(0, bytes.size() - 8)).status().code(),
            absl::StatusCode::kDataLoss);
  EXPECT_EQ(DecodeOutdoorMatrix("not a cache file").status().code(), absl::StatusCode::kDataLoss);
}

TEST(OutdoorCacheTest, PutWritesAFileThatLoadReadsBackAndCorruptFilesAreDiscarded) {
  const std::string dir = FreshDir("load");
  const OutdoorMatrix good = TestMatrix("good");
  {
    OutdoorCache cache(dir);
    ASSERT_TRUE(cache.Load().ok());
    ASSERT_TRUE(cache.Put(std::make_shared<OutdoorMatrix>(good)).ok());
    ASSERT_TRUE(cache.Put(std::make_shared<OutdoorMatrix>(TestMatrix("bad"))).ok());
    EXPECT_FALSE(cache.LoadedFromDisk("good"));
    // Corrupt one file on disk
    const std::string path = cache.PathFor("bad");
    std::string bytes = ReadAll(path);
    bytes[bytes.size() - 100] ^= 0x01;
    std::ofstream(path, std::ios::binary) << bytes;
  }
  OutdoorCache cache(dir);
  absl::StatusOr<OutdoorCache::LoadReport> report = cache.Load();
  ASSERT_TRUE(report.ok()) << report.status();
  EXPECT_EQ(report->loaded, 1);
  ASSERT_EQ(report->discarded.size(), 1u);
  EXPECT_THAT(report->discarded[0], HasSubstr("checksum"));
  ASSERT_NE(cache.Find("good"), nullptr);
  EXPECT_TRUE(cache.LoadedFromDisk("good"));
  EXPECT_TRUE(cache.Find("good")->coefficients == good.coefficients);
  EXPECT_EQ(cache.Find("bad"), nullptr);
  EXPECT_FALSE(fs::exists(cache.PathFor("bad")));
}

TEST(OutdoorCacheTest, ConcurrentRequestsForOneKeyComputeOnce) {
  OutdoorCache cache(FreshDir("once"));
  ASSERT_TRUE(cache.Load().ok());
  std::atomic<int> computations = 0;
  auto compute = [&]() -> absl::StatusOr<OutdoorMatrix> {
    ++computations;
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    return TestMatrix("k");
  };
  std::vector<std::thread> threads;
  std::atomic<int> computed = 0;
  for (int i = 0; i < 4; ++i) {
    threads.emplace_back([&] {
      absl::StatusOr<OutdoorCache::Lookup> lookup = cache.GetOrCompute("k", compute);
      ASSERT_TRUE(lookup.ok());
      EXPECT_EQ(lookup->matrix->key, "k");
      computed += lookup->computed;
    });
  }
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(computations, 1);
  EXPECT_EQ(computed, 1);
}

TEST(OutdoorCacheTest, FailuresAreNotCachedAndWaitsCanBeCancelled) {
  OutdoorCache cache(FreshDir("fail"));
  ASSERT_TRUE(cache.Load().ok());
  auto failing = []() -> absl::StatusOr<OutdoorMatrix> {
    return absl::InvalidArgumentError("no window");
  };
  EXPECT_EQ(cache.GetOrCompute("k", failing).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(cache.Find("k"), nullptr);

  // A waiter gives up when cancelled while another caller computes
  std::atomic<bool> release = false;
  std::thread slow([&] {
    (void)cache.GetOrCompute("slow", [&]() -> absl::StatusOr<OutdoorMatrix> {
      while (!release) std::this_thread::sleep_for(std::chrono::milliseconds(10));
      return TestMatrix("slow");
    });
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  absl::Status waited = cache.GetOrCompute("slow", failing, [] { return true; }).status();
  EXPECT_EQ(waited.code(), absl::StatusCode::kCancelled);
  release = true;
  slow.join();
  EXPECT_NE(cache.Find("slow"), nullptr);
}

TEST(OutdoorCacheTest, MatricesNoOneHoldsAreReadBackFromTheirFiles) {
  const std::string dir = FreshDir("held");
  OutdoorCache cache(dir);
  ASSERT_TRUE(cache.Load().ok());
  const OutdoorMatrix m = TestMatrix("k");
  std::weak_ptr<const OutdoorMatrix> held;
  {
    auto shared = std::make_shared<const OutdoorMatrix>(m);
    held = shared;
    ASSERT_TRUE(cache.Put(shared).ok());
    EXPECT_EQ(cache.Find("k"), shared);  // while held, the same object
  }
  EXPECT_TRUE(held.expired());  // the cache keeps no matrix alive
  EXPECT_TRUE(cache.Contains("k"));
  std::shared_ptr<const OutdoorMatrix> read = cache.Find("k");
  ASSERT_NE(read, nullptr);
  EXPECT_TRUE(read->coefficients == m.coefficients);
  EXPECT_FALSE(cache.LoadedFromDisk("k"));  // this process computed it
  // A file that turned corrupt since is dropped
  read.reset();
  std::ofstream(cache.PathFor("k"), std::ios::binary | std::ios::trunc) << "garbage";
  EXPECT_EQ(cache.Find("k"), nullptr);
  EXPECT_FALSE(cache.Contains("k"));
  EXPECT_FALSE(fs::exists(cache.PathFor("k")));
}

// With a memory bound, the matrices used last stay in memory though no one holds them, the
// least recently used dropped first; eviction drops them from memory too.
TEST(OutdoorCacheTest, TheMatricesUsedLastStayInMemoryUpToTheBound) {
  const std::string dir = FreshDir("recent");
  const OutdoorMatrix a = TestMatrix("a"), b = TestMatrix("b");
  int64_t values = a.coefficients.size() + a.standard_error.size();
  for (const Matrix& batch : a.batches) values += batch.size();
  const int64_t one = static_cast<int64_t>(sizeof(double)) * values;
  OutdoorCache cache(dir, nullptr, /*memory_bytes=*/one * 3 / 2);  // room for one
  ASSERT_TRUE(cache.Load().ok());
  std::weak_ptr<const OutdoorMatrix> held_a;
  {
    auto shared = std::make_shared<const OutdoorMatrix>(a);
    held_a = shared;
    ASSERT_TRUE(cache.Put(shared).ok());
  }
  EXPECT_FALSE(held_a.expired());  // kept, though no one holds it
  // Its file is not read again: a corrupt file goes unnoticed while the matrix is in memory
  std::ofstream(cache.PathFor("a"), std::ios::binary | std::ios::trunc) << "garbage";
  EXPECT_EQ(cache.Find("a"), held_a.lock());
  EXPECT_THAT(cache.KeysInMemory(), testing::ElementsAre("a"));

  ASSERT_TRUE(cache.Put(std::make_shared<const OutdoorMatrix>(b)).ok());
  EXPECT_TRUE(held_a.expired());  // no room for two: a dropped
  EXPECT_THAT(cache.KeysInMemory(), testing::ElementsAre("b"));
  EXPECT_EQ(cache.Find("a"), nullptr);  // read back from its file, found corrupt
  EXPECT_FALSE(cache.Contains("a"));

  // A matrix only the bound keeps can be evicted, from disk and memory
  std::weak_ptr<const OutdoorMatrix> held_b = cache.Find("b");
  EXPECT_FALSE(held_b.expired());
  ASSERT_TRUE(cache.EvictOne());
  EXPECT_FALSE(cache.Contains("b"));
  EXPECT_FALSE(fs::exists(cache.PathFor("b")));
  EXPECT_TRUE(held_b.expired());
  EXPECT_THAT(cache.KeysInMemory(), testing::IsEmpty());
}

TEST(OutdoorCacheTest, EvictionTakesTheLeastRecentlyUsedMatrixNoOneUses) {
  const std::string dir = FreshDir("evict");
  OutdoorCache cache(dir);
  ASSERT_TRUE(cache.Load().ok());
  for (const char* key : {"a", "b", "c", "d"}) {
    ASSERT_TRUE(cache.Put(std::make_shared<const OutdoorMatrix>(TestMatrix(key))).ok());
  }
  std::shared_ptr<const OutdoorMatrix> held_c = cache.Find("c");      // a job holds c
  (void)cache.Find("a");                                              // a used last
  cache.SetInUse([](const std::string& key) { return key == "b"; });  // a site uses b
  // Least recently used first: d, then a; never b (in use) or c (held)
  ASSERT_TRUE(cache.EvictOne());
  EXPECT_FALSE(cache.Contains("d"));
  EXPECT_FALSE(fs::exists(cache.PathFor("d")));
  ASSERT_TRUE(cache.EvictOne());
  EXPECT_FALSE(cache.Contains("a"));
  EXPECT_FALSE(cache.EvictOne());
  EXPECT_TRUE(cache.Contains("b"));
  EXPECT_TRUE(cache.Contains("c"));
}

TEST(OutdoorCacheTest, WithoutRoomAMatrixIsKeptInMemory) {
  const std::string dir = FreshDir("no_room");
  std::unique_ptr<DataDir> data_dir = *DataDir::Open(dir, 1000);
  OutdoorCache cache(data_dir->outdoor_dir().string(), data_dir.get());
  ASSERT_TRUE(cache.Load().ok());
  const absl::Status put = cache.Put(std::make_shared<const OutdoorMatrix>(TestMatrix("k")));
  EXPECT_EQ(put.code(), absl::StatusCode::kResourceExhausted);
  EXPECT_FALSE(fs::exists(cache.PathFor("k")));
  ASSERT_NE(cache.Find("k"), nullptr);
  EXPECT_FALSE(cache.EvictOne());  // nothing on disk to evict
}

// Two processes' caches on one store (the matrices table works on SQLite as on PostgreSQL).
TEST(OutdoorCacheTest, InAStoreMatricesAreSharedCheckedAndTheLatestKeptInMemory) {
  const std::string dir = FreshDir("store");
  fs::create_directories(dir);
  absl::StatusOr<std::unique_ptr<Store>> store = OpenStoreUrl("sqlite:" + dir);
  ASSERT_TRUE(store.ok()) << store.status();
  const OutdoorMatrix a = TestMatrix("a"), b = TestMatrix("b");
  int64_t values = a.coefficients.size() + a.standard_error.size();
  for (const Matrix& batch : a.batches) values += batch.size();
  const int64_t one = static_cast<int64_t>(sizeof(double)) * values;
  OutdoorCache cache(**store, /*memory_bytes=*/one * 3 / 2);  // room for one
  ASSERT_TRUE(cache.Load().ok());
  ASSERT_TRUE(cache.Put(std::make_shared<const OutdoorMatrix>(a)).ok());
  ASSERT_TRUE(cache.Put(std::make_shared<const OutdoorMatrix>(b)).ok());
  EXPECT_THAT(cache.KeysInMemory(), testing::ElementsAre("b"));  // a dropped: no room
  EXPECT_FALSE(cache.LoadedFromDisk("a"));
  std::shared_ptr<const OutdoorMatrix> read = cache.Find("a");  // read back from the store
  ASSERT_NE(read, nullptr);
  EXPECT_TRUE(read->coefficients == a.coefficients);
  EXPECT_THAT(cache.KeysInMemory(), testing::ElementsAre("a"));

  // Another process's cache finds them in the store, and tells so
  OutdoorCache other(**store, one * 3);
  absl::StatusOr<OutdoorCache::LoadReport> loaded = other.Load();
  ASSERT_TRUE(loaded.ok()) << loaded.status();
  EXPECT_EQ(loaded->loaded, 2);
  EXPECT_TRUE(other.Contains("b"));
  ASSERT_NE(other.Find("b"), nullptr);
  EXPECT_TRUE(other.LoadedFromDisk("b"));
  EXPECT_TRUE(
      other
          .GetOrCompute(
              "b",
              [] { return absl::StatusOr<OutdoorMatrix>(absl::InternalError("computed again")); })
          ->matrix != nullptr);
  EXPECT_FALSE(other.EvictOne());  // the store keeps every matrix

  // A stored matrix that does not decode (another build's format) is dropped, then traced
  // again
  ASSERT_TRUE((*store)->PutMatrix("c", "not a matrix").ok());
  OutdoorCache third(**store, one);
  EXPECT_EQ(third.Find("c"), nullptr);
  EXPECT_FALSE(third.Contains("c"));
  absl::StatusOr<OutdoorCache::Lookup> traced =
      third.GetOrCompute("c", [] { return absl::StatusOr<OutdoorMatrix>(TestMatrix("c")); });
  ASSERT_TRUE(traced.ok()) << traced.status();
  EXPECT_TRUE(traced->computed);
  EXPECT_TRUE(*(*store)->HasMatrix("c"));
}

}  // namespace
}  // namespace fenestra
