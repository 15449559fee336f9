// TetFracture: Voronoi pieces of a cube mesh, checked against a brute-force
// nearest seed and the exact partition identities, and the input checks.

#include "Error.h"
#include "TestMeshes.h"
#include "TetFracture.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <vector>

namespace
{

using namespace translucency;
using namespace translucency::testing;

TEST(TetFracture, PartitionIsTheNearestSeed)
{
  const MeshData mesh = CubeMesh(6, 6.0, 0.2, 3);
  const std::vector<double> seeds = { 1, 1, 1, 5, 1, 2, 3, 5, 4, 2, 3, 5, 50, 50, 50 };
  TetFracture fracture;
  fracture.SetSeeds(seeds);
  fracture.Split(mesh.Points, mesh.Tets);
  ASSERT_EQ(fracture.GetNumberOfPieces(), 4); // the far seed owns nothing
  std::vector<int> seen(mesh.NumberOfTets(), 0);
  for (int k = 0; k < fracture.GetNumberOfPieces(); ++k)
  {
    const auto& tets = fracture.GetPieceTets(k);
    const auto& points = fracture.GetPiecePoints(k);
    const auto& local = fracture.GetPieceConnectivity(k);
    EXPECT_EQ(fracture.GetPieceSeed(k), k);
    ASSERT_EQ(local.size(), 4 * tets.size());
    EXPECT_TRUE(std::is_sorted(points.begin(), points.end()));
    std::vector<int> used(points.size(), 0);
    for (std::size_t j = 0; j < tets.size(); ++j)
    {
      const int t = tets[j];
      ++seen[t];
      // Brute-force nearest seed of the centroid.
      double c[3] = { 0, 0, 0 };
      for (int v = 0; v < 4; ++v)
      {
        for (int d = 0; d < 3; ++d)
        {
          c[d] += 0.25 * mesh.Points[3 * mesh.Tets[4 * t + v] + d];
        }
        // Local ids map back to the input vertex, in order.
        EXPECT_EQ(points[local[4 * j + v]], mesh.Tets[4 * t + v]);
        used[local[4 * j + v]] = 1;
      }
      int best = -1;
      double bestD = std::numeric_limits<double>::infinity();
      for (std::size_t s = 0; s < seeds.size() / 3; ++s)
      {
        double d2 = 0;
        for (int d = 0; d < 3; ++d)
        {
          d2 += (c[d] - seeds[3 * s + d]) * (c[d] - seeds[3 * s + d]);
        }
        if (d2 < bestD)
        {
          bestD = d2;
          best = static_cast<int>(s);
        }
      }
      EXPECT_EQ(best, fracture.GetPieceSeed(k));
      EXPECT_EQ(fracture.GetTetSeeds()[t], best);
    }
    // Compact: every piece point is used.
    EXPECT_EQ(std::count(used.begin(), used.end(), 1), static_cast<long>(used.size()));
  }
  for (int t = 0; t < mesh.NumberOfTets(); ++t)
  {
    EXPECT_EQ(seen[t], 1) << "tet " << t;
  }
}

TEST(TetFracture, RandomSeedsAreReproducibleCentroids)
{
  const MeshData mesh = CubeMesh(4, 4.0);
  const auto a = TetFracture::RandomSeeds(mesh.Points, mesh.Tets, 7, 42);
  const auto b = TetFracture::RandomSeeds(mesh.Points, mesh.Tets, 7, 42);
  const auto c = TetFracture::RandomSeeds(mesh.Points, mesh.Tets, 7, 43);
  ASSERT_EQ(a.size(), 21u);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  // Seeds are distinct centroids: each seed's Voronoi cell holds its own tet.
  TetFracture fracture;
  fracture.SetSeeds(a);
  fracture.Split(mesh.Points, mesh.Tets);
  EXPECT_EQ(fracture.GetNumberOfPieces(), 7);
  // Clamped to the number of tets.
  EXPECT_EQ(TetFracture::RandomSeeds(mesh.Points, mesh.Tets, 1 << 20, 1).size(),
    3 * mesh.Tets.size() / 4);
}

TEST(TetFracture, InputChecks)
{
  const MeshData mesh = CubeMesh(2, 1.0);
  TetFracture fracture;
  EXPECT_THROW(fracture.Split(mesh.Points, mesh.Tets), Error); // no seeds
  fracture.SetSeeds({ 0, 0 });
  EXPECT_THROW(fracture.Split(mesh.Points, mesh.Tets), Error);
  fracture.SetSeeds({ 0, 0, 0 });
  std::vector<int> bad = mesh.Tets;
  bad[5] = mesh.NumberOfPoints();
  EXPECT_THROW(fracture.Split(mesh.Points, bad), Error);
  try
  {
    TetFracture none;
    none.Split(mesh.Points, mesh.Tets);
  }
  catch (const Error& e)
  {
    EXPECT_NE(std::string(e.what()).find("no seed points"), std::string::npos);
  }
}

} // namespace
