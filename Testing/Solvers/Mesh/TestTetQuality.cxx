// Tests of the mesh shape statistics (Mesh/TetQuality.h) on tets whose
// angles and radii are known in closed form.
#include "Error.h"
#include "TetQuality.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace translucency;

TEST(TetQuality, RegularTetHasTheKnownAnglesAndRatio)
{
  // Regular tet with edge 2 sqrt(2): alternate corners of a cube of side 2.
  const std::vector<double> points = { 1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1 };
  const std::vector<int> tets = { 0, 1, 2, 3 };
  const TetQualityStats s = ComputeTetQuality(points, tets, 1.414);
  const double dihedral = std::acos(1.0 / 3.0) * 180.0 / M_PI; // 70.53 degrees
  EXPECT_NEAR(s.MinDihedral, dihedral, 1e-9);
  EXPECT_NEAR(s.MaxDihedral, dihedral, 1e-9);
  EXPECT_NEAR(s.MaxRadiusEdge, std::sqrt(6.0) / 4.0, 1e-12); // R / a = sqrt(6)/4
  EXPECT_NEAR(s.MeanEdgeLength, 2 * std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(s.EdgeLengthCV, 0.0, 1e-7);
  EXPECT_EQ(s.MinDihedralHistogram[7], 1u);
  EXPECT_EQ(s.FractionAboveRadiusEdgeBound, 0.0);
  EXPECT_NEAR(s.MinVolume, 8.0 / 3.0, 1e-12);
  // Orientation does not matter.
  const TetQualityStats flipped = ComputeTetQuality(points, { 1, 0, 2, 3 });
  EXPECT_NEAR(flipped.MinDihedral, dihedral, 1e-9);
  EXPECT_NEAR(flipped.MaxRadiusEdge, std::sqrt(6.0) / 4.0, 1e-12);
}

TEST(TetQuality, CornerTetAndSliverAreMeasured)
{
  // Corner tet (0,0,0),(1,0,0),(0,1,0),(0,0,1): dihedral angles 90 at the
  // three axes and acos(1/sqrt(3)) = 54.7 at the others; circumradius
  // sqrt(3)/2, shortest edge 1.
  // Sliver: a square's four corners lifted alternately by +-e: all four
  // points almost on a circle of radius 1/sqrt(2) with edges 1 and sqrt(2):
  // radius-edge ~0.707 yet dihedral angles near 0 and 180.
  const double e = 1e-3;
  const std::vector<double> points = { 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, //
    0, 0, e, 1, 0, -e, 1, 1, e, 0, 1, -e };
  const TetQualityStats corner = ComputeTetQuality(points, { 0, 1, 2, 3 }, 0.8);
  EXPECT_NEAR(corner.MinDihedral, std::acos(1 / std::sqrt(3.0)) * 180 / M_PI, 1e-9);
  EXPECT_NEAR(corner.MaxDihedral, 90.0, 1e-9);
  EXPECT_NEAR(corner.MaxRadiusEdge, std::sqrt(3.0) / 2.0, 1e-12);
  EXPECT_EQ(corner.FractionAboveRadiusEdgeBound, 1.0);
  EXPECT_EQ(corner.MinDihedralHistogram[5], 1u);
  const TetQualityStats sliver = ComputeTetQuality(points, { 4, 5, 6, 7 }, 1.414);
  EXPECT_LT(sliver.MinDihedral, 1.0);
  EXPECT_GT(sliver.MaxDihedral, 179.0);
  EXPECT_NEAR(sliver.MaxRadiusEdge, std::sqrt(0.5), 1e-3);
  EXPECT_EQ(sliver.MinDihedralHistogram[0], 1u);
  EXPECT_EQ(sliver.FractionAboveRadiusEdgeBound, 0.0);
  const TetQualityStats both = ComputeTetQuality(points, { 0, 1, 2, 3, 4, 5, 6, 7 }, 0.8);
  EXPECT_EQ(both.NumberOfTets, 2u);
  EXPECT_DOUBLE_EQ(both.FractionAboveRadiusEdgeBound, 0.5);
  EXPECT_DOUBLE_EQ(both.MinDihedral, sliver.MinDihedral);
}

TEST(TetQuality, BadIdsAreNamed)
{
  const std::vector<double> points = { 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1 };
  try
  {
    ComputeTetQuality(points, { 0, 1, 2, 4 });
    FAIL() << "no error";
  }
  catch (const Error& e)
  {
    EXPECT_NE(std::string(e.what()).find("tet 0 has point id 4"), std::string::npos) << e.what();
  }
  const TetQualityStats empty = ComputeTetQuality(points, {});
  EXPECT_EQ(empty.NumberOfTets, 0u);
}
