#include "FormFactors.h"

#include "Error.h"
#include "RadiosityScene.h"
#include "RayCaster.h"
#include "ResourceLimits.h"
#include "Timer.h"
#include "TriangleGeometry.h"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <sstream>

namespace translucency
{

namespace
{

constexpr double Pi = 3.14159265358979323846;

/// SplitMix64 finaliser: a counter-based random stream.
inline std::uint64_t Mix(std::uint64_t z)
{
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

inline double ToUnit(std::uint64_t z)
{
  return static_cast<double>(z >> 11) * (1.0 / 9007199254740992.0);
}

} // namespace

void FormFactorMatrix::Multiply(const std::vector<double>& x, std::vector<double>& y) const
{
  y.assign(3 * static_cast<std::size_t>(NumberOfPatches), 0.0);
#pragma omp parallel for schedule(static, 256) if (NumberOfPatches > 16384)
  for (int i = 0; i < NumberOfPatches; ++i)
  {
    double s[3] = { 0.0, 0.0, 0.0 };
    for (int k = RowOffsets[i]; k < RowOffsets[i + 1]; ++k)
    {
      const double f = Values[k];
      const double* xj = &x[3 * static_cast<std::size_t>(Columns[k])];
      s[0] += f * xj[0];
      s[1] += f * xj[1];
      s[2] += f * xj[2];
    }
    for (int c = 0; c < 3; ++c)
    {
      y[3 * static_cast<std::size_t>(i) + c] = s[c];
    }
  }
}

double FormFactorMatrix::RowSum(int i) const
{
  double s = 0.0;
  for (int k = RowOffsets[i]; k < RowOffsets[i + 1]; ++k)
  {
    s += Values[k];
  }
  return s;
}

double FormFactorMatrix::Get(int i, int j) const
{
  auto begin = Columns.begin() + RowOffsets[i], end = Columns.begin() + RowOffsets[i + 1];
  auto it = std::lower_bound(begin, end, j);
  return it != end && *it == j ? Values[it - Columns.begin()] : 0.0;
}

namespace
{
/// Compute: ray r's cosine-weighted direction in the patch frame (dx, dy,
/// dz): stratified square (the first `stratified` = side^2 rays) ->
/// concentric disk, rotated by patchRotation -> hemisphere; h hashes the
/// ray.
inline void CosineDirection(int r, int side, int stratified, std::uint64_t h,
  double patchRotation, double& dx, double& dy, double& dz)
{
  double u1 = ToUnit(Mix(h + 3)), u2 = ToUnit(h);
  if (r < stratified)
  {
    u1 = ((r % side) + u1) / side;
    u2 = ((r / side) + u2) / side;
  }
  const double sx = 2.0 * u1 - 1.0, sy = 2.0 * u2 - 1.0;
  double dr = 0.0, phi = 0.0;
  if (sx != 0.0 || sy != 0.0)
  {
    if (std::abs(sx) > std::abs(sy))
    {
      dr = sx;
      phi = (Pi / 4.0) * (sy / sx);
    }
    else
    {
      dr = sy;
      phi = (Pi / 2.0) - (Pi / 4.0) * (sx / sy);
    }
  }
  phi += patchRotation;
  dx = dr * std::cos(phi);
  dy = dr * std::sin(phi);
  dz = std::sqrt(std::max(0.0, 1.0 - dx * dx - dy * dy));
}

/// Compute: the per-row results merged into the CSR matrix F; returns the
/// sum of the dropped fractions.
double MergeRows(std::vector<std::vector<std::pair<int, float>>>& rows,
  const std::vector<double>& dropped, FormFactorMatrix& F)
{
  const int numPatches = static_cast<int>(rows.size());
  F.NumberOfPatches = numPatches;
  F.RowOffsets.assign(numPatches + 1, 0);
  for (int i = 0; i < numPatches; ++i)
  {
    F.RowOffsets[i + 1] = F.RowOffsets[i] + static_cast<int>(rows[i].size());
  }
  F.Columns.resize(F.RowOffsets.back());
  F.Values.resize(F.RowOffsets.back());
  double droppedSum = 0.0;
  for (int i = 0; i < numPatches; ++i)
  {
    int k = F.RowOffsets[i];
    for (const auto& e : rows[i])
    {
      F.Columns[k] = e.first;
      F.Values[k] = e.second;
      ++k;
    }
    droppedSum += dropped[i];
    std::vector<std::pair<int, float>>().swap(rows[i]);
  }
  return droppedSum;
}

} // namespace

bool FormFactorComputer::Compute(const RadiosityScene& scene, FormFactorMatrix& F)
{
  if (RaysPerPatch_ < 1)
  {
    throw Error("form factors: rays per patch must be >= 1, not " + std::to_string(RaysPerPatch_));
  }
  if (!(Threshold_ >= 0.0) || !std::isfinite(Threshold_))
  {
    std::ostringstream os;
    os << "form factors: threshold " << Threshold_ << " must be finite and >= 0";
    throw Error(os.str());
  }
  const int numPatches = scene.GetNumberOfPatches();
  {
    const double rays = static_cast<double>(numPatches) * RaysPerPatch_;
    if (rays > MaxRays_ && !GetLongRunsAllowed())
    {
      throw Error("form factors: " + std::to_string(numPatches) + " patches x " +
        std::to_string(RaysPerPatch_) + " rays per patch = " + FormatNumber(rays) +
        " rays, above the budget of " + FormatNumber(MaxRays_) +
        " rays: use fewer rays per patch (rays_per_patch, --rays) or larger patches (or " +
        LongRunOverride() + ", or FormFactorComputer::SetMaxRays)");
    }
    const double entries =
      static_cast<double>(numPatches) * std::min<double>(RaysPerPatch_, numPatches);
    CheckMemory("form factors: " + std::to_string(numPatches) + " patches x " +
        std::to_string(RaysPerPatch_) + " rays per patch (up to " + FormatNumber(entries) +
        " entries)",
      entries * 12.0 + numPatches * 64.0, MemoryLimit_, "use fewer rays per patch or larger patches");
  }
  const auto start = Clock::now();
  const std::vector<double>& points = scene.GetPoints();
  const std::vector<int>& triangles = scene.GetTriangles();
  const std::vector<double>& normals = scene.GetNormals();
  const RayCaster& caster = scene.GetRayCaster();
  const double offset = scene.GetRayOffset();
  const int n = RaysPerPatch_;
  const int side = std::max(1, static_cast<int>(std::floor(std::sqrt(static_cast<double>(n)))));
  const int stratified = side * side; // rays beyond side^2 are plain random

  // Per-row results, merged into CSR after the parallel loop.
  std::vector<std::vector<std::pair<int, float>>> rows(numPatches);
  std::vector<double> dropped(numPatches, 0.0);
  std::atomic<bool> aborted(false);
  std::atomic<int> done(0);

  // The callback runs on the calling thread only (thread 0): once before the
  // loop, so an abort is seen even if the other threads take every row, then
  // every 256 rows thread 0 computes.
  if (Progress_ && !Progress_(0.0))
  {
    return false;
  }
#pragma omp parallel
  {
    std::vector<int> hits;
    int rowsOfThisThread = 0;
#pragma omp for schedule(dynamic, 16)
    for (int i = 0; i < numPatches; ++i)
    {
      if (aborted.load(std::memory_order_relaxed))
      {
        continue;
      }
      if (Progress_ && omp_get_thread_num() == 0 && ++rowsOfThisThread % 256 == 0 &&
        !Progress_(static_cast<double>(done.load()) / numPatches))
      {
        aborted.store(true);
        continue;
      }
      const double* a = &points[3 * static_cast<std::size_t>(triangles[3 * i])];
      const double* b = &points[3 * static_cast<std::size_t>(triangles[3 * i + 1])];
      const double* c = &points[3 * static_cast<std::size_t>(triangles[3 * i + 2])];
      const double* nrm = &normals[3 * static_cast<std::size_t>(i)];
      double t[3], s[3]; // orthonormal frame (t, s, n)
      OrthonormalFrame(nrm, t, s);
      hits.clear();
      const std::uint64_t key = Mix(Seed_ * 0x632be59bd9b4e019ULL + static_cast<std::uint64_t>(i));
      // A random rotation of the stratified pattern about the normal per
      // patch: neighbouring patches do not share ray directions (which
      // would correlate their errors into visible streaks).
      const double patchRotation = 2.0 * Pi * ToUnit(Mix(key ^ 0x5851f42d4c957f2dULL));
      for (int r = 0; r < n; ++r)
      {
        const std::uint64_t h = Mix(key + 4 * static_cast<std::uint64_t>(r));
        // Uniform point on the triangle (square-root parametrisation).
        const double r1 = ToUnit(Mix(h + 1)), r2 = ToUnit(Mix(h + 2));
        const double sq = std::sqrt(r1);
        const double wa = 1.0 - sq, wb = sq * (1.0 - r2), wc = sq * r2;
        // Cosine-weighted direction: stratified square -> concentric disk -> hemisphere.
        double dx, dy, dz;
        CosineDirection(r, side, stratified, h, patchRotation, dx, dy, dz);
        double origin[3], dir[3];
        for (int d = 0; d < 3; ++d)
        {
          origin[d] = wa * a[d] + wb * b[d] + wc * c[d] + offset * nrm[d];
          dir[d] = dx * t[d] + dy * s[d] + dz * nrm[d];
        }
        double hitT;
        int j;
        if (caster.FirstHit(origin, dir, std::numeric_limits<double>::infinity(), hitT, j) &&
          j != i)
        {
          const double* nj = &normals[3 * static_cast<std::size_t>(j)];
          // Only the front of patch j receives (one-sided patches).
          if (nj[0] * dir[0] + nj[1] * dir[1] + nj[2] * dir[2] < 0.0)
          {
            hits.push_back(j);
          }
        }
      }
      std::sort(hits.begin(), hits.end());
      auto& row = rows[i];
      for (std::size_t k = 0; k < hits.size();)
      {
        std::size_t m = k;
        while (m < hits.size() && hits[m] == hits[k])
        {
          ++m;
        }
        const double f = static_cast<double>(m - k) / n;
        if (f >= Threshold_)
        {
          row.emplace_back(hits[k], static_cast<float>(f));
        }
        else
        {
          dropped[i] += f;
        }
        k = m;
      }
      done.fetch_add(1, std::memory_order_relaxed);
    }
  }
  if (aborted.load())
  {
    return false;
  }
  const double droppedSum = MergeRows(rows, dropped, F);
  NumberOfRays_ = static_cast<long long>(numPatches) * n;
  NumberOfNonZeros_ = static_cast<long long>(F.Columns.size());
  DroppedFraction_ = numPatches > 0 ? droppedSum / numPatches : 0.0;
  MemoryBytes_ = F.MemoryBytes();
  Milliseconds_ =
    MillisecondsSince(start);
  return true;
}

} // namespace translucency
