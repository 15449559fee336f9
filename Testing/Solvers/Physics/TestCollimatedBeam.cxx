// The extended collimated source's fast evaluation (issue 31: the relight
// under the default extended-moments model) against the straightforward one
// it replaced (CollimatedEvaluation::Reference: per-tet logarithms, the 4- and
// 32-point rules with direct exponentials, the exact integrals by the
// memoised divided-difference recursion): the same rays, so the same
// collimated fluence bit for bit, and the same loads to 1e-12 relative at
// every point, on the bunny, a sphere and a heterogeneous material with a
// nearly transparent region. Each case counts the tets (per beam and
// channel) that take each rule, from the beam itself, so that the test
// fails if a case stops exercising one of them.

#include "CollimatedSource.h"
#include "LightSources.h"
#include "OpticalProperties.h"
#include "TestMeshes.h"
#include "TestProblems.h"
#include "TetGenMeshes.h"
#include "TetMesh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <string>
#include <vector>

namespace
{

using namespace translucency;
using namespace translucency::testing;

TetMesh Build(const MeshData& raw)
{
  std::vector<int> pointOrder, tetOrder;
  TetMesh::ComputeSpatialOrder(raw.Points, raw.Tets, pointOrder, tetOrder);
  const MeshData ordered = Permute(raw, pointOrder, tetOrder);
  TetMesh mesh;
  mesh.SetGeometry(ordered.Points, ordered.Tets);
  return mesh;
}

TetMesh Bunny(const std::string& switches)
{
  std::vector<double> points;
  std::vector<int> triangles;
  ReadPly(std::string(TRANSLUCENCY_DATA_DIR) + "/bunny.ply", points, triangles);
  return Build(Tetrahedralize(points, triangles, switches));
}

TetMesh Sphere(double radius, const std::string& switches)
{
  std::vector<double> points;
  std::vector<int> triangles;
  IcoSphere(3, radius, points, triangles);
  return Build(Tetrahedralize(points, triangles, switches));
}

LightSource Directional(double dx, double dy, double dz, double power)
{
  LightSource light;
  light.Type = LightSource::Kind::Directional;
  light.Direction = { dx, dy, dz };
  light.Power = { power, power, power };
  return light;
}

OpticalProperties Preset(const TetMesh& mesh, const char* name)
{
  const MaterialPreset& preset = FindMaterialPreset(name);
  return OpticalProperties::Uniform(
    mesh.GetNumberOfTets(), preset.Absorption, preset.ReducedScattering, preset.RefractiveIndex);
}

/// The rules a tet's beam and channel take, by the range of ln E_c over its
/// vertices: unlit, partly lit (linear), <= 0.5 (4 points), <= 1 (32
/// points), <= 4 (the exact integrals' series), wider (the recursion).
enum Rule
{
  Unlit,
  PartlyLit,
  FourPoints,
  ThirtyTwoPoints,
  Series,
  Recursion,
  NumberOfRules
};
const char* const RuleNames[NumberOfRules] = { "unlit", "partly lit", "4 points", "32 points",
  "exact, series", "exact, recursion" };

std::array<long, NumberOfRules> CountRules(const TetMesh& mesh, const CollimatedSource& source)
{
  std::array<long, NumberOfRules> counts{};
  for (const CollimatedSource::Beam& beam : source.Beams)
  {
    for (int t = 0; t < mesh.GetNumberOfTets(); ++t)
    {
      const int* v = mesh.GetTet(t);
      for (int c = 0; c < 3; ++c)
      {
        int lit = 0;
        double low = 0.0, high = 0.0;
        for (int k = 0; k < 4; ++k)
        {
          const double e = beam.Fluence[3 * static_cast<size_t>(v[k]) + c];
          if (e > 0.0)
          {
            const double l = std::log(e);
            low = lit == 0 ? l : std::min(low, l);
            high = lit == 0 ? l : std::max(high, l);
            ++lit;
          }
        }
        const double range = high - low;
        const Rule rule = lit == 0 ? Unlit
          : lit < 4                ? PartlyLit
          : range <= 0.5           ? FourPoints
          : range <= 1.0           ? ThirtyTwoPoints
          : range <= 4.0           ? Series
                                   : Recursion;
        ++counts[rule];
      }
    }
  }
  return counts;
}

/// Fast against Reference on one case; returns the rules' counts.
std::array<long, NumberOfRules> ExpectSameSource(const TetMesh& mesh,
  const OpticalProperties& material, const std::vector<LightSource>& lights, bool shadows,
  const std::string& what)
{
  const CollimatedSource fast =
    ComputeCollimatedSource(mesh, material, lights, shadows, CollimatedEvaluation::Fast);
  const CollimatedSource reference =
    ComputeCollimatedSource(mesh, material, lights, shadows, CollimatedEvaluation::Reference);
  // The rays are the same code: the beams are equal bit for bit.
  EXPECT_EQ(fast.Fluence, reference.Fluence) << what;
  EXPECT_EQ(fast.Beams.size(), reference.Beams.size()) << what;
  for (size_t b = 0; b < std::min(fast.Beams.size(), reference.Beams.size()); ++b)
  {
    EXPECT_EQ(fast.Beams[b].Fluence, reference.Beams[b].Fluence) << what << ", beam " << b;
    EXPECT_EQ(fast.Beams[b].OpticalPath, reference.Beams[b].OpticalPath) << what << ", beam " << b;
  }
  // The loads: relative to each point's own load (a sum of positive terms, so
  // each tet's integrals to 1e-12 give it), zero where the reference is zero.
  EXPECT_EQ(fast.Load.size(), reference.Load.size()) << what;
  double worst = 0.0, largest = 0.0;
  long lit = 0;
  for (size_t i = 0; i < std::min(fast.Load.size(), reference.Load.size()); ++i)
  {
    largest = std::max(largest, reference.Load[i]);
    if (reference.Load[i] == 0.0)
    {
      EXPECT_EQ(fast.Load[i], 0.0) << what << ", value " << i;
      continue;
    }
    ++lit;
    worst = std::max(worst, std::abs(fast.Load[i] - reference.Load[i]) / reference.Load[i]);
  }
  EXPECT_GT(largest, 0.0) << what;
  EXPECT_LT(worst, 1e-12) << what;
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_NEAR(fast.Scattered[c] / reference.Scattered[c], 1.0, 1e-12) << what << ", channel " << c;
    EXPECT_NEAR(fast.Absorbed[c] / reference.Absorbed[c], 1.0, 1e-12) << what << ", channel " << c;
    EXPECT_EQ(fast.Entering[c], reference.Entering[c]) << what << ", channel " << c;
  }
  const std::array<long, NumberOfRules> counts = CountRules(mesh, reference);
  std::cout << what << ": " << mesh.GetNumberOfTets() << " tets, " << lit
            << " lit load values, worst relative difference " << worst << "; tets x beams x channels by rule:";
  for (int r = 0; r < NumberOfRules; ++r)
  {
    std::cout << " " << RuleNames[r] << " " << counts[r] << (r + 1 < NumberOfRules ? "," : "\n");
  }
  return counts;
}

TEST(CollimatedBeam, FastEqualsTheReferenceOnTheBunny)
{
  // Marble (mu_t' 2.2-3.0 /mm) on tets of about 2 mm: every rule is taken.
  const TetMesh mesh = Bunny("pq1.4a1.5Q");
  const OpticalProperties material = Preset(mesh, "marble");
  // The default key light, the same turned 15 degrees, and two beams at once
  // (each integrated on its own), with and without shadows.
  const double t = 15.0 * 3.14159265358979323846 / 180.0;
  const std::array<long, NumberOfRules> counts =
    ExpectSameSource(mesh, material, { Directional(0.0, -1.0, -1.0, 1.0) }, true, "bunny, key light");
  for (int r = 0; r < NumberOfRules; ++r)
  {
    EXPECT_GT(counts[r], 0) << RuleNames[r];
  }
  ExpectSameSource(mesh, material,
    { Directional(0.0, -std::cos(t) + std::sin(t), -std::sin(t) - std::cos(t), 1.0),
      Directional(0.7, -0.2, 0.4, 2.5) },
    false, "bunny, two beams, no shadows");
}

TEST(CollimatedBeam, FastEqualsTheReferenceOnASphere)
{
  const TetMesh mesh = Sphere(6.0, "pq1.3a0.2Q");
  const OpticalProperties material = Preset(mesh, "skin1");
  const std::array<long, NumberOfRules> counts = ExpectSameSource(
    mesh, material, { Directional(0.3, -1.0, 0.2, 1.0) }, true, "sphere, skin1");
  EXPECT_GT(counts[FourPoints] + counts[ThirtyTwoPoints], 0);
  EXPECT_GT(counts[Series], 0);
}

TEST(CollimatedBeam, FastEqualsTheReferenceOnAHeterogeneousMaterial)
{
  // The bunny in three regions by the tets' centroids: marble, ketchup
  // (x > 0; mu_t' up to 1.5 /mm, channels far apart) and a nearly transparent
  // region (mu_a 1e-4, mu_s' 1e-3 /mm: the beam crosses it almost
  // unattenuated, every tet lit by the 4-point rule).
  const TetMesh mesh = Bunny("pq1.4a1.5Q");
  OpticalProperties material = Preset(mesh, "marble");
  const MaterialPreset& ketchup = FindMaterialPreset("ketchup");
  // The clear region: the top quarter of the bunny's height (y), the ears.
  double low = mesh.GetPoint(0)[1], high = low;
  for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
  {
    low = std::min(low, mesh.GetPoint(i)[1]);
    high = std::max(high, mesh.GetPoint(i)[1]);
  }
  const double top = low + 0.75 * (high - low);
  int clear = 0;
  for (int t = 0; t < mesh.GetNumberOfTets(); ++t)
  {
    const int* v = mesh.GetTet(t);
    double centroid[3] = { 0.0, 0.0, 0.0 };
    for (int k = 0; k < 4; ++k)
    {
      for (int j = 0; j < 3; ++j)
      {
        centroid[j] += 0.25 * mesh.GetPoint(v[k])[j];
      }
    }
    for (int c = 0; c < 3; ++c)
    {
      if (centroid[1] > top)
      {
        material.AbsorptionCoefficient[3 * static_cast<size_t>(t) + c] = 1e-4;
        material.ReducedScatteringCoefficient[3 * static_cast<size_t>(t) + c] = 1e-3;
      }
      else if (centroid[0] > 0.0)
      {
        material.AbsorptionCoefficient[3 * static_cast<size_t>(t) + c] = ketchup.Absorption[c];
        material.ReducedScatteringCoefficient[3 * static_cast<size_t>(t) + c] =
          ketchup.ReducedScattering[c];
      }
    }
    clear += centroid[1] > top ? 1 : 0;
  }
  ASSERT_GT(clear, 100);
  ExpectSameSource(mesh, material, { Directional(0.0, -1.0, -1.0, 1.0) }, true,
    "bunny, marble + ketchup + clear");
  ExpectSameSource(mesh, material, { Directional(0.0, -1.0, 0.0, 1.0) }, true,
    "bunny, marble + ketchup + clear, from above");
}

/// CollimatedSourceCache against a fresh ComputeCollimatedSource of the same
/// arguments: the beam field and the loads equal bit for bit, the power sums
/// to rounding, and what the cache says it did.
void ExpectCachedEqualsFresh(CollimatedSourceCache& cache, const TetMesh& mesh,
  const OpticalProperties& material, const std::vector<LightSource>& lights,
  const std::string& update, const std::string& what)
{
  const CollimatedSource cached = cache.Compute(mesh, material, lights, true);
  const CollimatedSource fresh = ComputeCollimatedSource(mesh, material, lights, true);
  EXPECT_EQ(cache.GetLastUpdate(), update) << what;
  std::cout << what << ": " << cache.GetLastUpdate() << ", " << cache.GetTetsIntegrated() << " of "
            << mesh.GetNumberOfTets() << " tets integrated\n";
  EXPECT_EQ(cached.Fluence, fresh.Fluence) << what;
  ASSERT_EQ(cached.Beams.size(), fresh.Beams.size()) << what;
  for (size_t b = 0; b < fresh.Beams.size(); ++b)
  {
    EXPECT_EQ(cached.Beams[b].Fluence, fresh.Beams[b].Fluence) << what << ", beam " << b;
    EXPECT_EQ(cached.Beams[b].OpticalPath, fresh.Beams[b].OpticalPath) << what << ", beam " << b;
  }
  EXPECT_EQ(cached.Load, fresh.Load) << what;
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_EQ(cached.Entering[c], fresh.Entering[c]) << what << ", channel " << c;
    EXPECT_NEAR(cached.Scattered[c] / fresh.Scattered[c], 1.0, 1e-13) << what << ", channel " << c;
    EXPECT_NEAR(cached.Absorbed[c] / fresh.Absorbed[c], 1.0, 1e-13) << what << ", channel " << c;
  }
}

/// Tets with a vertex within `radius` of `centre`; `boundary`: whether one
/// of them has a boundary triangle.
std::vector<int> TetsNear(const TetMesh& mesh, const double centre[3], double radius, bool& boundary)
{
  std::vector<int> tets =
    translucency::testing::TetsNear(mesh, { centre[0], centre[1], centre[2] }, radius);
  std::vector<char> underTriangle(static_cast<size_t>(mesh.GetNumberOfTets()), 0);
  for (const int t : mesh.GetBoundaryTriangleTets())
  {
    underTriangle[static_cast<size_t>(t)] = 1;
  }
  boundary = std::any_of(tets.begin(), tets.end(),
    [&](int t) { return underTriangle[static_cast<size_t>(t)] != 0; });
  return tets;
}

TEST(CollimatedSourceCache, PaintsRelightsAndPowersEqualAFreshSource)
{
  const TetMesh mesh = Bunny("pq1.4a1.5Q");
  OpticalProperties material = Preset(mesh, "marble");
  const MaterialPreset& ketchup = FindMaterialPreset("ketchup");
  std::vector<LightSource> lights = { Directional(0.0, -1.0, -1.0, 1.0),
    Directional(0.7, -0.2, 0.4, 2.5) };
  CollimatedSourceCache cache;
  ExpectCachedEqualsFresh(cache, mesh, material, lights, "full", "first call");
  const long long all = cache.GetTetsIntegrated();
  EXPECT_EQ(all, mesh.GetNumberOfTets());
  ExpectCachedEqualsFresh(cache, mesh, material, lights, "kept", "the same arguments");
  EXPECT_EQ(cache.GetTetsIntegrated(), 0);

  // An interior stroke (no tet under the boundary): E_c unchanged, the
  // stroke's tets and their neighbours integrated again.
  bool boundary = true;
  const double inside[3] = { -1.0, 10.0, 0.0 };
  const std::vector<int> interior = TetsNear(mesh, inside, 3.0, boundary);
  ASSERT_FALSE(boundary);
  ASSERT_GT(interior.size(), 20u);
  for (const int t : interior)
  {
    for (int c = 0; c < 3; ++c)
    {
      material.AbsorptionCoefficient[3 * static_cast<size_t>(t) + c] = ketchup.Absorption[c];
      material.ReducedScatteringCoefficient[3 * static_cast<size_t>(t) + c] =
        ketchup.ReducedScattering[c];
    }
  }
  ExpectCachedEqualsFresh(cache, mesh, material, lights, "loads", "interior stroke");
  EXPECT_GE(cache.GetTetsIntegrated(), static_cast<long long>(interior.size()));
  EXPECT_LT(cache.GetTetsIntegrated(), all / 10);

  // A stroke through the lit surface: E_c changes behind it along the beams
  // (the entry material), so more tets, but not all.
  const double* top = nullptr;
  for (const int p : mesh.GetBoundaryPoints())
  {
    if (!top || mesh.GetPoint(p)[1] + mesh.GetPoint(p)[2] > top[1] + top[2])
    {
      top = mesh.GetPoint(p);
    }
  }
  const std::vector<int> surface = TetsNear(mesh, top, 2.5, boundary);
  ASSERT_TRUE(boundary);
  for (const int t : surface)
  {
    material.ReducedScatteringCoefficient[3 * static_cast<size_t>(t) + 1] *= 3.0;
    material.RefractiveIndex[static_cast<size_t>(t)] = 1.45;
  }
  ExpectCachedEqualsFresh(cache, mesh, material, lights, "loads", "surface stroke, new index");
  EXPECT_LT(cache.GetTetsIntegrated(), all / 2);

  // A stroke undone (the material before it): equal again.
  for (const int t : surface)
  {
    material.ReducedScatteringCoefficient[3 * static_cast<size_t>(t) + 1] /= 3.0;
    material.RefractiveIndex[static_cast<size_t>(t)] = Preset(mesh, "marble").RefractiveIndex[0];
  }
  ExpectCachedEqualsFresh(cache, mesh, material, lights, "loads", "surface stroke undone");

  // A brighter light: every lit point's E_c changes (the loads integrated
  // anew, past a quarter of the tets); a turned light casts new rays.
  lights[1].Power = { 2.0, 3.0, 4.0 };
  ExpectCachedEqualsFresh(cache, mesh, material, lights, "loads", "brighter light");
  EXPECT_EQ(cache.GetTetsIntegrated(), all);
  lights[0].Direction = { 0.0, -1.0, -0.9 };
  ExpectCachedEqualsFresh(cache, mesh, material, lights, "full", "turned light");
  EXPECT_GT(cache.GetMemoryBytes(), 0u);
  cache.Clear();
  EXPECT_EQ(cache.GetMemoryBytes(), 0u);
  ExpectCachedEqualsFresh(cache, mesh, material, lights, "full", "after Clear");
}

} // namespace
