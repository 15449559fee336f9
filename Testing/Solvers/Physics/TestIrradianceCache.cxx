// IrradianceCache (issue 31): the kept per-light and uniform terms give the
// full ComputeProjectedIrradiance() of the same lights to 1e-12 for every
// light kind (directional, point, spot, coloured), and a change of one light
// recomputes that light only (the counters), a change of the uniform light,
// the geometry or the refractive index what depends on it.

#include "Error.h"
#include "IrradianceCache.h"
#include "LightSources.h"
#include "RayCaster.h"
#include "ShadowCaster.h"
#include "TestMeshes.h"
#include "TestProblems.h"
#include "TetMesh.h"

#include <gtest/gtest.h>

#include <random>

#include <algorithm>
#include <cmath>

namespace
{

using namespace translucency;
using translucency::testing::RelativeDifference;

/// An 8 mm cube in 6^3 cells with a 4 x 4 x 4 mm well dug from its top
/// (the walls shadow the floor), the refractive index varying by tet.
void MakeWell(TetMesh& mesh, std::vector<double>& tetEta, double shift = 0.0)
{
  const translucency::testing::MeshData box = translucency::testing::CubeMesh(6, 8.0, 0.2, 3);
  std::vector<int> tets;
  std::vector<double> points = box.Points;
  for (size_t k = 0; k < points.size(); k += 3)
    points[k] += shift;
  for (size_t t = 0; t < box.Tets.size() / 4; ++t)
  {
    double centre[3] = { 0.0, 0.0, 0.0 };
    for (int v = 0; v < 4; ++v)
      for (int d = 0; d < 3; ++d)
        centre[d] += 0.25 * box.Points[3 * static_cast<size_t>(box.Tets[4 * t + v]) + d];
    if (centre[0] > 2.0 && centre[0] < 6.0 && centre[1] > 2.0 && centre[1] < 6.0 &&
      centre[2] > 4.0)
      continue;
    tets.insert(tets.end(), box.Tets.begin() + 4 * t, box.Tets.begin() + 4 * t + 4);
    tetEta.push_back(1.3 + 0.1 * (centre[0] > 4.0) + 0.05 * (centre[2] > 3.0));
  }
  mesh.SetGeometry(points, tets);
}


std::vector<double> Full(const TetMesh& mesh, const std::vector<double>& eta,
  const std::vector<LightSource>& lights, double uniform, int samples, bool shadows)
{
  std::vector<double> q;
  EXPECT_TRUE(ComputeProjectedIrradiance(mesh, eta, lights, uniform, samples, shadows, q));
  return q;
}

/// One light of each kind, white and coloured, all lighting part of the well.
std::vector<LightSource> EveryKind()
{
  return { DirectionalLight({ 0.3, -0.5, -1.0 }, { 1.0, 1.0, 1.0 }),
    DirectionalLight({ -0.4, 0.2, -1.0 }, { 0.9, 0.5, 0.2 }),
    PointLight({ 9.0, 4.0, 12.0 }, { 50.0, 50.0, 50.0 }),
    PointLight({ -3.0, 5.0, 10.0 }, { 20.0, 60.0, 70.0 }),
    SpotLight({ 4.0, 4.0, 14.0 }, { 0.1, 0.0, -1.0 }, 25.0, 2.0, { 80.0, 40.0, 30.0 }) };
}

/// `light` turned by `degrees` (its direction, or for a point light its
/// position about the well's axis).
LightSource Turned(LightSource light, double degrees)
{
  const double t = degrees * 3.14159265358979323846 / 180.0;
  auto rotate = [t](std::array<double, 3>& v, double cx, double cy) {
    const double x = v[0] - cx, y = v[1] - cy;
    v[0] = cx + std::cos(t) * x - std::sin(t) * y;
    v[1] = cy + std::sin(t) * x + std::cos(t) * y;
  };
  if (light.Type == LightSource::Kind::Directional || light.Type == LightSource::Kind::Spot)
    rotate(light.Direction, 0.0, 0.0);
  if (light.Type != LightSource::Kind::Directional)
    rotate(light.Position, 4.0, 4.0);
  return light;
}

TEST(IrradianceCache, EqualsTheFullComputationForEveryLightKind)
{
  TetMesh mesh;
  std::vector<double> eta;
  MakeWell(mesh, eta);
  const std::vector<LightSource> lights = EveryKind();
  IrradianceCache cache;
  std::vector<double> q;
  ASSERT_TRUE(cache.Compute(mesh, eta, lights, 0.1, 16, true, q));
  EXPECT_EQ(cache.GetNumberOfLightsComputed(), 5);
  EXPECT_TRUE(cache.GetUniformComputed());
  const std::vector<double> full = Full(mesh, eta, lights, 0.1, 16, true);
  EXPECT_LE(RelativeDifference(q, full), 1e-12);

  // Turn each light in turn: only it is recomputed, and the result is the
  // full computation of the new lights (which differs from the old one).
  std::vector<LightSource> current = lights;
  for (size_t l = 0; l < current.size(); ++l)
  {
    SCOPED_TRACE("light " + std::to_string(l));
    const std::vector<double> before = Full(mesh, eta, current, 0.1, 16, true);
    current[l] = Turned(current[l], 15.0);
    ASSERT_TRUE(cache.Compute(mesh, eta, current, 0.1, 16, true, q));
    EXPECT_EQ(cache.GetNumberOfLightsComputed(), 1);
    EXPECT_FALSE(cache.GetUniformComputed());
    const std::vector<double> after = Full(mesh, eta, current, 0.1, 16, true);
    EXPECT_LE(RelativeDifference(q, after), 1e-12);
    EXPECT_GT(RelativeDifference(before, after), 1e-3) << "turning the light changed nothing";
  }

  // Nothing changed: nothing recomputed.
  ASSERT_TRUE(cache.Compute(mesh, eta, current, 0.1, 16, true, q));
  EXPECT_EQ(cache.GetNumberOfLightsComputed(), 0);
  EXPECT_FALSE(cache.GetUniformComputed());
  EXPECT_LE(RelativeDifference(q, Full(mesh, eta, current, 0.1, 16, true)), 1e-12);

  // A light removed, another reordered: no light recomputed, same as full.
  std::vector<LightSource> fewer = { current[3], current[0], current[4] };
  ASSERT_TRUE(cache.Compute(mesh, eta, fewer, 0.1, 16, true, q));
  EXPECT_EQ(cache.GetNumberOfLightsComputed(), 0);
  EXPECT_LE(RelativeDifference(q, Full(mesh, eta, fewer, 0.1, 16, true)), 1e-12);

  // The uniform light's samples changed: it alone is recomputed.
  ASSERT_TRUE(cache.Compute(mesh, eta, fewer, 0.1, 32, true, q));
  EXPECT_EQ(cache.GetNumberOfLightsComputed(), 0);
  EXPECT_TRUE(cache.GetUniformComputed());
  EXPECT_LE(RelativeDifference(q, Full(mesh, eta, fewer, 0.1, 32, true)), 1e-12);

  // Shadows off: every term again.
  ASSERT_TRUE(cache.Compute(mesh, eta, fewer, 0.1, 32, false, q));
  EXPECT_EQ(cache.GetNumberOfLightsComputed(), 3);
  EXPECT_TRUE(cache.GetUniformComputed());
  EXPECT_LE(RelativeDifference(q, Full(mesh, eta, fewer, 0.1, 32, false)), 1e-12);
}

TEST(IrradianceCache, ForgetsOnAnotherGeometryOrRefractiveIndex)
{
  TetMesh mesh;
  std::vector<double> eta;
  MakeWell(mesh, eta);
  const std::vector<LightSource> lights = EveryKind();
  IrradianceCache cache;
  std::vector<double> q;
  ASSERT_TRUE(cache.Compute(mesh, eta, lights, 0.1, 8, true, q));

  // Another refractive index in one tet under the surface.
  std::vector<double> eta2 = eta;
  eta2[mesh.GetBoundaryTriangleTets()[0]] = 1.5;
  ASSERT_TRUE(cache.Compute(mesh, eta2, lights, 0.1, 8, true, q));
  EXPECT_EQ(cache.GetNumberOfLightsComputed(), 5);
  EXPECT_TRUE(cache.GetUniformComputed());
  EXPECT_LE(RelativeDifference(q, Full(mesh, eta2, lights, 0.1, 8, true)), 1e-12);

  // The same tets moved: a new geometry revision.
  TetMesh moved;
  std::vector<double> movedEta;
  MakeWell(moved, movedEta, 0.5);
  ASSERT_TRUE(cache.Compute(moved, movedEta, lights, 0.1, 8, true, q));
  EXPECT_EQ(cache.GetNumberOfLightsComputed(), 5);
  EXPECT_TRUE(cache.GetUniformComputed());
  EXPECT_LE(RelativeDifference(q, Full(moved, movedEta, lights, 0.1, 8, true)), 1e-12);
}

TEST(IrradianceCache, RefusesBadInputLikeTheFullComputation)
{
  TetMesh mesh;
  std::vector<double> eta;
  MakeWell(mesh, eta);
  IrradianceCache cache;
  std::vector<double> q;
  std::vector<LightSource> bad = { DirectionalLight({ 0.0, 0.0, 0.0 }, { 1.0, 1.0, 1.0 }) };
  EXPECT_THROW(cache.Compute(mesh, eta, bad, 0.1, 8, true, q), Error);
  std::vector<double> shortEta(eta.begin(), eta.end() - 1);
  EXPECT_THROW(cache.Compute(mesh, shortEta, {}, 0.1, 8, true, q), Error);
  EXPECT_THROW(cache.Compute(mesh, eta, {}, -1.0, 8, true, q), Error);
}

/// The uniform light's occlusion estimate (1/N sum_k V(w_k), no Fresnel) at
/// every boundary point, with N samples and the rays of
/// ComputeBoundaryIrradiance (origin offset, reach), cast by `occluded`.
template <typename Occluded>
std::vector<double> UniformVisibility(const TetMesh& mesh, int samples, Occluded occluded)
{
  const double diag = BoundingBoxDiagonal(mesh);
  const double offset = 1e-5 * diag;
  const std::vector<double>& normals = mesh.GetPointNormals();
  std::vector<double> v;
  for (int i : mesh.GetBoundaryPoints())
  {
    const double* x = mesh.GetPoint(i);
    const double* n = &normals[3 * static_cast<size_t>(i)];
    const double rotation = UniformSampleRotation(x);
    int visible = 0;
    for (int k = 0; k < samples; ++k)
    {
      double w[3];
      HemisphereDirection(n, k, samples, rotation, w);
      const double origin[3] = { x[0] + offset * (n[0] + w[0]), x[1] + offset * (n[1] + w[1]),
        x[2] + offset * (n[2] + w[2]) };
      visible += occluded(origin, w, 2.0 * diag) ? 0 : 1;
    }
    v.push_back(static_cast<double>(visible) / samples);
  }
  return v;
}

double Rms(const std::vector<double>& a, const std::vector<double>& b)
{
  double sum = 0.0;
  for (size_t k = 0; k < a.size(); ++k)
    sum += (a[k] - b[k]) * (a[k] - b[k]);
  return std::sqrt(sum / static_cast<double>(a.size()));
}

// ShadowCaster (Embree when built with it) answers the irradiance's rays as
// RayCaster does up to grazing rays: on the well (walls shadowing its floor)
// the uniform light's 32-sample visibility differs from RayCaster's by far
// less than the 32-sample estimate's own error against a 1024-sample
// reference (the sampling's tolerance: at most a tenth of it, RMS over the
// boundary points), and at most 0.2 % of the rays are answered differently.
TEST(ShadowCaster, AnswersTheUniformLightsRaysAsRayCasterToTheSamplingsTolerance)
{
  TetMesh mesh;
  std::vector<double> eta;
  MakeWell(mesh, eta);
  ShadowCaster shadow;
  shadow.Build(mesh.GetPoints(), mesh.GetBoundaryTriangles());
  RayCaster exact;
  exact.Build(mesh.GetPoints(), mesh.GetBoundaryTriangles());
  auto byShadow = [&](const double* o, const double* w, double t) { return shadow.Occluded(o, w, t); };
  auto byExact = [&](const double* o, const double* w, double t) { return exact.Occluded(o, w, t); };
  const std::vector<double> fast = UniformVisibility(mesh, 32, byShadow);
  const std::vector<double> slow = UniformVisibility(mesh, 32, byExact);
  const std::vector<double> reference = UniformVisibility(mesh, 1024, byExact);
  const double sampling = Rms(slow, reference);
  EXPECT_GT(sampling, 0.0);
  EXPECT_LE(Rms(fast, slow), 0.1 * sampling)
    << "sampling error " << sampling << (ShadowCaster::UsesEmbree() ? " (Embree)" : "");
  double differing = 0.0;
  for (size_t k = 0; k < fast.size(); ++k)
    differing += std::abs(fast[k] - slow[k]) * 32.0;
  EXPECT_LE(differing, 0.002 * 32.0 * static_cast<double>(fast.size()));
  // Some rays are occluded (the walls), some not.
  double mean = 0.0;
  for (double v : fast)
    mean += v / static_cast<double>(fast.size());
  EXPECT_GT(mean, 0.05);
  EXPECT_LT(mean, 0.95);

  // Random rays from random points in and around the box: the same answers
  // except rays through a triangle's edge (none expected at random).
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-4.0, 12.0), d(-1.0, 1.0);
  int disagree = 0;
  for (int r = 0; r < 20000; ++r)
  {
    const double o[3] = { u(rng), u(rng), u(rng) }, w[3] = { d(rng), d(rng), d(rng) };
    const double reach = r % 2 ? 30.0 : std::numeric_limits<double>::infinity();
    disagree += shadow.Occluded(o, w, reach) != exact.Occluded(o, w, reach);
  }
  EXPECT_LE(disagree, 2);
}

TEST(ShadowCaster, RefusesBadInputAndHitsNothingWhenEmpty)
{
  ShadowCaster caster;
  const double o[3] = { 0.0, 0.0, -1.0 }, w[3] = { 0.0, 0.0, 1.0 };
  caster.Build({}, {});
  EXPECT_FALSE(caster.Occluded(o, w, 10.0));
  const std::vector<double> points = { 0, 0, 0, 1, 0, 0, 0, 1, 0 };
  EXPECT_THROW(caster.Build(points, { 0, 1, 3 }), Error);
  EXPECT_THROW(caster.Build(points, { 0, 1 }), Error);
  std::vector<double> bad = points;
  bad[4] = std::nan("");
  EXPECT_THROW(caster.Build(bad, { 0, 1, 2 }), Error);
  caster.Build(points, { 0, 1, 2 });
  const double in[3] = { 0.2, 0.2, -1.0 };
  EXPECT_TRUE(caster.Occluded(in, w, 10.0));
  EXPECT_FALSE(caster.Occluded(in, w, 0.5)); // the triangle is 1 mm away
  const double back[3] = { 0.0, 0.0, -1.0 };
  EXPECT_FALSE(caster.Occluded(in, back, 10.0)); // it lies behind
  const double zero[3] = { 0.0, 0.0, 0.0 };
  EXPECT_FALSE(caster.Occluded(in, zero, 10.0));
}

} // namespace
