// TetPaint (TransCut Sec. 5.2 painting) against a brute-force reference:
// every tet's centroid against every stroke point, the Gaussian weight, the
// documented cut-off radius and the mode formulas written out directly.

#include "Error.h"
#include "TestMeshes.h"
#include "TetPaint.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace
{

using namespace translucency;
using translucency::testing::BoxMesh;
using translucency::testing::MeshData;
using translucency::testing::Uniform01;

struct Settings
{
  std::vector<double> Stroke;
  double Width = 1.0;
  double Strength = 1.0;
  double Cutoff = 1e-6;
  TetPaint::Mode Mode = TetPaint::Mode::Set;
  std::array<double, 3> TargetA{ { 0.061, 0.97, 1.45 } };
  std::array<double, 3> TargetS{ { 0.18, 0.07, 0.03 } };
  std::array<bool, 3> Mask{ { true, true, true } };
};

struct Result
{
  std::vector<double> A, S, W;
  std::vector<int> Changed;
};

/// The brute-force reference: O(tets x stroke points), serial.
Result Reference(const MeshData& mesh, const std::vector<double>& a0,
  const std::vector<double>& s0, const Settings& p)
{
  Result r{ a0, s0, std::vector<double>(mesh.NumberOfTets(), 0.0), {} };
  const bool cutoff = p.Cutoff > 0.0;
  // w(R) = Strength exp(-R^2 / (2 Width^2)) = Cutoff.
  const double r2 = cutoff ? 2.0 * p.Width * p.Width * std::log(p.Strength / p.Cutoff) : 0.0;
  for (int t = 0; t < mesh.NumberOfTets(); ++t)
  {
    if (p.Width == 0.0 || p.Strength == 0.0 || (cutoff && p.Cutoff >= p.Strength))
    {
      continue;
    }
    double c[3] = { 0, 0, 0 };
    for (int k = 0; k < 4; ++k)
    {
      for (int d = 0; d < 3; ++d)
      {
        c[d] += mesh.Points[3 * mesh.Tets[4 * t + k] + d] / 4.0;
      }
    }
    double d2 = std::numeric_limits<double>::infinity();
    for (size_t s = 0; s < p.Stroke.size() / 3; ++s)
    {
      const double dx = c[0] - p.Stroke[3 * s], dy = c[1] - p.Stroke[3 * s + 1],
                   dz = c[2] - p.Stroke[3 * s + 2];
      d2 = std::min(d2, dx * dx + dy * dy + dz * dz);
    }
    if (cutoff && d2 > r2)
    {
      continue;
    }
    const double w = p.Strength * std::exp(-d2 / (2.0 * p.Width * p.Width));
    r.W[t] = w;
    if (w == 0.0)
    {
      continue;
    }
    bool changed = false;
    for (int ch = 0; ch < 3; ++ch)
    {
      if (!p.Mask[ch])
      {
        continue;
      }
      double v[2];
      const double old[2] = { a0[3 * t + ch], s0[3 * t + ch] };
      const double target[2] = { p.TargetA[ch], p.TargetS[ch] };
      for (int k = 0; k < 2; ++k)
      {
        if (p.Mode == TetPaint::Mode::Set)
          v[k] = (1.0 - w) * old[k] + w * target[k];
        else if (p.Mode == TetPaint::Mode::Multiply)
          v[k] = old[k] * (1.0 + w * (target[k] - 1.0));
        else
          v[k] = old[k] + w * target[k];
        v[k] = std::max(v[k], 0.0);
      }
      if (v[0] + v[1] > 0.0)
      {
        changed = changed || v[0] != old[0] || v[1] != old[1];
        r.A[3 * t + ch] = v[0];
        r.S[3 * t + ch] = v[1];
      }
    }
    if (changed)
    {
      r.Changed.push_back(t);
    }
  }
  return r;
}

Result RunPaint(const MeshData& mesh, const std::vector<double>& a0, const std::vector<double>& s0,
  const Settings& p, int threads)
{
  TetPaint paint;
  paint.SetStrokePoints(p.Stroke);
  paint.SetWidth(p.Width);
  paint.SetStrength(p.Strength);
  paint.SetCutoffWeight(p.Cutoff);
  paint.SetMode(p.Mode);
  paint.SetTargetAbsorption(p.TargetA);
  paint.SetTargetScattering(p.TargetS);
  paint.SetChannelMask(p.Mask);
  paint.SetNumberOfThreads(threads);
  Result r{ a0, s0, {}, {} };
  paint.Paint(mesh.Points, mesh.Tets, r.A, r.S, &r.W);
  r.Changed = paint.GetChangedCells();
  return r;
}

void ExpectSame(const Result& expected, const Result& actual)
{
  ASSERT_EQ(expected.W.size(), actual.W.size());
  int bad = 0;
  for (size_t t = 0; t < expected.W.size() && bad < 5; ++t)
  {
    bad += expected.W[t] != actual.W[t];
    EXPECT_EQ(expected.W[t], actual.W[t]) << "weight of tet " << t;
  }
  for (size_t k = 0; k < expected.A.size() && bad < 5; ++k)
  {
    bad += expected.A[k] != actual.A[k] || expected.S[k] != actual.S[k];
    EXPECT_EQ(expected.A[k], actual.A[k]) << "mu_a value " << k;
    EXPECT_EQ(expected.S[k], actual.S[k]) << "sigma_s' value " << k;
  }
  EXPECT_EQ(expected.Changed, actual.Changed);
}

class TetPaintTest : public ::testing::Test
{
protected:
  void SetUp() override
  {
    Mesh = BoxMesh(12, 10, 8, 12.0, 10.0, 8.0, 0.3, 7);
    std::mt19937_64 rng(11);
    A0.resize(3 * Mesh.NumberOfTets());
    S0.resize(A0.size());
    for (size_t k = 0; k < A0.size(); ++k)
    {
      A0[k] = 0.01 + 0.1 * Uniform01(rng);
      S0[k] = 0.5 + 2.0 * Uniform01(rng);
    }
  }

  /// A wiggly polyline of n points across the box (some outside it).
  std::vector<double> Stroke(int n, std::uint64_t seed) const
  {
    std::mt19937_64 rng(seed);
    std::vector<double> s;
    for (int k = 0; k < n; ++k)
    {
      const double u = static_cast<double>(k) / std::max(1, n - 1);
      s.push_back(-1.0 + 14.0 * u);
      s.push_back(5.0 + 3.0 * std::sin(6.0 * u) + 0.2 * Uniform01(rng));
      s.push_back(4.0 + 0.5 * Uniform01(rng));
    }
    return s;
  }

  MeshData Mesh;
  std::vector<double> A0, S0;
};

TEST_F(TetPaintTest, MatchesBruteForceInEveryMode)
{
  for (TetPaint::Mode mode : { TetPaint::Mode::Set, TetPaint::Mode::Multiply, TetPaint::Mode::Add })
  {
    for (double cutoff : { 1e-6, 0.0, 1e-2 })
    {
      Settings p;
      p.Stroke = Stroke(37, 3);
      p.Width = 1.3;
      p.Strength = 0.8;
      p.Cutoff = cutoff;
      p.Mode = mode;
      if (mode == TetPaint::Mode::Multiply)
      {
        p.TargetA = { { 3.0, 0.5, 1.0 } };
        p.TargetS = { { 0.2, 2.0, 1.0 } };
      }
      else if (mode == TetPaint::Mode::Add)
      {
        p.TargetA = { { 0.05, -0.5, 0.0 } }; // -0.5 clamps some mu_a to 0
        p.TargetS = { { -0.1, 0.3, 0.0 } };
      }
      SCOPED_TRACE(::testing::Message() << "mode " << static_cast<int>(mode) << ", cut-off "
                                        << cutoff);
      const Result expected = Reference(Mesh, A0, S0, p);
      ASSERT_GT(expected.Changed.size(), 20u);
      if (cutoff > 0.0)
      {
        ASSERT_LT(expected.Changed.size(), static_cast<size_t>(Mesh.NumberOfTets()));
      }
      ExpectSame(expected, RunPaint(Mesh, A0, S0, p, 1));
      ExpectSame(expected, RunPaint(Mesh, A0, S0, p, 2));
      ExpectSame(expected, RunPaint(Mesh, A0, S0, p, 3));
    }
  }
}

TEST_F(TetPaintTest, CutoffDropsOnlyWeightsBelowIt)
{
  Settings p;
  p.Stroke = Stroke(5, 4);
  p.Width = 0.9;
  p.Cutoff = 0.0;
  const Result exact = RunPaint(Mesh, A0, S0, p, 2);
  p.Cutoff = 1e-3;
  const Result cut = RunPaint(Mesh, A0, S0, p, 2);
  int dropped = 0;
  for (size_t t = 0; t < exact.W.size(); ++t)
  {
    if (exact.W[t] >= 1e-3 * (1.0 + 1e-12))
    {
      EXPECT_EQ(cut.W[t], exact.W[t]);
    }
    else if (exact.W[t] < 1e-3 * (1.0 - 1e-12))
    {
      EXPECT_EQ(cut.W[t], 0.0);
      for (int c = 0; c < 3; ++c)
      {
        EXPECT_EQ(cut.A[3 * t + c], A0[3 * t + c]);
      }
      dropped += exact.W[t] > 0.0;
    }
  }
  EXPECT_GT(dropped, 100);
}

TEST_F(TetPaintTest, LongStrokeCoarsensTheGridAndStillMatches)
{
  // 3000 points scattered through the box (and 1 mm around it) with a narrow
  // Gaussian, R = 0.26 mm: (extent / R)^3 = 62 x 46 x 39 grid cells would be
  // more than the grid allows (max(4096, 8 x 3000)), so the spacing doubles;
  // the results must not change.
  Settings p;
  std::mt19937_64 rng(5);
  for (int k = 0; k < 3000; ++k)
  {
    p.Stroke.push_back(-1.0 + 14.0 * Uniform01(rng));
    p.Stroke.push_back(-1.0 + 12.0 * Uniform01(rng));
    p.Stroke.push_back(-1.0 + 10.0 * Uniform01(rng));
  }
  p.Width = 0.05;
  p.Mask = { { true, false, true } };
  const Result expected = Reference(Mesh, A0, S0, p);
  ASSERT_GT(expected.Changed.size(), 100u);
  ASSERT_LT(expected.Changed.size(), static_cast<size_t>(Mesh.NumberOfTets()));
  ExpectSame(expected, RunPaint(Mesh, A0, S0, p, 2));
}

TEST_F(TetPaintTest, ZeroWidthOrStrengthChangesNothing)
{
  for (int k = 0; k < 2; ++k)
  {
    Settings p;
    p.Stroke = Stroke(10, 6);
    (k == 0 ? p.Width : p.Strength) = 0.0;
    const Result r = RunPaint(Mesh, A0, S0, p, 2);
    EXPECT_EQ(r.A, A0);
    EXPECT_EQ(r.S, S0);
    EXPECT_TRUE(r.Changed.empty());
    for (double w : r.W)
    {
      ASSERT_EQ(w, 0.0);
    }
  }
}

TEST_F(TetPaintTest, SetAtACentroidGivesTheTarget)
{
  const int t = 123;
  Settings p;
  p.Stroke.assign(3, 0.0);
  for (int k = 0; k < 4; ++k)
  {
    for (int d = 0; d < 3; ++d)
    {
      p.Stroke[d] += Mesh.Points[3 * Mesh.Tets[4 * t + k] + d] / 4.0;
    }
  }
  const Result r = RunPaint(Mesh, A0, S0, p, 2);
  EXPECT_EQ(r.W[t], 1.0);
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_EQ(r.A[3 * t + c], p.TargetA[c]);
    EXPECT_EQ(r.S[3 * t + c], p.TargetS[c]);
  }
}

TEST_F(TetPaintTest, FloatPointsAnd64BitIdsGiveTheSameResult)
{
  // Integer coordinates: exact in float, so both layouts give the same doubles.
  const MeshData mesh = BoxMesh(6, 6, 6, 6.0, 6.0, 6.0);
  std::vector<float> pointsF(mesh.Points.begin(), mesh.Points.end());
  std::vector<long long> offsets(mesh.NumberOfTets() + 1), ids(mesh.Tets.begin(), mesh.Tets.end());
  for (size_t t = 0; t < offsets.size(); ++t)
  {
    offsets[t] = 4 * static_cast<long long>(t);
  }
  Settings p;
  p.Stroke = { 1.0, 2.0, 3.0, 4.0, 4.0, 3.5 };
  std::vector<double> a(3 * mesh.NumberOfTets(), 0.1), s(a.size(), 1.0);
  const Result expected = Reference(mesh, a, s, p);
  TetPaint paint;
  paint.SetStrokePoints(p.Stroke);
  paint.SetTargetAbsorption(p.TargetA);
  paint.SetTargetScattering(p.TargetS);
  std::vector<double> w(mesh.NumberOfTets());
  paint.Paint(pointsF.data(), mesh.NumberOfPoints(), offsets.data(), ids.data(),
    mesh.NumberOfTets(), a.data(), s.data(), w.data());
  ExpectSame(expected, Result{ a, s, w, paint.GetChangedCells() });
}

TEST_F(TetPaintTest, NonFinitePointsGiveZeroWeight)
{
  MeshData mesh = Mesh;
  const int bad = mesh.Tets[4 * 200];
  mesh.Points[3 * bad] = std::nan("");
  for (double cutoff : { 1e-6, 0.0 })
  {
    Settings p;
    p.Stroke = Stroke(20, 8);
    p.Width = 3.0;
    p.Cutoff = cutoff;
    const Result r = RunPaint(mesh, A0, S0, p, 2);
    int touching = 0;
    for (int t = 0; t < mesh.NumberOfTets(); ++t)
    {
      const int* tv = &mesh.Tets[4 * t];
      if (tv[0] == bad || tv[1] == bad || tv[2] == bad || tv[3] == bad)
      {
        ++touching;
        EXPECT_EQ(r.W[t], 0.0) << "tet " << t;
        EXPECT_EQ(r.A[3 * t], A0[3 * t]);
      }
    }
    EXPECT_GT(touching, 0);
    EXPECT_GT(r.Changed.size(), 100u); // the other tets are painted
  }
}

TEST_F(TetPaintTest, BadInputIsNamed)
{
  auto expectError = [&](TetPaint& paint, std::vector<int> tets, const char* fragment) {
    std::vector<double> a(3 * (tets.size() / 4), 0.1), s(a.size(), 1.0);
    try
    {
      paint.Paint(Mesh.Points, tets, a, s, nullptr);
      ADD_FAILURE() << "no error, expected one containing '" << fragment << "'";
    }
    catch (const Error& e)
    {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  };
  TetPaint paint;
  expectError(paint, Mesh.Tets, "at least one stroke point");
  paint.SetStrokePoints({ 1.0, 2.0, 3.0 });
  paint.SetWidth(-1.0);
  expectError(paint, Mesh.Tets, "width -1");
  paint.SetWidth(1.0);
  paint.SetTargetAbsorption({ { 0.0, std::nan(""), 0.0 } });
  expectError(paint, Mesh.Tets, "channel G");
  paint.SetTargetAbsorption({ { 0.0, 0.0, 0.0 } });
  std::vector<int> tets = Mesh.Tets;
  tets[4 * 17 + 2] = Mesh.NumberOfPoints() + 5;
  expectError(paint, tets, "cell 17");
  paint.SetStrokePoints({ 1.0, std::numeric_limits<double>::infinity(), 3.0 });
  expectError(paint, Mesh.Tets, "stroke point 0");
}


// TetPaint::SamplePolyline: the ParaView polyline widget gives a few handles;
// the filter paints along the line through them by sampling it.
TEST(TetPaintSamplePolyline, OneSegmentIsSplitEvenly)
{
  // 10 mm at a spacing of 3 mm: ceil(10 / 3) = 4 pieces of 2.5 mm.
  const std::vector<double> samples = TetPaint::SamplePolyline({ 0, 0, 0, 10, 0, 0 }, 3.0);
  const std::vector<double> expected{ 0, 0, 0, 2.5, 0, 0, 5, 0, 0, 7.5, 0, 0, 10, 0, 0 };
  ASSERT_EQ(samples.size(), expected.size());
  for (size_t k = 0; k < expected.size(); ++k)
  {
    EXPECT_NEAR(samples[k], expected[k], 1e-12) << k;
  }
  // A spacing that divides the length exactly adds no extra point.
  EXPECT_EQ(TetPaint::SamplePolyline({ 0, 0, 0, 0, 6, 0 }, 2.0).size(), 3u * 4u);
}

TEST(TetPaintSamplePolyline, KeepsTheHandlesAndCoversTheLine)
{
  std::mt19937 random(7);
  std::uniform_real_distribution<double> coordinate(-20.0, 20.0);
  std::vector<double> handles(3 * 6);
  for (double& x : handles)
  {
    x = coordinate(random);
  }
  handles.insert(handles.end(), handles.end() - 3, handles.end()); // a repeated handle
  const double spacing = 0.7;
  const std::vector<double> samples = TetPaint::SamplePolyline(handles, spacing);
  ASSERT_EQ(samples.size() % 3, 0u);
  const size_t n = samples.size() / 3;
  auto distance = [](const double* a, const double* b) {
    return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
      (a[2] - b[2]) * (a[2] - b[2]));
  };
  // Consecutive samples at most `spacing` apart.
  for (size_t i = 0; i + 1 < n; ++i)
  {
    EXPECT_LE(distance(&samples[3 * i], &samples[3 * i + 3]), spacing * (1 + 1e-12)) << i;
  }
  // Every handle is a sample, in order.
  size_t at = 0;
  for (size_t h = 0; h < handles.size() / 3; ++h)
  {
    while (at < n && distance(&samples[3 * at], &handles[3 * h]) > 0.0)
    {
      ++at;
    }
    ASSERT_LT(at, n) << "handle " << h << " is not a sample (in order)";
  }
  // Every point of the polyline is within spacing / 2 of a sample.
  for (size_t h = 0; h + 1 < handles.size() / 3; ++h)
  {
    for (int j = 0; j <= 100; ++j)
    {
      double p[3];
      for (int c = 0; c < 3; ++c)
      {
        p[c] = handles[3 * h + c] + j / 100.0 * (handles[3 * h + 3 + c] - handles[3 * h + c]);
      }
      double nearest = std::numeric_limits<double>::infinity();
      for (size_t i = 0; i < n; ++i)
      {
        nearest = std::min(nearest, distance(p, &samples[3 * i]));
      }
      EXPECT_LE(nearest, spacing / 2 * (1 + 1e-9)) << "segment " << h << ", t = " << j / 100.0;
    }
  }
  // One point or none: unchanged.
  EXPECT_EQ(TetPaint::SamplePolyline({ 1, 2, 3 }, 0.1), (std::vector<double>{ 1, 2, 3 }));
  EXPECT_TRUE(TetPaint::SamplePolyline({}, 0.1).empty());
}

TEST(TetPaintSamplePolyline, BadInputIsAnErrorNamingIt)
{
  auto expectError = [](const std::vector<double>& points, double spacing, std::int64_t limit,
                       const char* fragment) {
    try
    {
      TetPaint::SamplePolyline(points, spacing, limit);
      ADD_FAILURE() << "no error, expected one containing '" << fragment << "'";
    }
    catch (const Error& e)
    {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  };
  const std::vector<double> line{ 0, 0, 0, 1, 0, 0 };
  expectError(line, 0.0, 100, "spacing 0 mm");
  expectError(line, -1.0, 100, "spacing -1 mm");
  expectError(line, std::nan(""), 100, "spacing nan mm");
  expectError(line, std::numeric_limits<double>::infinity(), 100, "spacing inf mm");
  expectError({ 0, 0, 0, 1, std::nan(""), 0 }, 0.1, 100, "stroke point 1");
  expectError({ 0, 0, 0, 1 }, 0.1, 100, "4 stroke coordinates");
  expectError({ 0, 0, 0, 1e6, 0, 0 }, 1e-3, 1000, "more than 1000");
}

} // namespace
