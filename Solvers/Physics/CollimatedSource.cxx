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
  /// Per sub-tet of level 1, the sum of its nodes' barycentric coordinates.
  double NodeSums[8][4] = {};

  TetRules()
  {
    for (int s = 0; s < 8; ++s)
    {
      for (const int n : Sub[s])
      {
        if (n < 4)
        {
          NodeSums[s][n] += 1.0;
        }
        else
        {
          NodeSums[s][Edge[n - 4][0]] += 0.5;
          NodeSums[s][Edge[n - 4][1]] += 0.5;
        }
      }
    }
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
  // The sums by sub-tet and node: with g_{s,k} = base_s own_{n_k} and
  // l = b N_s + (a - b) node n_k (N_s the sum of sub-tet s's nodes),
  //   sum_p g_p l_p = b sum_s G_s N_s + (a - b) sum_n own_n B_n node_n,
  // G_s = base_s sum_k own_{n_k}, B_n = the sum of base_s over the sub-tets
  // that have node n (a node's barycentric coordinates: a vertex's unit
  // vector, a midpoint's half its edge's two).
  const TetRules& rules = Rules();
  double base[8], nodeBase[10] = {};
  total = 0.0;
  double moments[4] = { 0.0, 0.0, 0.0, 0.0 };
  for (int s = 0; s < 8; ++s)
  {
    const int* n = TetRules::Sub[s];
    base[s] = other[n[0]] * other[n[1]] * other[n[2]] * other[n[3]];
    const double g = base[s] * (own[n[0]] + own[n[1]] + own[n[2]] + own[n[3]]);
    total += g;
    for (int k = 0; k < 4; ++k)
    {
      nodeBase[n[k]] += base[s];
    }
    for (int j = 0; j < 4; ++j)
    {
      moments[j] += g * rules.NodeSums[s][j];
    }
  }
  const double ab = TetRules::A - TetRules::B;
  double node[4];
  for (int j = 0; j < 4; ++j)
  {
    node[j] = own[j] * nodeBase[j];
  }
  for (int m = 0; m < 6; ++m)
  {
    const double half = 0.5 * own[4 + m] * nodeBase[4 + m];
    node[TetRules::Edge[m][0]] += half;
    node[TetRules::Edge[m][1]] += half;
  }
  const double weight = volume / 32.0;
  total *= weight;
  for (int j = 0; j < 4; ++j)
  {
    moment[j] = weight * (TetRules::B * moments[j] + ab * node[j]);
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
 * What the entering power casts its shadow rays against, built from the
 * mesh's geometry alone: the shadow caster (ShadowCaster, as
 * ComputeTriangleCornerIrradiance builds it), the boundary triangles'
 * normals and the box's diagonal. A relight or a paint casts new rays on the
 * same surface, so the last mesh's is kept (BoundaryCastersOf).
 */
struct BoundaryCasters
{
  std::uint64_t Revision = 0;
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

/**
 * The rays of one beam all run along one direction d: the triangles that a
 * ray o + t d can hit are those whose projection along d holds o's. This
 * grid bins the boundary triangles by their projections on the plane
 * normal to d (cells of about one triangle's size) and answers FirstHit()
 * and Occluded() as RayCaster does for rays along d: RayCaster's queries
 * give exactly the answer of a loop over all triangles with
 * RayCaster::IntersectTriangle() (its contract), and these loop over the
 * triangles of the origin's cell with that same function (the same t to the
 * bit, the closest kept). Conservative: each projected box is padded by
 * 1e-9 of the diagonal, far more than IntersectTriangle's rounding can put
 * a hit outside a triangle (about 6 ulps of the diagonal over |cos| of the
 * angle between d and the triangle's normal), and a triangle within 1e-5 of
 * parallel to d is tried for every ray. Only exact ties in t between two
 * triangles (a ray through a shared edge) may resolve differently, which
 * RayCaster leaves unspecified too (and the origins' generic shift avoids).
 * Built per beam in O(triangles); a query tests the few triangles over one
 * cell instead of descending a tree.
 */
class DirectionGrid
{
public:
  DirectionGrid(const std::vector<double>& points, const std::vector<int>& triangles,
    const double direction[3], double diagonal)
  {
    const double origin[3] = { 0.0, 0.0, 0.0 };
    this->Valid = RayCaster::UnitDirection(origin, direction, this->D);
    const int numTriangles = static_cast<int>(triangles.size() / 3);
    if (!this->Valid || numTriangles == 0)
    {
      this->Valid = false;
      return;
    }
    // An orthonormal basis (U, V) of the plane normal to D.
    const double* d = this->D;
    const double helper[3] = { std::abs(d[0]) < 0.6 ? 1.0 : 0.0, std::abs(d[0]) < 0.6 ? 0.0 : 1.0,
      0.0 };
    Cross(d, helper, this->U);
    Normalize(this->U);
    Cross(d, this->U, this->V);
    Normalize(this->V);
    this->Points = &points;
    this->Triangles = &triangles;
    const double pad = 1e-9 * diagonal;
    std::vector<double> boxes(4 * static_cast<size_t>(numTriangles));
    this->Near.resize(static_cast<size_t>(numTriangles));
    this->Far.resize(static_cast<size_t>(numTriangles));
    double low[2] = { std::numeric_limits<double>::infinity(),
      std::numeric_limits<double>::infinity() };
    double high[2] = { -low[0], -low[1] };
    double area = 0.0;
    for (int f = 0; f < numTriangles; ++f)
    {
      double* box = &boxes[4 * static_cast<size_t>(f)];
      box[0] = box[1] = std::numeric_limits<double>::infinity();
      box[2] = box[3] = -std::numeric_limits<double>::infinity();
      double x[3][3];
      this->Near[f] = std::numeric_limits<double>::infinity();
      this->Far[f] = -std::numeric_limits<double>::infinity();
      for (int k = 0; k < 3; ++k)
      {
        const double* p = &points[3 * static_cast<size_t>(triangles[3 * static_cast<size_t>(f) + k])];
        const double pu = Dot(p, this->U), pv = Dot(p, this->V), pd = Dot(p, d);
        this->Near[f] = std::min(this->Near[f], pd - pad);
        this->Far[f] = std::max(this->Far[f], pd + pad);
        box[0] = std::min(box[0], pu - pad);
        box[1] = std::min(box[1], pv - pad);
        box[2] = std::max(box[2], pu + pad);
        box[3] = std::max(box[3], pv + pad);
        for (int j = 0; j < 3; ++j)
        {
          x[k][j] = p[j];
        }
      }
      double e1[3], e2[3], n[3];
      for (int j = 0; j < 3; ++j)
      {
        e1[j] = x[1][j] - x[0][j];
        e2[j] = x[2][j] - x[0][j];
      }
      Cross(e1, e2, n);
      const double length = std::sqrt(Dot(n, n));
      if (!(length > 0.0))
      {
        box[0] = box[1] = 1.0; // never hit (IntersectTriangle: det = 0): binned nowhere
        box[2] = box[3] = -1.0;
        continue;
      }
      if (std::abs(Dot(n, d)) < 1e-5 * length)
      {
        this->Everywhere.push_back(f);
        box[0] = box[1] = 1.0;
        box[2] = box[3] = -1.0;
        continue;
      }
      area += (box[2] - box[0]) * (box[3] - box[1]);
      low[0] = std::min(low[0], box[0]);
      low[1] = std::min(low[1], box[1]);
      high[0] = std::max(high[0], box[2]);
      high[1] = std::max(high[1], box[3]);
    }
    if (!(high[0] >= low[0] && high[1] >= low[1]))
    {
      this->Cells[0] = this->Cells[1] = 0;
      return;
    }
    // Cells of about half a projected triangle's box, at most 16 per triangle.
    double cell = std::max(0.5 * std::sqrt(area / numTriangles), 1e-12 * diagonal);
    const double maxCells = 16.0 * numTriangles + 1024.0;
    while (((high[0] - low[0]) / cell + 1.0) * ((high[1] - low[1]) / cell + 1.0) > maxCells)
    {
      cell *= 1.25;
    }
    for (int a = 0; a < 2; ++a)
    {
      this->Low[a] = low[a];
      this->Cells[a] = static_cast<int>((high[a] - low[a]) / cell) + 1;
      this->Scale[a] = this->Cells[a] / std::max(high[a] - low[a], 1e-300);
    }
    this->Bin(boxes, numTriangles);
  }

  /// RayCaster::FirstHit(origin, direction, infinity, t, triangle) for the
  /// grid's direction (epsilon 0).
  bool FirstHit(const double origin[3], double& t, int& triangle) const
  {
    bool hit = false;
    double best = std::numeric_limits<double>::infinity();
    this->Visit(origin, best, [&](int f) {
      double tt;
      if (this->Intersect(origin, f, 0.0, best, tt))
      {
        best = tt;
        triangle = f;
        hit = true;
      }
      return false;
    });
    if (hit)
    {
      t = best;
    }
    return hit;
  }

  /// RayCaster::Occluded(origin, direction, tMax) for the grid's direction.
  bool Occluded(const double origin[3], double tMax) const
  {
    bool hit = false;
    this->Visit(origin, tMax, [&](int f) {
      double tt;
      hit = this->Intersect(origin, f, 0.0, tMax, tt);
      return hit;
    });
    return hit;
  }

private:
  static double Dot(const double* a, const double* b)
  {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  }
  static void Cross(const double* a, const double* b, double* c)
  {
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
  }
  static void Normalize(double* a)
  {
    const double length = std::sqrt(Dot(a, a));
    for (int k = 0; k < 3; ++k)
    {
      a[k] /= length;
    }
  }
  /// The constructor's binning (CSR): counts, offsets, then the triangles
  /// in order; each cell's triangles by their nearest depth along d, so that
  /// a query stops at the first one beyond what it looks for.
  void Bin(const std::vector<double>& boxes, int numTriangles)
  {
    const size_t numCells = static_cast<size_t>(this->Cells[0]) * this->Cells[1];
    this->Offsets.assign(numCells + 1, 0);
    auto span = [&](const double* box, int range[4]) {
      for (int a = 0; a < 2; ++a)
      {
        range[a] = this->CellOf(box[a], a);
        range[2 + a] = this->CellOf(box[2 + a], a);
      }
      return box[2] >= box[0];
    };
    for (int pass = 0; pass < 2; ++pass)
    {
      if (pass == 1)
      {
        for (size_t c = 0; c < numCells; ++c)
        {
          this->Offsets[c + 1] += this->Offsets[c];
        }
        this->Entries.resize(this->Offsets[numCells]);
      }
      std::vector<int> fill(pass == 1 ? this->Offsets.begin() : this->Offsets.end(),
        pass == 1 ? this->Offsets.end() - 1 : this->Offsets.end());
      for (int f = 0; f < numTriangles; ++f)
      {
        int range[4];
        if (!span(&boxes[4 * static_cast<size_t>(f)], range))
        {
          continue;
        }
        for (int j = range[1]; j <= range[3]; ++j)
        {
          for (int i = range[0]; i <= range[2]; ++i)
          {
            const size_t c = static_cast<size_t>(j) * this->Cells[0] + i;
            if (pass == 0)
            {
              ++this->Offsets[c + 1];
            }
            else
            {
              this->Entries[fill[c]++] = { this->Near[f], this->Far[f], f };
            }
          }
        }
      }
    }
    for (size_t c = 0; c < numCells; ++c)
    {
      std::sort(this->Entries.begin() + this->Offsets[c], this->Entries.begin() + this->Offsets[c + 1],
        [](const Entry& x, const Entry& y) { return x.Near < y.Near; });
    }
  }

  int CellOf(double x, int axis) const
  {
    const double c = std::floor((x - this->Low[axis]) * this->Scale[axis]);
    return static_cast<int>(std::max(0.0, std::min(c, static_cast<double>(this->Cells[axis] - 1))));
  }
  bool Intersect(const double origin[3], int f, double tMin, double tMax, double& t) const
  {
    const int* tri = &(*this->Triangles)[3 * static_cast<size_t>(f)];
    const std::vector<double>& p = *this->Points;
    return RayCaster::IntersectTriangle(origin, this->D, &p[3 * static_cast<size_t>(tri[0])],
      &p[3 * static_cast<size_t>(tri[1])], &p[3 * static_cast<size_t>(tri[2])], tMin, tMax, t);
  }
  /// Calls visit(f) for the triangles that a ray from `origin` can hit at
  /// 0 < t < reach (its cell's, nearest first, then those tried
  /// everywhere) until visit returns true. `reach` is read at each step
  /// (FirstHit lowers it to the closest hit so far). A triangle's depth
  /// range along d, padded as its box, bounds the t of any hit on it
  /// (IntersectTriangle's rounding of t is below the pad as that of its
  /// position), so the skipped triangles are exactly those that could not
  /// be hit within (0, reach).
  template <class Function>
  void Visit(const double origin[3], const double& reach, Function&& visit) const
  {
    if (!this->Valid || !std::isfinite(origin[0]) || !std::isfinite(origin[1]) ||
      !std::isfinite(origin[2]))
    {
      return;
    }
    const double depth = Dot(origin, this->D);
    if (this->Cells[0] > 0)
    {
      const double pu = Dot(origin, this->U), pv = Dot(origin, this->V);
      const double i = std::floor((pu - this->Low[0]) * this->Scale[0]);
      const double j = std::floor((pv - this->Low[1]) * this->Scale[1]);
      if (i >= 0.0 && j >= 0.0 && i < this->Cells[0] && j < this->Cells[1])
      {
        const size_t c = static_cast<size_t>(j) * this->Cells[0] + static_cast<size_t>(i);
        for (int e = this->Offsets[c]; e < this->Offsets[c + 1]; ++e)
        {
          const Entry& entry = this->Entries[e];
          if (entry.Near - depth >= reach)
          {
            break; // this one and the rest lie beyond reach
          }
          if (entry.Far - depth <= 0.0)
          {
            continue; // behind the origin
          }
          if (visit(entry.Triangle))
          {
            return;
          }
        }
      }
    }
    for (const int f : this->Everywhere)
    {
      if (visit(f))
      {
        return;
      }
    }
  }

  bool Valid = false;
  double D[3] = { 0.0, 0.0, 0.0 }, U[3] = { 0.0, 0.0, 0.0 }, V[3] = { 0.0, 0.0, 0.0 };
  const std::vector<double>* Points = nullptr;
  const std::vector<int>* Triangles = nullptr;
  double Low[2] = { 0.0, 0.0 }, Scale[2] = { 0.0, 0.0 };
  int Cells[2] = { 0, 0 };
  /// A triangle in a cell, with its depth range along d (padded).
  struct Entry
  {
    double Near, Far;
    int Triangle;
  };
  std::vector<int> Offsets, Everywhere;
  std::vector<Entry> Entries;
  /// Each triangle's depth range along d (padded), while binning.
  std::vector<double> Near, Far;
};

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

/// The directional lights of `lights`, after checking every light
/// (ValidateLight) and the material on numTets tets (the entry points'
/// errors).
std::vector<LightSource> ValidatedBeams(
  const OpticalProperties& material, int numTets, const std::vector<LightSource>& lights)
{
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
  return beams;
}

/// A CollimatedSource of `numPoints` points and `numBeams` beams, zeroed.
CollimatedSource SizedSource(int numPoints, size_t numBeams)
{
  CollimatedSource out;
  out.Fluence.assign(3 * static_cast<size_t>(numPoints), 0.0);
  out.Load.assign(3 * static_cast<size_t>(numPoints), 0.0);
  out.Beams.resize(numBeams);
  for (CollimatedSource::Beam& beam : out.Beams)
  {
    beam.Fluence.assign(3 * static_cast<size_t>(numPoints), 0.0);
    beam.OpticalPath.assign(static_cast<size_t>(numPoints), 0.0);
  }
  return out;
}

/// The unit direction towards a beam's light, -d / |d|.
void TowardsLight(const LightSource& beam, double w[3])
{
  const double len = std::sqrt(beam.Direction[0] * beam.Direction[0] +
    beam.Direction[1] * beam.Direction[1] + beam.Direction[2] * beam.Direction[2]);
  w[0] = -beam.Direction[0] / len;
  w[1] = -beam.Direction[1] / len;
  w[2] = -beam.Direction[2] / len;
}

/// The unnormalised outward normal of `surface`'s triangle f; its length in nl.
const double* EntryNormal(const CollimatedEntrySurface& surface, int f, double n[3], double& nl)
{
  const std::vector<double>& surfacePoints = *surface.Points;
  const int* tri = &(*surface.Triangles)[3 * static_cast<size_t>(f)];
  const double* a = &surfacePoints[3 * static_cast<size_t>(tri[0])];
  const double* b = &surfacePoints[3 * static_cast<size_t>(tri[1])];
  const double* c3 = &surfacePoints[3 * static_cast<size_t>(tri[2])];
  const double e1[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
  const double e2[3] = { c3[0] - a[0], c3[1] - a[1], c3[2] - a[2] };
  n[0] = e1[1] * e2[2] - e1[2] * e2[1];
  n[1] = e1[2] * e2[0] - e1[0] * e2[2];
  n[2] = e1[0] * e2[1] - e1[1] * e2[0];
  nl = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  return a;
}

/**
 * The geometric half of the beam field (BeamFieldOnSurface): per beam and
 * query point, the boundary triangle through which the beam reaches the
 * point, or -1 (the ray towards the light leaves through no triangle, leaves
 * through one that does not face the light, or the entry point is shadowed).
 * Depends on the surface's geometry, the beams' directions, the shadow flag
 * and the points only, not on the material (CollimatedSourceCache keeps it
 * across paints). Each ray is cast against `surface` with `caster` (built
 * over it) or, without one, through a grid along each beam (the same hits,
 * DirectionGrid).
 */
std::vector<std::vector<int>> CastBeamEntries(const CollimatedEntrySurface& surface,
  const RayCaster* caster, const std::vector<LightSource>& beams, bool shadows,
  const std::vector<double>& points, const std::vector<char>& onBoundary,
  const std::vector<double>& pointNormals)
{
  const int numPoints = static_cast<int>(points.size() / 3);
  const std::vector<double>& surfacePoints = *surface.Points;
  const double diag = surface.Diagonal;
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
  // itself (EvaluateBeamField), so E_c changes only where the entry face
  // was such a tie.
  const double generic = 1e-9 * diag / std::sqrt(6.0);
  const double shift[3] = { generic, generic * std::sqrt(2.0), generic * std::sqrt(3.0) };
  // Without a caster (Fast): the rays of each beam through a grid along its
  // direction (the same hits as RayCaster's, DirectionGrid).
  std::vector<std::unique_ptr<DirectionGrid>> grids(beams.size());
  for (size_t index = 0; !caster && index < beams.size(); ++index)
  {
    double w[3];
    TowardsLight(beams[index], w);
    grids[index] =
      std::make_unique<DirectionGrid>(surfacePoints, *surface.Triangles, w, diag);
  }
  std::vector<std::vector<int>> entries(
    beams.size(), std::vector<int>(static_cast<size_t>(numPoints), -1));
#pragma omp parallel for schedule(dynamic, 256)
  for (int i = 0; i < numPoints; ++i)
  {
    const double* x = &points[3 * static_cast<size_t>(i)];
    double origin[3] = { x[0] + shift[0], x[1] + shift[1], x[2] + shift[2] };
    if (onBoundary[static_cast<size_t>(i)])
    {
      const double* n = &pointNormals[3 * static_cast<size_t>(i)];
      for (int k = 0; k < 3; ++k)
      {
        origin[k] -= offset * n[k]; // just inside
      }
    }
    for (size_t index = 0; index < beams.size(); ++index)
    {
      double w[3];
      TowardsLight(beams[index], w);
      double t = 0.0;
      int f = -1;
      const DirectionGrid* grid = grids[index].get();
      if (!(grid ? grid->FirstHit(origin, t, f)
                 : caster->FirstHit(origin, w, std::numeric_limits<double>::infinity(), t, f)))
      {
        continue;
      }
      // The entry triangle's outward normal.
      double n[3], nl = 0.0;
      EntryNormal(surface, f, n, nl);
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
        if (grid ? grid->Occluded(p, 2.0 * diag) : caster->Occluded(p, w, 2.0 * diag))
        {
          continue;
        }
      }
      entries[index][static_cast<size_t>(i)] = f;
    }
  }
  return entries;
}

/**
 * The optical half of the beam field (BeamFieldOnSurface): E_c of every
 * beam at the query points and the optical path to the entry point, from the
 * entry triangles of CastBeamEntries and the material under them (the
 * surface's Eta and Extinction). Fills out.Fluence (the sum over the beams,
 * in their order) and out.Beams, which must be sized and zeroed.
 */
void EvaluateBeamField(const CollimatedEntrySurface& surface,
  const std::vector<LightSource>& beams, const std::vector<double>& points,
  const std::vector<std::vector<int>>& entries, CollimatedSource& out)
{
  const int numPoints = static_cast<int>(points.size() / 3);
#pragma omp parallel for schedule(static)
  for (int i = 0; i < numPoints; ++i)
  {
    const double* x = &points[3 * static_cast<size_t>(i)];
    for (size_t index = 0; index < beams.size(); ++index)
    {
      const int f = entries[index][static_cast<size_t>(i)];
      if (f < 0)
      {
        continue;
      }
      const LightSource& beam = beams[index];
      CollimatedSource::Beam& field = out.Beams[index];
      double w[3];
      TowardsLight(beam, w);
      double n[3], nl = 0.0;
      const double* a = EntryNormal(surface, f, n, nl);
      const double cosIn = (n[0] * w[0] + n[1] * w[1] + n[2] * w[2]) / nl;
      const double eta = surface.Eta[static_cast<size_t>(f)];
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
        const double muT = surface.Extinction[3 * static_cast<size_t>(f) + c];
        const double value = beam.Power[c] * entering * std::exp(-muT * s);
        field.Fluence[3 * static_cast<size_t>(i) + c] = value;
        out.Fluence[3 * static_cast<size_t>(i) + c] += value;
      }
    }
  }
}

/// ComputeCollimatedBeamAtPoints: E_c of every beam at the query points
/// (zero where the ray toward the light leaves through no entry face, or is
/// shadowed) and the optical path to the entry point: CastBeamEntries, then
/// EvaluateBeamField.
void BeamFieldOnSurface(const CollimatedEntrySurface& surface, const RayCaster* caster,
  const std::vector<LightSource>& beams, bool shadows, const std::vector<double>& points,
  const std::vector<char>& onBoundary, const std::vector<double>& pointNormals,
  CollimatedSource& out)
{
  EvaluateBeamField(surface, beams, points,
    CastBeamEntries(surface, caster, beams, shadows, points, onBoundary, pointNormals), out);
}

/// The mesh's own boundary as the entry surface of its beams, with the
/// material under each triangle.
CollimatedEntrySurface MeshEntrySurface(
  const TetMesh& mesh, const OpticalProperties& material, double diagonal)
{
  const std::vector<int>& triangleTets = mesh.GetBoundaryTriangleTets();
  CollimatedEntrySurface surface;
  surface.Points = &mesh.GetPoints();
  surface.Triangles = &mesh.GetBoundaryTriangles();
  surface.Diagonal = diagonal;
  surface.Eta.resize(triangleTets.size());
  surface.Extinction.resize(3 * triangleTets.size());
  for (size_t f = 0; f < triangleTets.size(); ++f)
  {
    const size_t tet = static_cast<size_t>(triangleTets[f]);
    surface.Eta[f] = material.RefractiveIndex[tet];
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      surface.Extinction[3 * f + c] = material.AbsorptionCoefficient[3 * tet + c] +
        material.ReducedScatteringCoefficient[3 * tet + c];
    }
  }
  return surface;
}

/// Per mesh point: 1 on the boundary.
std::vector<char> BoundaryFlags(const TetMesh& mesh)
{
  const int numPoints = mesh.GetNumberOfPoints();
  std::vector<char> onBoundary(static_cast<size_t>(numPoints));
  for (int i = 0; i < numPoints; ++i)
  {
    onBoundary[static_cast<size_t>(i)] = mesh.IsBoundaryPoint(i) ? 1 : 0;
  }
  return onBoundary;
}

/// ComputeCollimatedSource: E_c of every beam at the mesh's points, cast
/// against its own boundary (BeamFieldOnSurface).
void BeamFieldAtPoints(const TetMesh& mesh, const OpticalProperties& material,
  const std::vector<LightSource>& beams, bool shadows, double diagonal, const RayCaster* caster,
  CollimatedSource& out)
{
  BeamFieldOnSurface(MeshEntrySurface(mesh, material, diagonal), caster, beams, shadows,
    mesh.GetPoints(), BoundaryFlags(mesh), mesh.GetPointNormals(), out);
}

/**
 * One tet's share of the beams' loads (BeamLoads): load[3 k + c] the
 * integral of mu_s' E_c phi_k over the tet (vertex k, channel c) and
 * absorbed[c] that of mu_a E_c, summed over `beams` in their order. `logs`:
 * per beam, ln E_c per point and channel (0 where E_c is 0; Fast), or null
 * (Fast takes the same logarithms here; Reference takes none).
 */
void TetBeamLoads(const int* v, double volume, const std::vector<CollimatedSource::Beam>& beams,
  const std::vector<std::vector<double>>* logs, bool fast, const double* muA, const double* muS,
  double load[12], double absorbed[3])
{
  std::fill_n(load, 12, 0.0);
  std::fill_n(absorbed, 3, 0.0);
  for (size_t b = 0; b < beams.size(); ++b)
  {
    const std::vector<double>& fluence = beams[b].Fluence;
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      double e[4], logE[4];
      for (int k = 0; k < 4; ++k)
      {
        const size_t at = 3 * static_cast<size_t>(v[k]) + c;
        e[k] = fluence[at];
        logE[k] = !fast ? 0.0 : logs ? (*logs)[b][at] : e[k] > 0.0 ? std::log(e[k]) : 0.0;
      }
      double moment[4], total = 0.0;
      const bool lit = fast ? ContinuousWaveTetIntegrals(e, logE, volume, total, moment)
                            : ReferenceTetIntegrals(e, volume, total, moment);
      if (!lit)
      {
        continue;
      }
      for (int k = 0; k < 4; ++k)
      {
        load[3 * k + c] += muS[c] * moment[k];
      }
      absorbed[c] += muA[c] * total;
    }
  }
}

/// ComputeCollimatedSource, loads: integral of mu_s' E_c phi_a per tet and
/// beam (TetBeamLoads), then scattered to the points (and mu_a E_c, the
/// absorbed power).
void BeamLoads(const TetMesh& mesh, const OpticalProperties& material,
  CollimatedEvaluation evaluation, CollimatedSource& out)
{
  const int numTets = mesh.GetNumberOfTets();
  const std::vector<double>& muA = material.AbsorptionCoefficient;
  const std::vector<double>& muS = material.ReducedScatteringCoefficient;
  // Per tet, zeroed by the thread that fills it (no pass over the whole
  // buffer first: at 1M tets it is 120 MB, new pages on every call).
  const std::unique_ptr<double[]> tetLoad(new double[12 * static_cast<size_t>(numTets)]);
  const std::unique_ptr<double[]> tetAbsorbed(new double[3 * static_cast<size_t>(numTets)]);
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
    TetBeamLoads(mesh.GetTet(t), mesh.GetTetVolume(t), out.Beams, &logs, fast,
      &muA[3 * static_cast<size_t>(t)], &muS[3 * static_cast<size_t>(t)],
      &tetLoad[12 * static_cast<size_t>(t)], &tetAbsorbed[3 * static_cast<size_t>(t)]);
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

void ComputeCollimatedBeamAtPoints(const CollimatedEntrySurface& surface,
  const std::vector<LightSource>& beams, bool shadows, const std::vector<double>& points,
  const std::vector<char>& onBoundary, const std::vector<double>& normals, CollimatedSource& out)
{
  const size_t numPoints = points.size() / 3;
  out.Fluence.assign(3 * numPoints, 0.0);
  out.Beams.resize(beams.size());
  for (CollimatedSource::Beam& beam : out.Beams)
  {
    beam.Fluence.assign(3 * numPoints, 0.0);
    beam.OpticalPath.assign(numPoints, 0.0);
  }
  if (beams.empty() || surface.Triangles->empty())
  {
    return;
  }
  // The rays through a grid along each beam (Fast's path).
  BeamFieldOnSurface(surface, nullptr, beams, shadows, points, onBoundary, normals, out);
}

std::vector<std::vector<int>> CastCollimatedBeamEntries(const CollimatedEntrySurface& surface,
  const std::vector<LightSource>& beams, bool shadows, const std::vector<double>& points,
  const std::vector<char>& onBoundary, const std::vector<double>& normals)
{
  if (beams.empty() || surface.Triangles->empty())
  {
    return std::vector<std::vector<int>>(
      beams.size(), std::vector<int>(points.size() / 3, -1));
  }
  return CastBeamEntries(surface, nullptr, beams, shadows, points, onBoundary, normals);
}

void EvaluateCollimatedBeamField(const CollimatedEntrySurface& surface,
  const std::vector<LightSource>& beams, const std::vector<double>& points,
  const std::vector<std::vector<int>>& entries, CollimatedSource& out)
{
  EvaluateBeamField(surface, beams, points, entries, out);
}

void AddCollimatedLoads(const TetMesh& mesh, const OpticalProperties& material, CollimatedSource& out)
{
  if (out.Load.size() != 3 * static_cast<size_t>(mesh.GetNumberOfPoints()))
  {
    out.Load.assign(3 * static_cast<size_t>(mesh.GetNumberOfPoints()), 0.0);
  }
  BeamLoads(mesh, material, CollimatedEvaluation::Fast, out);
}

CollimatedSource ComputeCollimatedSource(const TetMesh& mesh, const OpticalProperties& material,
  const std::vector<LightSource>& lights, bool shadows, CollimatedEvaluation evaluation)
{
  const int numPoints = mesh.GetNumberOfPoints();
  const int numTets = mesh.GetNumberOfTets();
  const std::vector<LightSource> beams = ValidatedBeams(material, numTets, lights);
  CollimatedSource out = SizedSource(numPoints, beams.size());
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
    // A caster built for the call.
    RayCaster caster;
    caster.Build(mesh.GetPoints(), mesh.GetBoundaryTriangles());
    BeamFieldAtPoints(mesh, material, beams, shadows, BoundingBoxDiagonal(mesh), &caster, out);
  }
  else
  {
    const std::shared_ptr<const BoundaryCasters> casters = BoundaryCastersOf(mesh, shadows);
    EnteringPower(mesh, tetEta, beams, shadows, *casters, out);
    BeamFieldAtPoints(mesh, material, beams, shadows, casters->Diagonal, nullptr, out);
  }

  // Loads: integral of mu_s' E_c phi_a per tet and beam, then scattered to
  // the points.
  BeamLoads(mesh, material, evaluation, out);
  return out;
}

//------------------------------------------------------------------------------
namespace
{
/// CollimatedLoadCache: the tets whose mu_a or mu_s' differ from the kept
/// ones or that have a point in `changedPoint`.
std::vector<int> DirtyTets(const TetMesh& mesh, const OpticalProperties& material,
  const std::vector<double>& keptMuA, const std::vector<double>& keptMuS,
  const std::vector<char>& changedPoint)
{
  const int numTets = mesh.GetNumberOfTets();
  const std::vector<double>& muA = material.AbsorptionCoefficient;
  const std::vector<double>& muS = material.ReducedScatteringCoefficient;
  std::vector<int> dirty;
  for (int t = 0; t < numTets; ++t)
  {
    const size_t at = 3 * static_cast<size_t>(t);
    bool changed = muA[at] != keptMuA[at] || muA[at + 1] != keptMuA[at + 1] ||
      muA[at + 2] != keptMuA[at + 2] || muS[at] != keptMuS[at] ||
      muS[at + 1] != keptMuS[at + 1] || muS[at + 2] != keptMuS[at + 2];
    const int* v = mesh.GetTet(t);
    for (int k = 0; !changed && k < 4; ++k)
    {
      changed = changedPoint[static_cast<size_t>(v[k])] != 0;
    }
    if (changed)
    {
      dirty.push_back(t);
    }
  }
  return dirty;
}

/// CollimatedLoadCache: per point, whether any beam's E_c differs from the
/// kept beams' (the same count and sizes).
std::vector<char> ChangedPoints(const std::vector<CollimatedSource::Beam>& now,
  const std::vector<CollimatedSource::Beam>& was, int numPoints)
{
  std::vector<char> changed(static_cast<size_t>(numPoints), 0);
  for (size_t b = 0; b < now.size(); ++b)
  {
    const std::vector<double>& e = now[b].Fluence;
    const std::vector<double>& kept = was[b].Fluence;
    for (size_t i = 0; i < e.size(); ++i)
    {
      if (e[i] != kept[i])
      {
        changed[i / 3] = 1;
      }
    }
  }
  return changed;
}
} // namespace

void CollimatedLoadCache::Clear()
{
  *this = CollimatedLoadCache();
}

std::size_t CollimatedLoadCache::GetMemoryBytes() const
{
  std::size_t bytes = sizeof(double) * (MuA_.size() + MuS_.size() + Load_.size());
  for (const CollimatedSource::Beam& beam : Beams_)
  {
    bytes += sizeof(double) * (beam.Fluence.size() + beam.OpticalPath.size());
  }
  return bytes;
}

void CollimatedLoadCache::Update(
  const TetMesh& mesh, const OpticalProperties& material, bool keep, CollimatedSource& out)
{
  const int numPoints = mesh.GetNumberOfPoints();
  const int numTets = mesh.GetNumberOfTets();
  const std::uint64_t revision = mesh.GetGeometryRevision();
  keep = keep && Valid_ && revision != 0 && revision == Revision_ && numPoints == Points_ &&
    numTets == Tets_ && out.Beams.size() == Beams_.size() &&
    mesh.GetPointTetOffsets().size() == static_cast<size_t>(numPoints) + 1;
  for (size_t b = 0; keep && b < out.Beams.size(); ++b)
  {
    keep = out.Beams[b].Fluence.size() == 3 * static_cast<size_t>(numPoints) &&
      Beams_[b].Fluence.size() == out.Beams[b].Fluence.size();
  }
  LastUpdate_ = "full";
  TetsIntegrated_ = numTets;
  std::vector<int> dirty;
  if (keep)
  {
    dirty = DirtyTets(mesh, material, MuA_, MuS_, ChangedPoints(out.Beams, Beams_, numPoints));
  }
  if (keep && 4 * dirty.size() <= static_cast<size_t>(numTets))
  {
    UpdateLoads(mesh, material, dirty, out);
    for (const int t : dirty)
    {
      for (size_t at = 3 * static_cast<size_t>(t); at < 3 * static_cast<size_t>(t) + 3; ++at)
      {
        MuA_[at] = material.AbsorptionCoefficient[at];
        MuS_[at] = material.ReducedScatteringCoefficient[at];
      }
    }
  }
  else
  {
    // Every tet, as AddCollimatedLoads() on a fresh source.
    out.Load.assign(3 * static_cast<size_t>(numPoints), 0.0);
    out.Scattered = {};
    out.Absorbed = {};
    BeamLoads(mesh, material, CollimatedEvaluation::Fast, out);
    LastUpdate_ = keep ? "loads" : "full";
    MuA_ = material.AbsorptionCoefficient;
    MuS_ = material.ReducedScatteringCoefficient;
  }
  Beams_ = out.Beams;
  Load_ = out.Load;
  Scattered_ = out.Scattered;
  Absorbed_ = out.Absorbed;
  Revision_ = revision;
  Points_ = numPoints;
  Tets_ = numTets;
  Valid_ = true;
}

void CollimatedLoadCache::UpdateLoads(const TetMesh& mesh, const OpticalProperties& material,
  const std::vector<int>& dirty, CollimatedSource& out)
{
  out.Load = Load_;
  out.Scattered = Scattered_;
  out.Absorbed = Absorbed_;
  LastUpdate_ = dirty.empty() ? "kept" : "loads";
  TetsIntegrated_ = 0;
  if (dirty.empty())
  {
    return;
  }
  const int numTets = mesh.GetNumberOfTets();
  const std::vector<int>& offsets = mesh.GetPointTetOffsets();
  const std::vector<int>& pointTets = mesh.GetPointTets();
  // The ring: every tet around a dirty tet's vertices (their loads are
  // summed again), numbered by position.
  std::vector<int> position(static_cast<size_t>(numTets), -1);
  std::vector<char> touched(static_cast<size_t>(mesh.GetNumberOfPoints()), 0);
  std::vector<int> points, ring;
  for (const int t : dirty)
  {
    const int* v = mesh.GetTet(t);
    for (int j = 0; j < 4; ++j)
    {
      if (touched[static_cast<size_t>(v[j])])
      {
        continue;
      }
      touched[static_cast<size_t>(v[j])] = 1;
      points.push_back(v[j]);
      for (int p = offsets[v[j]]; p < offsets[v[j] + 1]; ++p)
      {
        const int u = pointTets[static_cast<size_t>(p)];
        if (position[static_cast<size_t>(u)] < 0)
        {
          position[static_cast<size_t>(u)] = static_cast<int>(ring.size());
          ring.push_back(u);
        }
      }
    }
  }
  const std::vector<double>& muA = material.AbsorptionCoefficient;
  const std::vector<double>& muS = material.ReducedScatteringCoefficient;
  const int numRing = static_cast<int>(ring.size());
  const int numDirty = static_cast<int>(dirty.size());
  std::vector<double> load(12 * ring.size()), absorbed(3 * ring.size());
  std::vector<double> oldLoad(12 * dirty.size()), oldAbsorbed(3 * dirty.size());
#pragma omp parallel
  {
#pragma omp for schedule(dynamic, 64) nowait
    for (int r = 0; r < numRing; ++r)
    {
      const int t = ring[static_cast<size_t>(r)];
      const size_t at = 3 * static_cast<size_t>(t);
      TetBeamLoads(mesh.GetTet(t), mesh.GetTetVolume(t), out.Beams, nullptr, true, &muA[at],
        &muS[at], &load[12 * static_cast<size_t>(r)], &absorbed[3 * static_cast<size_t>(r)]);
    }
#pragma omp for schedule(dynamic, 64)
    for (int d = 0; d < numDirty; ++d)
    {
      const int t = dirty[static_cast<size_t>(d)];
      const size_t at = 3 * static_cast<size_t>(t);
      TetBeamLoads(mesh.GetTet(t), mesh.GetTetVolume(t), Beams_, nullptr, true, &MuA_[at],
        &MuS_[at], &oldLoad[12 * static_cast<size_t>(d)],
        &oldAbsorbed[3 * static_cast<size_t>(d)]);
    }
  }
  TetsIntegrated_ = numRing + numDirty;
  // Each touched point's load summed again over its tets in ascending order,
  // from 0, as BeamLoads sums it (GetPointTets lists them ascending).
  for (const int i : points)
  {
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      double sum = 0.0;
      for (int p = offsets[i]; p < offsets[i + 1]; ++p)
      {
        const int u = pointTets[static_cast<size_t>(p)];
        const int* v = mesh.GetTet(u);
        const int corner = v[0] == i ? 0 : v[1] == i ? 1 : v[2] == i ? 2 : 3;
        sum += load[12 * static_cast<size_t>(position[static_cast<size_t>(u)]) + 3 * corner + c];
      }
      out.Load[3 * static_cast<size_t>(i) + c] = sum;
    }
  }
  // The power sums: the dirty tets' differences.
  for (int d = 0; d < numDirty; ++d)
  {
    const size_t r = static_cast<size_t>(position[static_cast<size_t>(dirty[static_cast<size_t>(d)])]);
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      for (int j = 0; j < 4; ++j)
      {
        out.Scattered[c] += load[12 * r + 3 * j + c] - oldLoad[12 * static_cast<size_t>(d) + 3 * j + c];
      }
      out.Absorbed[c] += absorbed[3 * r + c] - oldAbsorbed[3 * static_cast<size_t>(d) + c];
    }
  }
}

//------------------------------------------------------------------------------
struct CollimatedSourceCache::Internals
{
  bool Valid = false;
  std::uint64_t Revision = 0;
  int Points = 0, Tets = 0;
  bool Shadows = false;
  std::vector<LightSource> Beams;
  double Diagonal = 0.0;
  std::vector<std::vector<int>> Entries; ///< per beam and point: entry triangle or -1
  std::vector<double> SurfaceEta, SurfaceExtinction;
  std::vector<double> Fluence; ///< the last result's E_c, summed over the beams
  std::array<double, NumberOfChannels> Entering{};
  CollimatedLoadCache Loads; ///< the last result's beams and loads

  /// Whether `beams` run along the kept beams' directions (bit for bit).
  bool SameDirections(const std::vector<LightSource>& beams) const
  {
    if (beams.size() != Beams.size())
    {
      return false;
    }
    for (size_t b = 0; b < beams.size(); ++b)
    {
      for (int k = 0; k < 3; ++k)
      {
        if (beams[b].Direction[k] != Beams[b].Direction[k])
        {
          return false;
        }
      }
    }
    return true;
  }

  bool SamePowers(const std::vector<LightSource>& beams) const
  {
    for (size_t b = 0; b < beams.size(); ++b)
    {
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        if (beams[b].Power[c] != Beams[b].Power[c])
        {
          return false;
        }
      }
    }
    return true;
  }
};

CollimatedSourceCache::CollimatedSourceCache()
  : I_(new Internals)
{
}

CollimatedSourceCache::~CollimatedSourceCache() = default;

void CollimatedSourceCache::Clear()
{
  I_.reset(new Internals);
}

std::size_t CollimatedSourceCache::GetMemoryBytes() const
{
  const Internals& k = *I_;
  std::size_t bytes =
    sizeof(double) * (k.SurfaceEta.size() + k.SurfaceExtinction.size() + k.Fluence.size()) +
    k.Loads.GetMemoryBytes();
  for (const std::vector<int>& entries : k.Entries)
  {
    bytes += sizeof(int) * entries.size();
  }
  return bytes;
}

CollimatedSource CollimatedSourceCache::Compute(const TetMesh& mesh,
  const OpticalProperties& material, const std::vector<LightSource>& lights, bool shadows)
{
  Internals& k = *I_;
  const int numPoints = mesh.GetNumberOfPoints();
  const int numTets = mesh.GetNumberOfTets();
  LastUpdate_ = "full";
  TetsIntegrated_ = numTets;
  const std::vector<LightSource> beams = ValidatedBeams(material, numTets, lights);
  const std::uint64_t revision = mesh.GetGeometryRevision();
  if (beams.empty() || mesh.GetNumberOfBoundaryTriangles() == 0 || revision == 0 ||
    mesh.GetPointTetOffsets().size() != static_cast<size_t>(numPoints) + 1)
  {
    // Nothing to keep (no beam), or no way to know the geometry again.
    Clear();
    return ComputeCollimatedSource(mesh, material, lights, shadows);
  }
  const bool sameRays = k.Valid && k.Revision == revision && k.Points == numPoints &&
    k.Tets == numTets && k.Shadows == shadows && k.SameDirections(beams);
  CollimatedSource out;
  if (!sameRays)
  {
    // Everything, as ComputeCollimatedSource (Fast) does it, the rays kept.
    k.Valid = false;
    out = SizedSource(numPoints, beams.size());
    const std::shared_ptr<const BoundaryCasters> casters = BoundaryCastersOf(mesh, shadows);
    EnteringPower(mesh, material.RefractiveIndex, beams, shadows, *casters, out);
    CollimatedEntrySurface surface = MeshEntrySurface(mesh, material, casters->Diagonal);
    k.Entries = CastBeamEntries(surface, nullptr, beams, shadows, mesh.GetPoints(),
      BoundaryFlags(mesh), mesh.GetPointNormals());
    EvaluateBeamField(surface, beams, mesh.GetPoints(), k.Entries, out);
    k.Revision = revision;
    k.Points = numPoints;
    k.Tets = numTets;
    k.Shadows = shadows;
    k.Diagonal = casters->Diagonal;
    k.SurfaceEta.swap(surface.Eta);
    k.SurfaceExtinction.swap(surface.Extinction);
  }
  else
  {
    // The kept rays: E_c again only if the material under the boundary or a
    // power changed.
    CollimatedEntrySurface surface = MeshEntrySurface(mesh, material, k.Diagonal);
    const bool samePowers = k.SamePowers(beams);
    const bool sameEta = surface.Eta == k.SurfaceEta;
    if (samePowers && sameEta && surface.Extinction == k.SurfaceExtinction)
    {
      out.Fluence = k.Fluence;
      out.Beams = k.Loads.GetBeams();
    }
    else
    {
      out = SizedSource(numPoints, beams.size());
      EvaluateBeamField(surface, beams, mesh.GetPoints(), k.Entries, out);
    }
    if (samePowers && sameEta)
    {
      out.Entering = k.Entering;
    }
    else
    {
      EnteringPower(mesh, material.RefractiveIndex, beams, shadows,
        *BoundaryCastersOf(mesh, shadows), out);
    }
    k.SurfaceEta.swap(surface.Eta);
    k.SurfaceExtinction.swap(surface.Extinction);
  }
  // The loads: the dirty tets only under the kept rays.
  k.Loads.Update(mesh, material, sameRays, out);
  LastUpdate_ = sameRays ? k.Loads.GetLastUpdate() : "full";
  TetsIntegrated_ = k.Loads.GetTetsIntegrated();
  k.Beams = beams;
  k.Fluence = out.Fluence;
  k.Entering = out.Entering;
  k.Valid = true;
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
