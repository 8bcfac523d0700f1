#include "core/common/radiance_matrix.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

namespace fenestra {
namespace {

namespace fs = std::filesystem;

class RadianceMatrixTest : public testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("fenestra_radiance_matrix_" +
            std::string(testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

Matrix Example() {
  Matrix m(2, 3);
  m << 1.5, 0, 2.25e-3, 7, 123456.789, 1e-9;
  return m;
}

TEST_F(RadianceMatrixTest, OneComponentRoundTrips) {
  for (const MatrixFormat format : {MatrixFormat::kAscii, MatrixFormat::kFloat}) {
    ASSERT_TRUE(WriteRadianceMatrix(Path("m.mtx"), Example(), format).ok());
    absl::StatusOr<Matrix> read = ReadRadianceMatrix(Path("m.mtx"));
    ASSERT_TRUE(read.ok()) << read.status();
    EXPECT_TRUE(read->isApprox(Example(), 1e-7));
  }
}

// Three equal components, each "r g b" in a column, as dctimestep writes grey results
TEST_F(RadianceMatrixTest, ThreeComponentsAreWrittenAsGreyChannels) {
  ASSERT_TRUE(WriteRadianceMatrix(Path("m.mtx"), Example(), MatrixFormat::kAscii, 3).ok());
  std::ifstream in(Path("m.mtx"));
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_NE(text.str().find("NROWS=2\nNCOLS=3\nNCOMP=3\nFORMAT=ascii\n\n1.5 1.5 1.5\t0 0 0\t"),
            std::string::npos)
      << text.str();
  for (const MatrixFormat format : {MatrixFormat::kAscii, MatrixFormat::kFloat}) {
    ASSERT_TRUE(WriteRadianceMatrix(Path("m.mtx"), Example(), format, 3).ok());
    absl::StatusOr<std::vector<Matrix>> read = ReadRadianceMatrixComponents(Path("m.mtx"));
    ASSERT_TRUE(read.ok()) << read.status();
    ASSERT_EQ(read->size(), 3u);
    for (const Matrix& channel : *read) EXPECT_TRUE(channel.isApprox(Example(), 1e-7));
    // The one-component reader says why it refuses
    absl::StatusOr<Matrix> one = ReadRadianceMatrix(Path("m.mtx"));
    ASSERT_FALSE(one.ok());
    EXPECT_NE(one.status().message().find("NCOMP=3"), std::string::npos);
  }
}

TEST_F(RadianceMatrixTest, BadComponentsAndShortDataAreErrors) {
  EXPECT_FALSE(WriteRadianceMatrix(Path("m.mtx"), Example(), MatrixFormat::kAscii, 2).ok());
  EXPECT_FALSE(fs::exists(Path("m.mtx")));
  std::ofstream(Path("short.mtx"))
      << "#?RADIANCE\nNROWS=1\nNCOLS=2\nNCOMP=3\nFORMAT=ascii\n\n1 1 1\t2 2\n";
  absl::StatusOr<std::vector<Matrix>> read = ReadRadianceMatrixComponents(Path("short.mtx"));
  ASSERT_FALSE(read.ok());
  EXPECT_NE(read.status().message().find("expected 6 values, found 5"), std::string::npos)
      << read.status();
}

// A header is checked against the data, components included, before anything is allocated.
TEST_F(RadianceMatrixTest, HeaderClaimingMoreValuesThanTheFileHoldsIsAnError) {
  for (const char* header : {"NROWS=1000000000000\nNCOLS=146\nNCOMP=1\nFORMAT=ascii\n\n",
                             "NROWS=2\nNCOLS=3333333333333332\nNCOMP=1\nFORMAT=float\n\n",
                             "NROWS=4611686018427387904\nNCOLS=4\nNCOMP=1\nFORMAT=double\n\n",
                             "NROWS=1\nNCOLS=4\nNCOMP=3\nFORMAT=float\n\n"}) {
    std::ofstream(Path("m.mtx"), std::ios::binary) << "#?RADIANCE\n"
                                                   << header << "1 2 3 4 5 6 7 8\n";
    const absl::StatusOr<Matrix> read = ReadRadianceMatrix(Path("m.mtx"));
    ASSERT_FALSE(read.ok()) << header;
    EXPECT_EQ(read.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(read.status().message().find("the header says NROWS="), std::string::npos)
        << read.status();
  }
}

}  // namespace
}  // namespace fenestra
