// CheckModelRange (ModelRange.h): the volume outside the diffusion model's
// albedo range and the surface over tets too coarse for the boundary layer,
// on a cube of Kuhn tets whose volumes and sizes are known in closed form.

#include "ModelRange.h"
#include "OpticalProperties.h"
#include "TetMesh.h"

#include "../TestMeshes.h"

#include <gtest/gtest.h>

#include <cmath>

namespace
{

using namespace translucency;

// The cube [0, 2]^3 in 4^3 cells of h = 0.5 mm, 6 tets each (volume h^3 / 6).
TetMesh Cube()
{
  const translucency::testing::MeshData data = translucency::testing::CubeMesh(4, 2.0);
  TetMesh mesh;
  mesh.SetGeometry(data.Points, data.Tets);
  return mesh;
}

OpticalProperties Uniform(const TetMesh& mesh, double muA, double muS)
{
  const double a[3] = { muA, muA, muA }, s[3] = { muS, muS, muS };
  return OpticalProperties::Uniform(mesh.GetNumberOfTets(), a, s, 1.3);
}

TEST(ModelRange, TetSizeIsTheEdgeOfTheRegularTetOfTheSameVolume)
{
  const TetMesh mesh = Cube();
  const std::vector<double> sizes = TetSizes(mesh);
  // h^3/6 = e^3/(6 sqrt 2)  =>  e = h 2^(1/6).
  for (double size : sizes)
  {
    EXPECT_NEAR(size, 0.5 * std::pow(2.0, 1.0 / 6.0), 1e-12);
  }
}

TEST(ModelRange, MarbleLikeMaterialIsInRange)
{
  const TetMesh mesh = Cube();
  const ModelRangeReport report = CheckModelRange(mesh, Uniform(mesh, 0.01, 1.0));
  EXPECT_EQ(report.LowAlbedoVolumeFraction, 0.0);
  EXPECT_EQ(report.CoarseAreaFraction, 0.0);
  EXPECT_NEAR(report.MinimumAlbedo, 1.0 / 1.01, 1e-12);
  EXPECT_EQ(report.Message(), "");
}

TEST(ModelRange, LowAlbedoLayerIsMeasuredByVolume)
{
  const TetMesh mesh = Cube();
  OpticalProperties material = Uniform(mesh, 0.01, 1.0);
  // The layer x < 0.5 (one cell of four along x: exactly a quarter of the
  // volume) absorbs strongly in the blue channel: albedo 1 / 1.2.
  int layer = 0;
  for (int t = 0; t < mesh.GetNumberOfTets(); ++t)
  {
    double x = 0.0;
    for (int a = 0; a < 4; ++a)
    {
      x += 0.25 * mesh.GetPoint(mesh.GetTet(t)[a])[0];
    }
    if (x < 0.5)
    {
      material.AbsorptionCoefficient[3 * t + 2] = 0.2;
      ++layer;
    }
  }
  ASSERT_EQ(layer, mesh.GetNumberOfTets() / 4);
  const ModelRangeReport report = CheckModelRange(mesh, material);
  EXPECT_NEAR(report.LowAlbedoVolumeFraction, 0.25, 1e-12);
  EXPECT_NEAR(report.MinimumAlbedo, 1.0 / 1.2, 1e-12);
  EXPECT_EQ(report.MinimumAlbedoChannel, 2);
  const std::string message = report.Message();
  EXPECT_NE(message.find("25 % of the volume"), std::string::npos) << message;
  EXPECT_NE(message.find("0.833"), std::string::npos) << message;
  EXPECT_NE(message.find("channel B"), std::string::npos) << message;
  EXPECT_EQ(message.find("coarse"), std::string::npos) << message;
}

TEST(ModelRange, CoarseSurfaceTetsAreMeasuredByArea)
{
  const TetMesh mesh = Cube();
  // l* = 1 / 10.01 mm: every tet (size 0.561 mm) is 5.6 l* across.
  const ModelRangeReport report = CheckModelRange(mesh, Uniform(mesh, 0.01, 10.0));
  EXPECT_NEAR(report.CoarseAreaFraction, 1.0, 1e-12);
  EXPECT_NEAR(report.LargestSizeInMeanFreePaths, 0.5 * std::pow(2.0, 1.0 / 6.0) * 10.01, 1e-9);
  EXPECT_EQ(report.LowAlbedoVolumeFraction, 0.0);
  const std::string message = report.Message();
  EXPECT_NE(message.find("coarse"), std::string::npos) << message;
  EXPECT_NE(message.find("100 % of the surface"), std::string::npos) << message;
  // Just inside the bound: size = 2.9 l*.
  const double muS = 2.9 / (0.5 * std::pow(2.0, 1.0 / 6.0)) - 0.01;
  EXPECT_EQ(CheckModelRange(mesh, Uniform(mesh, 0.01, muS)).CoarseAreaFraction, 0.0);
}

} // namespace
