#include "core/common/radiance_matrix.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace fenestra {
namespace {

class RadianceMatrixTest : public testing::Test {
 protected:
  void TearDown() override { std::filesystem::remove(path_); }

  // Writes `bytes` to this test's file and returns its path.
  const std::string& File(const std::string& bytes) {
    std::ofstream(path_, std::ios::binary) << bytes;
    return path_;
  }

  std::string path_ = (std::filesystem::temp_directory_path() /
                       ("fenestra_radiance_matrix_test_" + std::to_string(getpid())))
                          .string();
};

TEST_F(RadianceMatrixTest, AsciiAndFloatRoundTrip) {
  Matrix m(2, 3);
  m << 1, 2.5, -3, 4e-9, 0, 6;
  for (MatrixFormat format : {MatrixFormat::kAscii, MatrixFormat::kFloat}) {
    ASSERT_TRUE(WriteRadianceMatrix(path_, m, format).ok());
    absl::StatusOr<Matrix> read = ReadRadianceMatrix(path_);
    ASSERT_TRUE(read.ok()) << read.status();
    EXPECT_TRUE(read->isApprox(m, 1e-7)) << *read;
  }
}

// A header is checked against the data before the matrix is allocated.
TEST_F(RadianceMatrixTest, HeaderClaimingMoreValuesThanTheFileHoldsIsAnError) {
  for (const char* header : {"NROWS=1000000000000\nNCOLS=146\nNCOMP=1\nFORMAT=ascii\n\n",
                             "NROWS=2\nNCOLS=3333333333333332\nNCOMP=1\nFORMAT=float\n\n",
                             "NROWS=4611686018427387904\nNCOLS=4\nNCOMP=1\nFORMAT=double\n\n"}) {
    const absl::StatusOr<Matrix> read =
        ReadRadianceMatrix(File(std::string("#?RADIANCE\n") + header + "1 2 3 4 5 6 7 8\n"));
    ASSERT_FALSE(read.ok()) << header;
    EXPECT_EQ(read.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(read.status().message().find("the header says NROWS="), std::string::npos)
        << read.status();
  }
}

}  // namespace
}  // namespace fenestra
