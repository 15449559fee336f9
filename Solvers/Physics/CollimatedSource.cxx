#include "CollimatedSource.h"

#include "Error.h"
#include "ExponentialMoments.h"
#include "Fresnel.h"
#include "RayCaster.h"
#include "ShadowCaster.h"
#include "TetMesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <sstream>

namespace translucency
{

namespace
{

/// Rules on the reference tet, in barycentric coordinates: the tet split
/// `level` times into 8 of equal volume by its edge midpoints (4 corner tets
/// and the octahedron cut along the diagonal m02-m13), each with the
/// symmetric 4-point rule of degree 2 (a = (5 + 3 sqrt 5) / 20,
/// b = (5 - sqrt 5) / 20). Level L has 4 x 8^L points of equal weight.
struct TetRules
{
  static constexpr int MaxLevel = 4;
  std::vector<std::array<double, 4>> Points[MaxLevel + 1];
  /// The sub-tets of level 1 by their nodes: 0-3 the tet's vertices, 4-9 the
  /// midpoints of the edges 01, 02, 03, 12, 13, 23. Point 4 s + k of level 1
  /// is a Sub[s][k] + b (the other three nodes of sub-tet s), in barycentric
  /// coordinates (LevelOneIntegrals factorises its exponentials by them).
  static constexpr int Sub[8][4] = { { 0, 4, 5, 6 }, { 1, 4, 7, 8 }, { 2, 5, 7, 9 },
    { 3, 6, 8, 9 }, { 5, 8, 4, 7 }, { 5, 8, 7, 9 }, { 5, 8, 9, 6 }, { 5, 8, 6, 4 } };
  /// The vertices of the edge of each midpoint node 4-9.
  static constexpr int Edge[6][2] = { { 0, 1 }, { 0, 2 }, { 0, 3 }, { 1, 2 }, { 1, 3 }, { 2, 3 } };
  /// The symmetric 4-point rule of degree 2: a at its own vertex, b at the others.
  static constexpr double A = 0.5854101966249685, B = 0.1381966011250105;

  TetRules()
  {
    using Tet = std::array<std::array<double, 4>, 4>;
    std::vector<Tet> tets(1);
    for (int k = 0; k < 4; ++k)
    {
      for (int j = 0; j < 4; ++j)
      {
        tets[0][k][j] = k == j ? 1.0 : 0.0;
      }
    }
    const double a = A, b = B;
    for (int level = 0; level <= MaxLevel; ++level)
    {
      for (const Tet& t : tets)
      {
        for (int k = 0; k < 4; ++k)
        {
          std::array<double, 4> p{};
          for (int m = 0; m < 4; ++m)
          {
            for (int j = 0; j < 4; ++j)
            {
              p[j] += (m == k ? a : b) * t[m][j];
            }
          }
          Points[level].push_back(p);
        }
      }
      if (level == MaxLevel)
      {
        break;
      }
      std::vector<Tet> finer;
      finer.reserve(8 * tets.size());
      for (const Tet& t : tets)
      {
        std::array<double, 4> v[10];
        for (int k = 0; k < 4; ++k)
        {
          v[k] = t[k];
        }
        for (int m = 0; m < 6; ++m)
        {
          for (int j = 0; j < 4; ++j)
          {
            v[4 + m][j] = 0.5 * (t[Edge[m][0]][j] + t[Edge[m][1]][j]);
          }
        }
        // Midpoints 4..9: 01, 02, 03, 12, 13, 23.
        for (const auto& s : Sub)
        {
          finer.push_back(Tet{ v[s[0]], v[s[1]], v[s[2]], v[s[3]] });
        }
      }
      tets.swap(finer);
    }
  }
};

const TetRules& Rules()
{
  static const TetRules rules;
  return rules;
}

/// ln E_c + i phase as the exponent type: double drops the phase (k = 0).
template <class T>
T ExponentOf(double logE, double phase);
template <>
double ExponentOf<double>(double logE, double)
{
  return logE;
}
template <>
std::complex<double> ExponentOf<std::complex<double>>(double logE, double phase)
{
  return { logE, phase };
}

/// g exp(i phase) as T: double drops the phase (k = 0).
template <class T>
T Modulated(double g, double phase);
template <>
double Modulated<double>(double g, double)
{
  return g;
}
template <>
std::complex<double> Modulated<std::complex<double>>(double g, double phase)
{
  return g * std::polar(1.0, phase);
}

/// The quadrature level of one beam and channel on one tet (VisitTet): the
/// smallest (<= TetRules::MaxLevel) at which the exponent ln E_c - i k path
/// varies by at most 0.5 across a sub-tet (k = 0: the real range alone, as
/// the continuous-wave load); 1 where E_c is 0 at some vertex (E_c then
/// interpolated linearly). `positive`: E_c > 0 at every vertex, with its
/// logarithms in logE; `any`: at some vertex.
int QuadratureLevel(const double e[4], const double path[4], double wavenumber, double logE[4],
  bool& positive, bool& any)
{
  positive = true;
  any = false;
  for (int k = 0; k < 4; ++k)
  {
    positive = positive && e[k] > 0.0;
    any = any || e[k] > 0.0;
    logE[k] = e[k] > 0.0 ? std::log(e[k]) : 0.0;
  }
  if (!positive)
  {
    return 1;
  }
  const double real = std::max(std::max(logE[0], logE[1]), std::max(logE[2], logE[3])) -
    std::min(std::min(logE[0], logE[1]), std::min(logE[2], logE[3]));
  const double imaginary = wavenumber *
    (std::max(std::max(path[0], path[1]), std::max(path[2], path[3])) -
      std::min(std::min(path[0], path[1]), std::min(path[2], path[3])));
  const double range = imaginary > 0.0 ? std::hypot(real, imaginary) : real;
  int level = 0;
  while (level < TetRules::MaxLevel && range > 0.5 * (1 << level))
  {
    ++level;
  }
  return level;
}

/**
 * The quadrature of one beam and channel over one tet: E_c interpolated
 * log-linearly between the vertex values e[4] (linearly if one is 0), the
 * optical path linearly between path[4], at QuadratureLevel() capped at
 * `maxLevel`. Calls visit(g, l, pathAtPoint, weight) per point (g the
 * interpolated E_c, l the barycentric coordinates, weight = volume /
 * points) and returns the weight, or 0 if E_c is 0 at all four vertices (no
 * call).
 */
template <class Visit>
double VisitTet(const double e[4], const double path[4], double wavenumber, double volume,
  Visit&& visit, int maxLevel = TetRules::MaxLevel)
{
  double logE[4];
  bool positive = true, any = false;
  const int level =
    std::min(maxLevel, QuadratureLevel(e, path, wavenumber, logE, positive, any));
  if (!any)
  {
    return 0.0;
  }
  const std::vector<std::array<double, 4>>& points = Rules().Points[level];
  const double weight = volume / static_cast<double>(points.size());
  for (const std::array<double, 4>& l : points)
  {
    const double g = positive
      ? std::exp(l[0] * logE[0] + l[1] * logE[1] + l[2] * logE[2] + l[3] * logE[3])
      : l[0] * e[0] + l[1] * e[1] + l[2] * e[2] + l[3] * e[3];
    visit(g, l, l[0] * path[0] + l[1] * path[1] + l[2] * path[2] + l[3] * path[3], weight);
  }
  return weight;
}

/// From this quadrature level on (128 points and more), the loads take the
/// exact integrals of the log-linear E_c instead (ExponentialMoments.h):
/// the quadrature's cost grows 8x a level, the exact form's does not.
constexpr int ExactFromLevel = 2;

/**
 * The integrals over one tet of E_c exp(-i k path) (`total`) and of
 * lambda_j times it (moment[j]), E_c and the path interpolated as in
 * VisitTet: exactly (ExponentialMoments, z_j = ln E_c,j - i k path_j) where
 * the quadrature would need level ExactFromLevel or more, else by the
 * quadrature. T is double for k = 0 (the imaginary part is dropped).
 * Returns false (and zeros) if E_c is 0 at all four vertices.
 */
template <class T>
bool TetIntegrals(const double e[4], const double path[4], double wavenumber, double volume,
  T& total, T moment[4])
{
  double logE[4];
  bool positive = true, any = false;
  const int level = QuadratureLevel(e, path, wavenumber, logE, positive, any);
  total = T(0.0);
  for (int j = 0; j < 4; ++j)
  {
    moment[j] = T(0.0);
  }
  if (!any)
  {
    return false;
  }
  if (positive && level >= ExactFromLevel)
  {
    T z[4];
    for (int j = 0; j < 4; ++j)
    {
      z[j] = ExponentOf<T>(logE[j], -wavenumber * path[j]);
    }
    ExponentialMoments(z, volume, total, moment);
    return true;
  }
  const double weight = VisitTet(e, path, wavenumber, volume,
    [&](double g, const std::array<double, 4>& l, double p, double) {
      const T value = Modulated<T>(g, -wavenumber * p);
      total += value;
      for (int j = 0; j < 4; ++j)
      {
        moment[j] += value * l[j];
      }
    });
  total *= weight;
  for (int j = 0; j < 4; ++j)
  {
    moment[j] *= weight;
  }
  return true;
}

/**
 * The level-1 quadrature of VisitTet (32 points) for a positive E_c (e[4],
 * with logarithms logE[4]): the same sums, with 4 exponentials and 12
 * square roots instead of 32 exponentials. Point (s, k) of the rule is
 * a n_k + b (n_0 + n_1 + n_2 + n_3 - n_k) over the nodes n of sub-tet s
 * (TetRules::Sub), so with zeta_n the exponent at node n,
 *   exp(z . l) = prod_m exp(b zeta_{n_m}) x exp((a - b) zeta_{n_k});
 * at a vertex exp((a - b) zeta) = E_c / exp(b zeta)^4 (a + 3 b = 1), and at
 * a midpoint, where zeta is the mean of its edge's vertices' values, each
 * exponential is the geometric mean of its vertices'. Rounding differs from
 * the direct exponentials by a few ulps (test:
 * `CollimatedBeam.FastEqualsTheReferenceOnTheBunny`).
 */
void LevelOneIntegrals(const double e[4], const double logE[4], double volume, double& total,
  double moment[4])
{
  double own[10], other[10];
  for (int n = 0; n < 4; ++n)
  {
    other[n] = std::exp(TetRules::B * logE[n]);
    const double square = other[n] * other[n];
    own[n] = e[n] / (square * square);
  }
  for (int m = 0; m < 6; ++m)
  {
    const int i = TetRules::Edge[m][0], j = TetRules::Edge[m][1];
    own[4 + m] = std::sqrt(own[i] * own[j]);
    other[4 + m] = std::sqrt(other[i] * other[j]);
  }
  const std::vector<std::array<double, 4>>& points = Rules().Points[1];
  total = 0.0;
  for (int j = 0; j < 4; ++j)
  {
    moment[j] = 0.0;
  }
  for (int s = 0; s < 8; ++s)
  {
    const int* n = TetRules::Sub[s];
    const double base = other[n[0]] * other[n[1]] * other[n[2]] * other[n[3]];
    for (int k = 0; k < 4; ++k)
    {
      const double g = base * own[n[k]];
      const std::array<double, 4>& l = points[4 * static_cast<size_t>(s) + k];
      total += g;
      for (int j = 0; j < 4; ++j)
      {
        moment[j] += g * l[j];
      }
    }
  }
  const double weight = volume / static_cast<double>(points.size());
  total *= weight;
  for (int j = 0; j < 4; ++j)
  {
    moment[j] *= weight;
  }
}

/**
 * TetIntegrals<double> (continuous wave) with the logarithms of E_c given
 * (logE[k] = ln e[k] where e[k] > 0, taken once per point by BeamLoads
 * instead of four times per tet): the same rule (VisitTet's levels 0 and 1,
 * the exact integrals from ExactFromLevel on), the level-1 quadrature by
 * LevelOneIntegrals.
 */
bool ContinuousWaveTetIntegrals(const double e[4], const double logE[4], double volume,
  double& total, double moment[4])
{
  bool positive = true, any = false;
  for (int k = 0; k < 4; ++k)
  {
    positive = positive && e[k] > 0.0;
    any = any || e[k] > 0.0;
  }
  if (!any)
  {
    total = 0.0;
    for (int j = 0; j < 4; ++j)
    {
      moment[j] = 0.0;
    }
    return false;
  }
  const double range = std::max(std::max(logE[0], logE[1]), std::max(logE[2], logE[3])) -
    std::min(std::min(logE[0], logE[1]), std::min(logE[2], logE[3]));
  // QuadratureLevel's levels: 0 up to a range of 0.5, 1 up to 1, then exact.
  static_assert(ExactFromLevel == 2, "the levels below follow QuadratureLevel");
  if (!positive)
  {
    const double path[4] = { 0.0, 0.0, 0.0, 0.0 };
    return TetIntegrals(e, path, 0.0, volume, total, moment);
  }
  if (!(range > 0.5))
  {
    // Level 0: VisitTet's 4 points, as TetIntegrals sums them.
    const std::vector<std::array<double, 4>>& points = Rules().Points[0];
    total = 0.0;
    for (int j = 0; j < 4; ++j)
    {
      moment[j] = 0.0;
    }
    for (const std::array<double, 4>& l : points)
    {
      const double g =
        std::exp(l[0] * logE[0] + l[1] * logE[1] + l[2] * logE[2] + l[3] * logE[3]);
      total += g;
      for (int j = 0; j < 4; ++j)
      {
        moment[j] += g * l[j];
      }
    }
    const double weight = volume / static_cast<double>(points.size());
    total *= weight;
    for (int j = 0; j < 4; ++j)
    {
      moment[j] *= weight;
    }
    return true;
  }
  if (range > 1.0)
  {
    ExponentialMoments(logE, volume, total, moment);
  }
  else
  {
    LevelOneIntegrals(e, logE, volume, total, moment);
  }
  return true;
}

/// CollimatedEvaluation::Reference's TetIntegrals<double>: the logarithms
/// per tet, VisitTet's direct exponentials below ExactFromLevel and the
/// memoised recursion of ExponentialDividedDifference from it on.
bool ReferenceTetIntegrals(const double e[4], double volume, double& total, double moment[4])
{
  double logE[4];
  bool positive = true, any = false;
  const double path[4] = { 0.0, 0.0, 0.0, 0.0 };
  if (QuadratureLevel(e, path, 0.0, logE, positive, any) < ExactFromLevel || !positive)
  {
    return TetIntegrals(e, path, 0.0, volume, total, moment);
  }
  // Hermite-Genocchi: int_T exp(z . lambda) dV = 6 V exp[z_0..z_3] and
  // int_T lambda_k exp(z . lambda) dV = 6 V exp[z_0..z_3, z_k].
  double nodes[5] = { logE[0], logE[1], logE[2], logE[3], 0.0 };
  total = 6.0 * volume * ExponentialDividedDifference(nodes, 4);
  for (int k = 0; k < 4; ++k)
  {
    nodes[4] = logE[k];
    moment[k] = 6.0 * volume * ExponentialDividedDifference(nodes, 5);
  }
  return true;
}

/// The vertex values of beam `beam`, channel c, on tet v: E_c and the path.
void TetValues(const CollimatedSource::Beam& beam, const int* v, int c, double e[4],
  double path[4])
{
  for (int k = 0; k < 4; ++k)
  {
    e[k] = beam.Fluence[3 * static_cast<size_t>(v[k]) + c];
    path[k] = beam.OpticalPath[v[k]];
  }
}

/**
 * The time load of one beam and channel on one tet (ComputeCollimatedTimeLoad):
 * the continuous-wave load sigma int_T lambda_k E_c dV of TetIntegrals, split
 * over the step times [first, end) by the arrival time path / c at the
 * quadrature's points (a hat function in time between the two step times
 * around each arrival), added to w[12 (j - first) + 3 k] (w offset by the
 * channel). Where the load is the exact integral (level ExactFromLevel or
 * more) the split is the quadrature's at level ExactFromLevel, scaled so that
 * the times sum to the exact load: the time integral is the continuous-wave
 * load in either case. `share` is scratch space.
 */
void DepositInTime(const double e[4], const double path[4], double volume, double sigma,
  const std::vector<double>& times, int first, int end, double* w, std::vector<double>& share)
{
  double logE[4];
  bool positive = true, any = false;
  const bool exact =
    QuadratureLevel(e, path, 0.0, logE, positive, any) >= ExactFromLevel && positive;
  const int last = static_cast<int>(times.size()) - 1;
  share.assign(4 * static_cast<size_t>(end - first), 0.0);
  double quadrature[4] = { 0.0, 0.0, 0.0, 0.0 };
  VisitTet(e, path, 0.0, volume,
    [&](double g, const std::array<double, 4>& l, double p, double weight) {
      const double scaled = sigma * weight * g;
      for (int k = 0; k < 4; ++k)
      {
        quadrature[k] += scaled * l[k];
      }
      const double tau = p / SpeedOfLightMillimetresPerNanosecond;
      const int j =
        static_cast<int>(std::upper_bound(times.begin(), times.end(), tau) - times.begin());
      int j0 = 0, j1 = 0;
      double share1 = 0.0;
      if (j > last)
      {
        return; // arrives after the last time: not in this run
      }
      if (j > 0)
      {
        j0 = j - 1;
        j1 = j;
        share1 = (tau - times[j0]) / (times[j1] - times[j0]);
      }
      // (Inside [first, end) up to rounding of the interpolation.)
      j0 = std::max(first, std::min(j0, end - 1));
      j1 = std::max(first, std::min(j1, end - 1));
      for (int k = 0; k < 4; ++k)
      {
        share[4 * static_cast<size_t>(j0 - first) + k] += (1.0 - share1) * scaled * l[k];
        share[4 * static_cast<size_t>(j1 - first) + k] += share1 * scaled * l[k];
      }
    },
    exact ? ExactFromLevel : TetRules::MaxLevel);
  double factor[4] = { 1.0, 1.0, 1.0, 1.0 };
  if (exact)
  {
    double total = 0.0, moment[4];
    TetIntegrals(e, path, 0.0, volume, total, moment);
    for (int k = 0; k < 4; ++k)
    {
      factor[k] = quadrature[k] > 0.0 ? sigma * moment[k] / quadrature[k] : 0.0;
    }
  }
  for (int j = 0; j < end - first; ++j)
  {
    for (int k = 0; k < 4; ++k)
    {
      w[12 * static_cast<size_t>(j) + 3 * k] += factor[k] * share[4 * static_cast<size_t>(j) + k];
    }
  }
}

} // namespace

std::vector<LightSource> NonCollimatedLights(const std::vector<LightSource>& lights)
{
  std::vector<LightSource> rest;
  for (const LightSource& light : lights)
  {
    if (light.Type != LightSource::Kind::Directional)
    {
      rest.push_back(light);
    }
  }
  return rest;
}

namespace
{
/**
 * What ComputeCollimatedSource casts its rays against, built from the mesh's
 * geometry alone: the closest-hit caster of the entry rays (RayCaster), the
 * shadow caster of the entering power (ShadowCaster, as
 * ComputeTriangleCornerIrradiance builds it), the boundary triangles' normals
 * and the box's diagonal. A relight or a paint casts new rays on the same
 * surface, so the last mesh's is kept (BoundaryCastersOf).
 */
struct BoundaryCasters
{
  std::uint64_t Revision = 0;
  RayCaster Rays;
  ShadowCaster Shadows;
  bool HasShadows = false;
  std::vector<double> TriangleNormals;
  double Diagonal = 0.0;
};

/**
 * The BoundaryCasters of `mesh`: the kept ones when they were built for its
 * geometry (TetMesh::GetGeometryRevision(): unique per SetGeometry() and
 * UpdatePoints() in the process, shared by copies), else new ones, which
 * replace them (one mesh kept: the memory of one boundary's trees; the
 * shadow tree is built when first asked for). Thread-safe; the casters
 * themselves are read-only once returned.
 */
std::shared_ptr<const BoundaryCasters> BoundaryCastersOf(const TetMesh& mesh, bool shadows)
{
  static std::mutex mutex;
  // Never destroyed (as ShadowCaster's Embree device): an Embree scene
  // released during the static destruction at exit could outlive Embree.
  static auto* const kept = new std::shared_ptr<const BoundaryCasters>();
  std::lock_guard<std::mutex> lock(mutex);
  const std::uint64_t revision = mesh.GetGeometryRevision();
  if (*kept && revision != 0 && (*kept)->Revision == revision && ((*kept)->HasShadows || !shadows))
  {
    return *kept;
  }
  auto made = std::make_shared<BoundaryCasters>();
  made->Revision = revision;
  made->Rays.Build(mesh.GetPoints(), mesh.GetBoundaryTriangles());
  made->HasShadows = shadows;
  if (shadows)
  {
    made->Shadows.Build(mesh.GetPoints(), mesh.GetBoundaryTriangles());
  }
  made->TriangleNormals = BoundaryTriangleNormals(mesh);
  made->Diagonal = BoundingBoxDiagonal(mesh);
  *kept = made;
  return made;
}

/// ComputeCollimatedSource: the power of the beams transmitted into the
/// object: ComputeTriangleCornerIrradiance's corner values of the beams
/// alone (AddLightCornerIrradiance, light by light, on the kept shadow
/// caster), integrated over the boundary triangles.
void EnteringPower(const TetMesh& mesh, const std::vector<double>& tetEta,
  const std::vector<LightSource>& beams, bool shadows, const BoundaryCasters& casters,
  CollimatedSource& out)
{
  CheckBoundaryTriangleEta(mesh, tetEta);
  std::vector<double> cornerQ(9 * static_cast<size_t>(mesh.GetNumberOfBoundaryTriangles()), 0.0);
  for (const LightSource& beam : beams)
  {
    AddLightCornerIrradiance(mesh, tetEta, casters.TriangleNormals, beam, shadows,
      shadows ? &casters.Shadows : nullptr, casters.Diagonal, cornerQ);
  }
  const std::vector<double>& areas = mesh.GetBoundaryTriangleAreas();
  for (int f = 0; f < mesh.GetNumberOfBoundaryTriangles(); ++f)
  {
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      const double* q = &cornerQ[9 * static_cast<size_t>(f) + c];
      out.Entering[c] += areas[f] * (q[0] + q[3] + q[6]) / 3.0;
    }
  }
}

/// ComputeCollimatedSource: E_c of every beam at the points (zero where the
/// ray toward the light leaves through no entry face, or is shadowed) and
/// the optical path to the entry point.
void BeamFieldAtPoints(const TetMesh& mesh, const OpticalProperties& material,
  const std::vector<LightSource>& beams, bool shadows, const BoundaryCasters& casters,
  CollimatedSource& out)
{
  const int numPoints = mesh.GetNumberOfPoints();
  const std::vector<double>& tetEta = material.RefractiveIndex;
  const std::vector<double>& muA = material.AbsorptionCoefficient;
  const std::vector<double>& muS = material.ReducedScatteringCoefficient;
  const double diag = casters.Diagonal;
  const double offset = 1e-5 * diag;
  // Every ray's origin is moved by one fixed, generic vector of 1e-9 of the
  // diagonal ((1, sqrt 2, sqrt 3) / sqrt 6: no small-integer relation between
  // its components, so it lies in no plane of a structured mesh's lattice).
  // A ray from a grid point of a structured mesh lit along a lattice
  // direction (the default key light (0, -1, -1) on a box of Kuhn cells)
  // otherwise runs exactly through mesh edges or along face planes, where
  // the entry triangle is a tie that rounding in the triangle's vertex order
  // and the ray caster's triangle order decide: the numbering, so another
  // partition or a renumbered mesh took another face (a collimated fluence
  // of 0 instead of the serial value where the beam grazes an edge: Fluence
  // up to 70 % off; Documentation/Parallel.md). 1e-9 is far above the
  // rounding of the origin (~1e-16 of the diagonal) and far below any mesh
  // feature; the depth below the entry plane is measured from the point
  // itself, so E_c changes only where the entry face was such a tie.
  const double generic = 1e-9 * diag / std::sqrt(6.0);
  const double shift[3] = { generic, generic * std::sqrt(2.0), generic * std::sqrt(3.0) };
  const std::vector<int>& triangles = mesh.GetBoundaryTriangles();
  const std::vector<int>& triangleTets = mesh.GetBoundaryTriangleTets();
  const RayCaster& caster = casters.Rays;
  const std::vector<double>& pointNormals = mesh.GetPointNormals();

  // E_c at the points.
#pragma omp parallel for schedule(dynamic, 256)
  for (int i = 0; i < numPoints; ++i)
  {
    const double* x = mesh.GetPoint(i);
    double origin[3] = { x[0] + shift[0], x[1] + shift[1], x[2] + shift[2] };
    if (mesh.IsBoundaryPoint(i))
    {
      const double* n = &pointNormals[3 * static_cast<size_t>(i)];
      for (int k = 0; k < 3; ++k)
      {
        origin[k] -= offset * n[k]; // just inside
      }
    }
    for (size_t index = 0; index < beams.size(); ++index)
    {
      const LightSource& beam = beams[index];
      CollimatedSource::Beam& field = out.Beams[index];
      const double len = std::sqrt(beam.Direction[0] * beam.Direction[0] +
        beam.Direction[1] * beam.Direction[1] + beam.Direction[2] * beam.Direction[2]);
      const double w[3] = { -beam.Direction[0] / len, -beam.Direction[1] / len,
        -beam.Direction[2] / len };
      double t = 0.0;
      int f = -1;
      if (!caster.FirstHit(origin, w, std::numeric_limits<double>::infinity(), t, f))
      {
        continue;
      }
      // The entry triangle's outward normal.
      const int* tri = &triangles[3 * static_cast<size_t>(f)];
      const double* a = mesh.GetPoint(tri[0]);
      const double* b = mesh.GetPoint(tri[1]);
      const double* c3 = mesh.GetPoint(tri[2]);
      const double e1[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
      const double e2[3] = { c3[0] - a[0], c3[1] - a[1], c3[2] - a[2] };
      double n[3] = { e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
        e1[0] * e2[1] - e1[1] * e2[0] };
      const double nl = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      if (!(nl > 0.0))
      {
        continue;
      }
      const double cosIn = (n[0] * w[0] + n[1] * w[1] + n[2] * w[2]) / nl;
      if (!(cosIn > 0.0))
      {
        continue; // not an exit towards the light: no entry along this ray
      }
      if (shadows)
      {
        const double p[3] = { origin[0] + t * w[0] + offset * (n[0] / nl + w[0]),
          origin[1] + t * w[1] + offset * (n[1] / nl + w[1]),
          origin[2] + t * w[2] + offset * (n[2] / nl + w[2]) };
        if (caster.Occluded(p, w, 2.0 * diag))
        {
          continue;
        }
      }
      const int tet = triangleTets[f];
      const double eta = tetEta[tet];
      const double sin2 = (1.0 - cosIn * cosIn) / (eta * eta);
      const double cosT = std::sqrt(std::max(0.0, 1.0 - sin2));
      if (!(cosT > 0.0))
      {
        continue;
      }
      // Depth of x below the entry plane (from x itself, not the shifted
      // origin), then the refracted path to that depth.
      const double depth =
        std::max(0.0, (n[0] * (a[0] - x[0]) + n[1] * (a[1] - x[1]) + n[2] * (a[2] - x[2])) / nl);
      const double s = depth / cosT;
      const double entering = cosIn * Fresnel::Transmittance(cosIn, eta) / cosT;
      field.OpticalPath[i] = eta * s;
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        const double muT = muA[3 * static_cast<size_t>(tet) + c] +
          muS[3 * static_cast<size_t>(tet) + c];
        const double value = beam.Power[c] * entering * std::exp(-muT * s);
        field.Fluence[3 * static_cast<size_t>(i) + c] = value;
        out.Fluence[3 * static_cast<size_t>(i) + c] += value;
      }
    }
  }
}

/// ComputeCollimatedSource, loads: integral of mu_s' E_c phi_a per tet and
/// beam, then scattered to the points (and mu_a E_c, the absorbed power).
void BeamLoads(const TetMesh& mesh, const OpticalProperties& material,
  CollimatedEvaluation evaluation, CollimatedSource& out)
{
  const int numTets = mesh.GetNumberOfTets();
  const std::vector<double>& muA = material.AbsorptionCoefficient;
  const std::vector<double>& muS = material.ReducedScatteringCoefficient;
  std::vector<double> tetLoad(12 * static_cast<size_t>(numTets), 0.0);
  std::vector<double> tetAbsorbed(3 * static_cast<size_t>(numTets), 0.0);
  // ln E_c per point, beam and channel (0 where E_c = 0, as QuadratureLevel).
  const int numPoints = mesh.GetNumberOfPoints();
  const bool fast = evaluation == CollimatedEvaluation::Fast;
  std::vector<std::vector<double>> logs(out.Beams.size());
  for (size_t b = 0; fast && b < out.Beams.size(); ++b)
  {
    const std::vector<double>& fluence = out.Beams[b].Fluence;
    std::vector<double>& log = logs[b];
    log.resize(fluence.size());
#pragma omp parallel for schedule(static)
    for (int i = 0; i < 3 * numPoints; ++i)
    {
      log[i] = fluence[i] > 0.0 ? std::log(fluence[i]) : 0.0;
    }
  }
  // (Dynamic: the tets' costs differ by their rule, and the lit tets cluster.)
#pragma omp parallel for schedule(dynamic, 256)
  for (int t = 0; t < numTets; ++t)
  {
    const int* v = mesh.GetTet(t);
    const double volume = mesh.GetTetVolume(t);
    for (size_t b = 0; b < out.Beams.size(); ++b)
    {
      const std::vector<double>& fluence = out.Beams[b].Fluence;
      const std::vector<double>& log = logs[b];
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        double e[4], logE[4];
        for (int k = 0; k < 4; ++k)
        {
          e[k] = fluence[3 * static_cast<size_t>(v[k]) + c];
          logE[k] = fast ? log[3 * static_cast<size_t>(v[k]) + c] : 0.0;
        }
        double moment[4], total = 0.0;
        const bool lit = fast ? ContinuousWaveTetIntegrals(e, logE, volume, total, moment)
                              : ReferenceTetIntegrals(e, volume, total, moment);
        if (!lit)
        {
          continue;
        }
        const double sigma = muS[3 * static_cast<size_t>(t) + c];
        for (int k = 0; k < 4; ++k)
        {
          tetLoad[12 * static_cast<size_t>(t) + 3 * k + c] += sigma * moment[k];
        }
        tetAbsorbed[3 * static_cast<size_t>(t) + c] += muA[3 * static_cast<size_t>(t) + c] * total;
      }
    }
  }
  for (int t = 0; t < numTets; ++t)
  {
    const int* v = mesh.GetTet(t);
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      for (int k = 0; k < 4; ++k)
      {
        const double load = tetLoad[12 * static_cast<size_t>(t) + 3 * k + c];
        out.Load[3 * static_cast<size_t>(v[k]) + c] += load;
        out.Scattered[c] += load;
      }
      out.Absorbed[c] += tetAbsorbed[3 * static_cast<size_t>(t) + c];
    }
  }
}

} // namespace

CollimatedSource ComputeCollimatedSource(const TetMesh& mesh, const OpticalProperties& material,
  const std::vector<LightSource>& lights, bool shadows, CollimatedEvaluation evaluation)
{
  const int numPoints = mesh.GetNumberOfPoints();
  const int numTets = mesh.GetNumberOfTets();
  material.Validate(numTets);
  std::vector<LightSource> beams;
  for (size_t l = 0; l < lights.size(); ++l)
  {
    ValidateLight(lights[l], l);
    if (lights[l].Type == LightSource::Kind::Directional)
    {
      beams.push_back(lights[l]);
    }
  }
  CollimatedSource out;
  out.Fluence.assign(3 * static_cast<size_t>(numPoints), 0.0);
  out.Load.assign(3 * static_cast<size_t>(numPoints), 0.0);
  out.Beams.resize(beams.size());
  for (CollimatedSource::Beam& beam : out.Beams)
  {
    beam.Fluence.assign(3 * static_cast<size_t>(numPoints), 0.0);
    beam.OpticalPath.assign(static_cast<size_t>(numPoints), 0.0);
  }
  if (beams.empty() || mesh.GetNumberOfBoundaryTriangles() == 0)
  {
    return out;
  }
  const std::vector<double>& tetEta = material.RefractiveIndex;

  // Entering power: the triangle-integrated irradiance of the beams.
  if (evaluation == CollimatedEvaluation::Reference)
  {
    std::vector<double> cornerQ;
    ComputeTriangleCornerIrradiance(mesh, tetEta, beams, 0.0, 0, shadows, cornerQ);
    const std::vector<double>& areas = mesh.GetBoundaryTriangleAreas();
    for (int f = 0; f < mesh.GetNumberOfBoundaryTriangles(); ++f)
    {
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        const double* q = &cornerQ[9 * static_cast<size_t>(f) + c];
        out.Entering[c] += areas[f] * (q[0] + q[3] + q[6]) / 3.0;
      }
    }
    // The casters built anew (not the kept ones).
    BoundaryCasters casters;
    casters.Rays.Build(mesh.GetPoints(), mesh.GetBoundaryTriangles());
    casters.Diagonal = BoundingBoxDiagonal(mesh);
    BeamFieldAtPoints(mesh, material, beams, shadows, casters, out);
  }
  else
  {
    const std::shared_ptr<const BoundaryCasters> casters = BoundaryCastersOf(mesh, shadows);
    EnteringPower(mesh, tetEta, beams, shadows, *casters, out);
    BeamFieldAtPoints(mesh, material, beams, shadows, *casters, out);
  }

  // Loads: integral of mu_s' E_c phi_a per tet and beam, then scattered to
  // the points.
  BeamLoads(mesh, material, evaluation, out);
  return out;
}

void ComputeCollimatedFrequencyLoad(const TetMesh& mesh, const OpticalProperties& material,
  const CollimatedSource& source, double wavenumber, std::vector<std::complex<double>>& load,
  std::vector<std::complex<double>>& fluence)
{
  if (!std::isfinite(wavenumber) || wavenumber < 0.0)
  {
    std::ostringstream out;
    out << "collimated source: wavenumber omega / c = " << wavenumber
        << " rad/mm (expected a finite value >= 0)";
    throw Error(out.str());
  }
  const int numPoints = mesh.GetNumberOfPoints();
  const int numTets = mesh.GetNumberOfTets();
  material.Validate(numTets);
  load.assign(3 * static_cast<size_t>(numPoints), 0.0);
  fluence.assign(3 * static_cast<size_t>(numPoints), 0.0);
  for (const CollimatedSource::Beam& beam : source.Beams)
  {
    if (beam.Fluence.size() != 3 * static_cast<size_t>(numPoints) ||
      beam.OpticalPath.size() != static_cast<size_t>(numPoints))
    {
      throw Error("collimated source: the beams do not match the mesh's points");
    }
    for (int i = 0; i < numPoints; ++i)
    {
      const std::complex<double> phase = std::polar(1.0, -wavenumber * beam.OpticalPath[i]);
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        fluence[3 * static_cast<size_t>(i) + c] += beam.Fluence[3 * static_cast<size_t>(i) + c] * phase;
      }
    }
  }
  const std::vector<double>& muS = material.ReducedScatteringCoefficient;
  std::vector<std::complex<double>> tetLoad(12 * static_cast<size_t>(numTets), 0.0);
#pragma omp parallel for schedule(static)
  for (int t = 0; t < numTets; ++t)
  {
    const int* v = mesh.GetTet(t);
    const double volume = mesh.GetTetVolume(t);
    for (const CollimatedSource::Beam& beam : source.Beams)
    {
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        double e[4], path[4];
        TetValues(beam, v, c, e, path);
        // The beam's own modulation exp(-i omega eta s / c) with E_c.
        std::complex<double> moment[4], total;
        if (!TetIntegrals(e, path, wavenumber, volume, total, moment))
        {
          continue;
        }
        const double sigma = muS[3 * static_cast<size_t>(t) + c];
        for (int k = 0; k < 4; ++k)
        {
          tetLoad[12 * static_cast<size_t>(t) + 3 * k + c] += sigma * moment[k];
        }
      }
    }
  }
  for (int t = 0; t < numTets; ++t)
  {
    const int* v = mesh.GetTet(t);
    for (int k = 0; k < 4; ++k)
    {
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        load[3 * static_cast<size_t>(v[k]) + c] += tetLoad[12 * static_cast<size_t>(t) + 3 * k + c];
      }
    }
  }
}

std::vector<CollimatedDeposit> ComputeCollimatedTimeLoad(const TetMesh& mesh,
  const OpticalProperties& material, const CollimatedSource& source,
  const std::vector<double>& times)
{
  if (times.empty() || times.front() != 0.0 || !std::is_sorted(times.begin(), times.end()))
  {
    throw Error("collimated source: the step times must start at 0 and ascend");
  }
  const int numPoints = mesh.GetNumberOfPoints();
  const int numTets = mesh.GetNumberOfTets();
  material.Validate(numTets);
  for (const CollimatedSource::Beam& beam : source.Beams)
  {
    if (beam.Fluence.size() != 3 * static_cast<size_t>(numPoints) ||
      beam.OpticalPath.size() != static_cast<size_t>(numPoints))
    {
      throw Error("collimated source: the beams do not match the mesh's points");
    }
  }
  const std::vector<double>& muS = material.ReducedScatteringCoefficient;
  const int last = static_cast<int>(times.size()) - 1;
  // Per tet (in tet order, so the sums below do not depend on the threads).
  std::vector<std::vector<CollimatedDeposit>> perTet(static_cast<size_t>(numTets));
#pragma omp parallel
  {
    // The tet's deposits, dense over the times its arrivals span: weights
    // [(j - first) * 12 + 3 k + c] for time j, vertex k, channel c.
    std::vector<double> dense, share;
#pragma omp for schedule(static)
    for (int t = 0; t < numTets; ++t)
    {
      const int* v = mesh.GetTet(t);
      const double volume = mesh.GetTetVolume(t);
      // The arrivals in the tet lie between its lit vertices' (linear in
      // the barycentric coordinates): the times around them. (In a tet a
      // beam lights partly, the points near an unlit vertex, whose path is
      // 0, are clamped to that range: the beam has reached the tet by then.)
      int first = last, end = 0;
      for (const CollimatedSource::Beam& beam : source.Beams)
      {
        for (int k = 0; k < 4; ++k)
        {
          const double* lit = &beam.Fluence[3 * static_cast<size_t>(v[k])];
          if (!(lit[0] > 0.0 || lit[1] > 0.0 || lit[2] > 0.0))
          {
            continue;
          }
          const double tau = beam.OpticalPath[v[k]] / SpeedOfLightMillimetresPerNanosecond;
          const int j = static_cast<int>(
            std::upper_bound(times.begin(), times.end(), tau) - times.begin());
          first = std::min(first, std::max(0, std::min(j, last + 1) - 1));
          end = std::max(end, std::min(j, last) + 1);
        }
      }
      if (end <= first)
      {
        continue;
      }
      dense.assign(12 * static_cast<size_t>(end - first), 0.0);
      for (const CollimatedSource::Beam& beam : source.Beams)
      {
        for (int c = 0; c < NumberOfChannels; ++c)
        {
          double e[4], path[4];
          TetValues(beam, v, c, e, path);
          DepositInTime(e, path, volume, muS[3 * static_cast<size_t>(t) + c], times, first, end,
            dense.data() + c, share);
        }
      }
      std::vector<CollimatedDeposit>& out = perTet[static_cast<size_t>(t)];
      for (int j = first; j < end; ++j)
      {
        for (int k = 0; k < 4; ++k)
        {
          const double* w = &dense[12 * static_cast<size_t>(j - first) + 3 * k];
          if (w[0] != 0.0 || w[1] != 0.0 || w[2] != 0.0)
          {
            CollimatedDeposit d;
            d.Time = j;
            d.Point = v[k];
            d.Load = { w[0], w[1], w[2] };
            out.push_back(d);
          }
        }
      }
    }
  }
  std::vector<CollimatedDeposit> deposits;
  for (std::vector<CollimatedDeposit>& list : perTet)
  {
    deposits.insert(deposits.end(), list.begin(), list.end());
    std::vector<CollimatedDeposit>().swap(list);
  }
  std::stable_sort(deposits.begin(), deposits.end(),
    [](const CollimatedDeposit& a, const CollimatedDeposit& b) {
      return a.Time != b.Time ? a.Time < b.Time : a.Point < b.Point;
    });
  std::vector<CollimatedDeposit> merged;
  for (const CollimatedDeposit& d : deposits)
  {
    if (!merged.empty() && merged.back().Time == d.Time && merged.back().Point == d.Point)
    {
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        merged.back().Load[c] += d.Load[c];
      }
    }
    else
    {
      merged.push_back(d);
    }
  }
  return merged;
}

} // namespace translucency
