#include "core/metrics/illuminance.h"

#include <gtest/gtest.h>

#include <numbers>
#include <vector>

namespace fenestra {
namespace {

Matrix Make(int rows, int cols, std::initializer_list<double> values) {
  Matrix m(rows, cols);
  auto it = values.begin();
  for (int i = 0; i < rows; ++i) {
    for (int j = 0; j < cols; ++j) m(i, j) = *it++;
  }
  return m;
}

TEST(IlluminanceTest, GreyKeepsOnlyTheChosenColumns) {
  const Matrix dc = Make(2, 3, {1, 2, 3, 0.5, 0, 1});
  const Matrix sky = Make(3, 4, {0, 1, 0, 2, 0, 1, 0, 0, 0, 1, 0, 1});
  const std::vector<int> columns = {1, 3};
  absl::StatusOr<Matrix> e = Illuminance(dc, sky, columns);
  ASSERT_TRUE(e.ok()) << e.status();
  ASSERT_EQ(e->rows(), 2);
  ASSERT_EQ(e->cols(), 2);
  EXPECT_DOUBLE_EQ((*e)(0, 0), 179.0 * 6);
  EXPECT_DOUBLE_EQ((*e)(0, 1), 179.0 * 5);
  EXPECT_DOUBLE_EQ((*e)(1, 0), 179.0 * 1.5);
  EXPECT_DOUBLE_EQ((*e)(1, 1), 179.0 * 2);
}

TEST(IlluminanceTest, LitColumnsSkipsNightColumns) {
  const Matrix sky = Make(3, 4, {0, 1, 0, 2, 0, 1, 0, 0, 0, 1, 0, 1});
  EXPECT_EQ(LitColumns(sky), (std::vector<int>{1, 3}));
  EXPECT_TRUE(LitColumns(Matrix::Zero(146, 24)).empty());
}

TEST(IlluminanceTest, UniformSkyOnAnOpenPlaneGives179PiL) {
  // Sum of the coefficients over the sky bins of an unobstructed upward sensor is pi
  Matrix dc = Matrix::Constant(1, 146, std::numbers::pi / 145);
  dc(0, 0) = 0;
  const Matrix sky = Matrix::Constant(146, 1, 2.0);
  const std::vector<int> columns = {0};
  absl::StatusOr<Matrix> e = Illuminance(dc, sky, columns);
  ASSERT_TRUE(e.ok());
  EXPECT_NEAR((*e)(0, 0), 179 * std::numbers::pi * 2.0, 1e-9);
}

TEST(IlluminanceTest, RgbSkyUsesRadianceWeights) {
  const Matrix dc = Make(1, 1, {1});
  const std::vector<Matrix> sky = {Make(1, 1, {1}), Make(1, 1, {0}), Make(1, 1, {0})};
  const std::vector<Matrix> grey = {dc};
  const std::vector<int> columns = {0};
  absl::StatusOr<Matrix> red = Illuminance(grey, sky, columns);
  ASSERT_TRUE(red.ok());
  EXPECT_NEAR((*red)(0, 0), 47.4, 0.05);  // rtrace -I: 47.4 R + 119.9 G + 11.6 B
  EXPECT_DOUBLE_EQ((*red)(0, 0), 179 * 0.265074126);

  const std::vector<Matrix> white = {Make(1, 1, {2}), Make(1, 1, {2}), Make(1, 1, {2})};
  absl::StatusOr<Matrix> e = Illuminance(grey, white, columns);
  ASSERT_TRUE(e.ok());
  EXPECT_NEAR((*e)(0, 0), 179 * 2.0, 1e-6);  // the weights sum to 1
}

TEST(IlluminanceTest, RgbCoefficientsAndSkyPerChannel) {
  const std::vector<Matrix> dc = {Make(1, 2, {1, 0}), Make(1, 2, {0, 1}), Make(1, 2, {1, 1})};
  const std::vector<Matrix> sky = {Make(2, 1, {3, 5}), Make(2, 1, {7, 11}), Make(2, 1, {13, 17})};
  const std::vector<int> columns = {0};
  absl::StatusOr<Matrix> e = Illuminance(dc, sky, columns);
  ASSERT_TRUE(e.ok());
  const double expected = 179 * (0.265074126 * 3 + 0.670114631 * 11 + 0.064811243 * 30);
  EXPECT_NEAR((*e)(0, 0), expected, 1e-9);

  // Coloured coefficients under a grey sky
  const std::vector<Matrix> grey_sky = {Make(2, 1, {3, 5})};
  absl::StatusOr<Matrix> g = Illuminance(dc, grey_sky, columns);
  ASSERT_TRUE(g.ok());
  EXPECT_NEAR((*g)(0, 0), 179 * (0.265074126 * 3 + 0.670114631 * 5 + 0.064811243 * 8), 1e-9);
}

TEST(IlluminanceTest, RejectsBadInput) {
  const Matrix dc = Matrix::Ones(2, 3);
  const Matrix sky = Matrix::Ones(3, 4);
  const std::vector<int> ok = {0, 2};
  EXPECT_EQ(Illuminance(dc, Matrix::Ones(4, 4), ok).status().code(),
            absl::StatusCode::kInvalidArgument);
  const std::vector<int> descending = {2, 1};
  EXPECT_EQ(Illuminance(dc, sky, descending).status().code(), absl::StatusCode::kInvalidArgument);
  const std::vector<int> repeated = {1, 1};
  EXPECT_FALSE(Illuminance(dc, sky, repeated).ok());
  const std::vector<int> outside = {0, 4};
  EXPECT_FALSE(Illuminance(dc, sky, outside).ok());
  const std::vector<Matrix> two = {dc, dc};
  const std::vector<Matrix> one_sky = {sky};
  EXPECT_FALSE(Illuminance(two, one_sky, ok).ok());
}

}  // namespace
}  // namespace fenestra
