#include "CollimatedSource.h"

#include "Error.h"
#include "ExponentialMoments.h"
#include "Fresnel.h"
#include "RayCaster.h"
#include "TetMesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <limits>
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
    const double a = 0.5854101966249685, b = 0.1381966011250105;
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
        const int pairs[6][2] = { { 0, 1 }, { 0, 2 }, { 0, 3 }, { 1, 2 }, { 1, 3 }, { 2, 3 } };
        for (int m = 0; m < 6; ++m)
        {
          for (int j = 0; j < 4; ++j)
          {
            v[4 + m][j] = 0.5 * (t[pairs[m][0]][j] + t[pairs[m][1]][j]);
          }
        }
        // Midpoints 4..9: 01, 02, 03, 12, 13, 23.
        const int sub[8][4] = { { 0, 4, 5, 6 }, { 1, 4, 7, 8 }, { 2, 5, 7, 9 }, { 3, 6, 8, 9 },
          { 5, 8, 4, 7 }, { 5, 8, 7, 9 }, { 5, 8, 9, 6 }, { 5, 8, 6, 4 } };
        for (const auto& s : sub)
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

void ComputeCollimatedBeamAtPoints(const CollimatedEntrySurface& surface,
  const std::vector<LightSource>& beams, bool shadows, const std::vector<double>& points,
  const std::vector<char>& onBoundary, const std::vector<double>& normals, CollimatedSource& out)
{
  const int numPoints = static_cast<int>(points.size() / 3);
  const std::vector<double>& surfacePoints = *surface.Points;
  const std::vector<int>& triangles = *surface.Triangles;
  out.Fluence.assign(3 * static_cast<size_t>(numPoints), 0.0);
  out.Beams.resize(beams.size());
  for (CollimatedSource::Beam& beam : out.Beams)
  {
    beam.Fluence.assign(3 * static_cast<size_t>(numPoints), 0.0);
    beam.OpticalPath.assign(static_cast<size_t>(numPoints), 0.0);
  }
  if (beams.empty() || triangles.empty())
  {
    return;
  }
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
  // itself, so E_c changes only where the entry face was such a tie.
  const double generic = 1e-9 * diag / std::sqrt(6.0);
  const double shift[3] = { generic, generic * std::sqrt(2.0), generic * std::sqrt(3.0) };
  RayCaster caster;
  caster.Build(surfacePoints, triangles);
  auto vertex = [&surfacePoints](int p) { return &surfacePoints[3 * static_cast<size_t>(p)]; };

  // E_c at the points.
#pragma omp parallel for schedule(dynamic, 256)
  for (int i = 0; i < numPoints; ++i)
  {
    const double* x = &points[3 * static_cast<size_t>(i)];
    double origin[3] = { x[0] + shift[0], x[1] + shift[1], x[2] + shift[2] };
    if (onBoundary[static_cast<size_t>(i)])
    {
      const double* n = &normals[3 * static_cast<size_t>(i)];
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
      const double* a = vertex(tri[0]);
      const double* b = vertex(tri[1]);
      const double* c3 = vertex(tri[2]);
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

namespace
{
/// ComputeCollimatedSource: E_c of every beam at the mesh's points, cast
/// against its own boundary (ComputeCollimatedBeamAtPoints).
void BeamFieldAtPoints(const TetMesh& mesh, const OpticalProperties& material,
  const std::vector<LightSource>& beams, bool shadows, CollimatedSource& out)
{
  const int numPoints = mesh.GetNumberOfPoints();
  const std::vector<int>& triangleTets = mesh.GetBoundaryTriangleTets();
  CollimatedEntrySurface surface;
  surface.Points = &mesh.GetPoints();
  surface.Triangles = &mesh.GetBoundaryTriangles();
  surface.Diagonal = BoundingBoxDiagonal(mesh);
  surface.Eta.resize(triangleTets.size());
  surface.Extinction.resize(3 * triangleTets.size());
  for (std::size_t f = 0; f < triangleTets.size(); ++f)
  {
    const std::size_t tet = static_cast<std::size_t>(triangleTets[f]);
    surface.Eta[f] = material.RefractiveIndex[tet];
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      surface.Extinction[3 * f + c] =
        material.AbsorptionCoefficient[3 * tet + c] + material.ReducedScatteringCoefficient[3 * tet + c];
    }
  }
  std::vector<char> onBoundary(static_cast<std::size_t>(numPoints));
  for (int i = 0; i < numPoints; ++i)
  {
    onBoundary[static_cast<std::size_t>(i)] = mesh.IsBoundaryPoint(i) ? 1 : 0;
  }
  ComputeCollimatedBeamAtPoints(
    surface, beams, shadows, mesh.GetPoints(), onBoundary, mesh.GetPointNormals(), out);
}

} // namespace

void AddCollimatedLoads(const TetMesh& mesh, const OpticalProperties& material, CollimatedSource& out)
{
  const int numTets = mesh.GetNumberOfTets();
  if (out.Load.size() != 3 * static_cast<size_t>(mesh.GetNumberOfPoints()))
  {
    out.Load.assign(3 * static_cast<size_t>(mesh.GetNumberOfPoints()), 0.0);
  }
  const std::vector<double>& muA = material.AbsorptionCoefficient;
  const std::vector<double>& muS = material.ReducedScatteringCoefficient;
  std::vector<double> tetLoad(12 * static_cast<size_t>(numTets), 0.0);
  std::vector<double> tetAbsorbed(3 * static_cast<size_t>(numTets), 0.0);
#pragma omp parallel for schedule(static)
  for (int t = 0; t < numTets; ++t)
  {
    const int* v = mesh.GetTet(t);
    const double volume = mesh.GetTetVolume(t);
    for (const CollimatedSource::Beam& beam : out.Beams)
    {
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        double e[4], path[4];
        TetValues(beam, v, c, e, path);
        double moment[4], total = 0.0;
        if (!TetIntegrals(e, path, 0.0, volume, total, moment))
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

CollimatedSource ComputeCollimatedSource(const TetMesh& mesh, const OpticalProperties& material,
  const std::vector<LightSource>& lights, bool shadows)
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
  }

  BeamFieldAtPoints(mesh, material, beams, shadows, out);

  // Loads: integral of mu_s' E_c phi_a per tet and beam, then scattered to
  // the points.
  AddCollimatedLoads(mesh, material, out);
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
