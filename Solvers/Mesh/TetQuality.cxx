#include "TetQuality.h"

#include "Error.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace translucency
{
namespace
{
struct Vec
{
  double X, Y, Z;
};
Vec Sub(const double* a, const double* b)
{
  return { a[0] - b[0], a[1] - b[1], a[2] - b[2] };
}
Vec Cross(const Vec& a, const Vec& b)
{
  return { a.Y * b.Z - a.Z * b.Y, a.Z * b.X - a.X * b.Z, a.X * b.Y - a.Y * b.X };
}
double Dot(const Vec& a, const Vec& b)
{
  return a.X * b.X + a.Y * b.Y + a.Z * b.Z;
}
double Norm(const Vec& a)
{
  return std::sqrt(Dot(a, a));
}

struct PerTet
{
  double MinAngle, MaxAngle, RadiusEdge, Volume;
  double EdgeSum, EdgeSquares;
};

PerTet Measure(const double* p[4])
{
  PerTet r{};
  static const int edgePairs[6][2] = { { 0, 1 }, { 0, 2 }, { 0, 3 }, { 1, 2 }, { 1, 3 }, { 2, 3 } };
  double shortest = std::numeric_limits<double>::infinity();
  for (const auto& e : edgePairs)
  {
    const double l = Norm(Sub(p[e[1]], p[e[0]]));
    shortest = std::min(shortest, l);
    r.EdgeSum += l;
    r.EdgeSquares += l * l;
  }
  const Vec a = Sub(p[1], p[0]), b = Sub(p[2], p[0]), c = Sub(p[3], p[0]);
  const double det = Dot(a, Cross(b, c));
  r.Volume = std::abs(det) / 6.0;
  // Circumcentre relative to p0: (|a|^2 b x c + |b|^2 c x a + |c|^2 a x b) / (2 det).
  if (det != 0.0)
  {
    const Vec bc = Cross(b, c), ca = Cross(c, a), ab = Cross(a, b);
    const double aa = Dot(a, a), bb = Dot(b, b), cc = Dot(c, c);
    const Vec o = { (aa * bc.X + bb * ca.X + cc * ab.X) / (2 * det),
      (aa * bc.Y + bb * ca.Y + cc * ab.Y) / (2 * det),
      (aa * bc.Z + bb * ca.Z + cc * ab.Z) / (2 * det) };
    r.RadiusEdge = Norm(o) / shortest;
  }
  else
  {
    r.RadiusEdge = std::numeric_limits<double>::infinity();
  }
  // Outward face normals; the interior dihedral angle at the edge shared by
  // faces i and j is pi - angle(n_i, n_j).
  Vec n[4];
  static const int faces[4][3] = { { 1, 2, 3 }, { 0, 3, 2 }, { 0, 1, 3 }, { 0, 2, 1 } };
  for (int f = 0; f < 4; ++f)
  {
    n[f] = Cross(Sub(p[faces[f][1]], p[faces[f][0]]), Sub(p[faces[f][2]], p[faces[f][0]]));
  }
  r.MinAngle = 180.0;
  r.MaxAngle = 0.0;
  for (int i = 0; i < 4; ++i)
  {
    for (int j = i + 1; j < 4; ++j)
    {
      const double ni = Norm(n[i]), nj = Norm(n[j]);
      double angle = 0.0;
      if (ni > 0 && nj > 0 && det != 0.0)
      {
        const double cosine = std::clamp(Dot(n[i], n[j]) / (ni * nj), -1.0, 1.0);
        // With det < 0 the normals point inwards; the angle between them is the same.
        angle = 180.0 - std::acos(cosine) * 180.0 / 3.14159265358979323846;
      }
      r.MinAngle = std::min(r.MinAngle, angle);
      r.MaxAngle = std::max(r.MaxAngle, det != 0.0 ? angle : 180.0);
    }
  }
  return r;
}
} // namespace

TetQualityStats ComputeTetQuality(
  const std::vector<double>& points, const std::vector<int>& tets, double radiusEdgeBound)
{
  TetQualityStats s;
  const long long numTets = static_cast<long long>(tets.size() / 4);
  const long long numPoints = static_cast<long long>(points.size() / 3);
  s.NumberOfTets = static_cast<std::size_t>(numTets);
  if (numTets == 0)
  {
    return s;
  }
  for (long long t = 0; t < numTets; ++t)
  {
    for (int k = 0; k < 4; ++k)
    {
      const int id = tets[4 * t + k];
      if (id < 0 || id >= numPoints)
      {
        throw Error("tet " + std::to_string(t) + " has point id " + std::to_string(id) +
          " (the mesh has " + std::to_string(numPoints) + " points)");
      }
    }
  }
  double minAngle = 180.0, maxAngle = 0.0, maxRe = 0.0, sumRe = 0.0, edgeSum = 0.0,
         edgeSquares = 0.0, minVol = std::numeric_limits<double>::infinity(), maxVol = 0.0;
  long long above = 0, below5 = 0;
  std::array<long long, 8> hist{};
  const double bound = radiusEdgeBound > 0 ? radiusEdgeBound * (1 + 1e-9) : 0.0;
#pragma omp parallel
  {
    std::array<long long, 8> localHist{};
#pragma omp for reduction(min : minAngle, minVol) reduction(max : maxAngle, maxRe, maxVol) \
  reduction(+ : sumRe, edgeSum, edgeSquares, above, below5)
    for (long long t = 0; t < numTets; ++t)
    {
      const double* p[4];
      for (int k = 0; k < 4; ++k)
      {
        p[k] = &points[3 * static_cast<std::size_t>(tets[4 * t + k])];
      }
      const PerTet m = Measure(p);
      minAngle = std::min(minAngle, m.MinAngle);
      maxAngle = std::max(maxAngle, m.MaxAngle);
      maxRe = std::max(maxRe, m.RadiusEdge);
      sumRe += m.RadiusEdge;
      edgeSum += m.EdgeSum;
      edgeSquares += m.EdgeSquares;
      minVol = std::min(minVol, m.Volume);
      maxVol = std::max(maxVol, m.Volume);
      if (bound > 0 && m.RadiusEdge > bound)
      {
        ++above;
      }
      localHist[std::min(7, static_cast<int>(m.MinAngle / 10.0))]++;
      below5 += m.MinAngle < 5.0 ? 1 : 0;
    }
#pragma omp critical
    for (int k = 0; k < 8; ++k)
    {
      hist[k] += localHist[k];
    }
  }
  s.MinDihedral = minAngle;
  s.MaxDihedral = maxAngle;
  for (int k = 0; k < 8; ++k)
  {
    s.MinDihedralHistogram[k] = static_cast<std::size_t>(hist[k]);
  }
  s.TetsBelow5Degrees = static_cast<std::size_t>(below5);
  s.MaxRadiusEdge = maxRe;
  s.MeanRadiusEdge = sumRe / static_cast<double>(numTets);
  s.FractionAboveRadiusEdgeBound = static_cast<double>(above) / static_cast<double>(numTets);
  const double edges = 6.0 * static_cast<double>(numTets);
  s.MeanEdgeLength = edgeSum / edges;
  const double variance = std::max(0.0, edgeSquares / edges - s.MeanEdgeLength * s.MeanEdgeLength);
  s.EdgeLengthCV = s.MeanEdgeLength > 0 ? std::sqrt(variance) / s.MeanEdgeLength : 0.0;
  s.MinVolume = minVol;
  s.MaxVolume = maxVol;
  return s;
}

} // namespace translucency
