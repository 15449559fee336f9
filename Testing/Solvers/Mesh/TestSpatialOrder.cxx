// Tests of the shared Morton order (Mesh/SpatialOrder.h) and point-triangle
// query (Mesh/TriangleGeometry.h).
#include "SpatialOrder.h"
#include "TriangleGeometry.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <random>

using namespace translucency;

TEST(SpatialOrder, CornersOfACubeFollowTheZCurve)
{
  // Morton code bit d of each cell is its coordinate on axis d: x fastest.
  std::vector<double> xyz;
  const int expected[8] = { 0, 4, 2, 6, 1, 5, 3, 7 }; // point index = 4 x + 2 y + z
  for (int x = 0; x < 2; ++x)
    for (int y = 0; y < 2; ++y)
      for (int z = 0; z < 2; ++z)
        xyz.insert(xyz.end(), { double(x), double(y), double(z) });
  const std::vector<int> order = MortonOrder(xyz.data(), 8);
  for (int k = 0; k < 8; ++k)
  {
    EXPECT_EQ(order[k], expected[k]) << "position " << k;
  }
}

TEST(SpatialOrder, TiesKeepIndexOrderAndOnlyTheFirstPointsCount)
{
  // Three equal points, then a far point that is not part of the first 3.
  const std::vector<double> xyz = { 1, 1, 1, 1, 1, 1, 1, 1, 1, 100, 100, 100 };
  EXPECT_EQ(MortonOrder(xyz.data(), 3), (std::vector<int>{ 0, 1, 2 }));
  EXPECT_EQ(SortByCode({ 5, 3, 5, 1 }), (std::vector<int>{ 3, 1, 0, 2 }));
}

TEST(TriangleGeometry, ClosestPointMatchesDenseSamplingAndItsWeights)
{
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  const Eigen::Vector3d a(0, 0, 0), b(1, 0, 0.2), c(0.3, 1.1, -0.1);
  for (int trial = 0; trial < 200; ++trial)
  {
    const Eigen::Vector3d p(u(rng), u(rng), u(rng));
    double w[3];
    const Eigen::Vector3d q = ClosestPointOnTriangle(p, a, b, c, w);
    EXPECT_NEAR(w[0] + w[1] + w[2], 1.0, 1e-12);
    EXPECT_GE(std::min({ w[0], w[1], w[2] }), 0.0);
    EXPECT_LT((w[0] * a + w[1] * b + w[2] * c - q).norm(), 1e-12);
    // No sample of the triangle is closer (to the sampling resolution).
    double best = HUGE_VAL;
    const int n = 200;
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j)
      {
        const Eigen::Vector3d s = a + (b - a) * (double(i) / n) + (c - a) * (double(j) / n);
        best = std::min(best, (s - p).norm());
      }
    EXPECT_LE((q - p).norm(), best + 1e-12);
    EXPECT_GE((q - p).norm(), best - 0.01);
  }
}

TEST(TriangleGeometry, OrthonormalFrameIsRightHandedAndOrthonormal)
{
  std::mt19937 rng(11);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int trial = 0; trial < 500; ++trial)
  {
    Eigen::Vector3d n(g(rng), g(rng), g(rng));
    if (trial == 0)
    {
      n = Eigen::Vector3d(1, 0, 0); // the branch for normals near the x axis
    }
    n.normalize();
    double t[3], b[3];
    OrthonormalFrame(n.data(), t, b);
    const Eigen::Vector3d T(t), B(b);
    EXPECT_NEAR(T.norm(), 1.0, 1e-14);
    EXPECT_NEAR(B.norm(), 1.0, 1e-14);
    EXPECT_NEAR(T.dot(n), 0.0, 1e-14);
    EXPECT_NEAR(B.dot(n), 0.0, 1e-14);
    EXPECT_NEAR(T.dot(B), 0.0, 1e-14);
    EXPECT_LT((T.cross(B) - n).norm(), 1e-14); // (t, b, n) right-handed
  }
}
