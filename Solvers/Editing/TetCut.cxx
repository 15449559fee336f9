#include "TetCut.h"

#include "Error.h"

#include <omp.h>

#include <algorithm>
#include <cstdint>
#include <cmath>
#include <string>

namespace translucency
{

namespace
{
void Sub(const double* a, const double* b, double* r)
{
  r[0] = a[0] - b[0];
  r[1] = a[1] - b[1];
  r[2] = a[2] - b[2];
}
void Cross(const double* a, const double* b, double* r)
{
  r[0] = a[1] * b[2] - a[2] * b[1];
  r[1] = a[2] * b[0] - a[0] * b[2];
  r[2] = a[0] * b[1] - a[1] * b[0];
}
double Dot(const double* a, const double* b)
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
constexpr double Pi = 3.14159265358979323846;

/// Indices k with flag[k] != 0, ascending (a parallel stream compaction:
/// per-thread counts, an exclusive scan, then each thread writes its block).
std::vector<int> Compact(const std::vector<char>& flag)
{
  const std::int64_t n = static_cast<std::int64_t>(flag.size());
  std::vector<std::int64_t> counts(static_cast<std::size_t>(omp_get_max_threads()) + 1, 0);
  std::vector<int> out;
#pragma omp parallel
  {
    const int threads = omp_get_num_threads(), tid = omp_get_thread_num();
    const std::int64_t begin = n * tid / threads, end = n * (tid + 1) / threads;
    std::int64_t count = 0;
    for (std::int64_t k = begin; k < end; ++k)
    {
      count += flag[k] != 0;
    }
    counts[tid + 1] = count;
#pragma omp barrier
#pragma omp single
    {
      for (int t = 0; t < threads; ++t)
      {
        counts[t + 1] += counts[t];
      }
      out.resize(counts[threads]);
    }
    std::int64_t at = counts[tid];
    for (std::int64_t k = begin; k < end; ++k)
    {
      if (flag[k])
      {
        out[at++] = static_cast<int>(k);
      }
    }
  }
  return out;
}
}

//------------------------------------------------------------------------------
double TetCut::SignedVolume(const double* a, const double* b, const double* c, const double* d)
{
  double u[3], v[3], w[3], n[3];
  Sub(b, a, u);
  Sub(c, a, v);
  Sub(d, a, w);
  Cross(u, v, n);
  return Dot(n, w) / 6.0;
}

//------------------------------------------------------------------------------
double TetCut::MinimumDihedralAngle(
  const double* a, const double* b, const double* c, const double* d)
{
  return std::acos(LargestDihedralCosine(a, b, c, d)) * 180.0 / Pi;
}

//------------------------------------------------------------------------------
double TetCut::LargestDihedralCosine(
  const double* a, const double* b, const double* c, const double* d)
{
  const double* p[4] = { a, b, c, d };
  // Outward normal of face k (the face opposite vertex k).
  double n[4][3];
  for (int k = 0; k < 4; ++k)
  {
    const double* q0 = p[(k + 1) % 4];
    const double* q1 = p[(k + 2) % 4];
    const double* q2 = p[(k + 3) % 4];
    double u[3], v[3], w[3];
    Sub(q1, q0, u);
    Sub(q2, q0, v);
    Cross(u, v, n[k]);
    Sub(p[k], q0, w);
    const double s = Dot(n[k], w) > 0 ? -1.0 : 1.0;
    const double len = std::sqrt(Dot(n[k], n[k]));
    if (len == 0.0)
    {
      return 1.0; // a degenerate face: angle 0
    }
    for (int j = 0; j < 3; ++j)
    {
      n[k][j] *= s / len;
    }
  }
  // The dihedral angle at the edge shared by faces k and l is pi minus the
  // angle between their outward normals: its cosine is -n_k.n_l.
  double largest = -1.0;
  for (int k = 0; k < 4; ++k)
  {
    for (int l = k + 1; l < 4; ++l)
    {
      largest = std::max(largest, std::min(1.0, -Dot(n[k], n[l])));
    }
  }
  return largest;
}

namespace
{
/// Cut, 1. The tets to keep (not all four vertices on the removed side)
/// and the points they use; the first tet with a point id out of range
/// (in tet order) is an error.
void MarkKept(int numPoints, const std::vector<int>& tets, const std::vector<double>& side,
  std::vector<char>& keepTet, std::vector<char>& keepPoint)
{
  const int numTets = static_cast<int>(tets.size() / 4);
  keepTet.assign(numTets, 0);
  keepPoint.assign(numPoints, 0);
  std::int64_t firstBad = numTets;
#pragma omp parallel for schedule(static) reduction(min : firstBad)
  for (std::int64_t t = 0; t < numTets; ++t)
  {
    const int* v = &tets[4 * t];
    bool removed = true, valid = true;
    for (int a = 0; a < 4; ++a)
    {
      valid = valid && v[a] >= 0 && v[a] < numPoints;
      removed = removed && valid && side[v[a]] > 0.0;
    }
    keepTet[t] = valid && !removed;
    if (!valid)
    {
      firstBad = std::min(firstBad, t);
    }
  }
  if (firstBad < numTets)
  {
    const int* v = &tets[4 * firstBad];
    int bad = v[0];
    for (int a = 0; a < 4; ++a)
    {
      if (v[a] < 0 || v[a] >= numPoints)
      {
        bad = v[a];
        break;
      }
    }
    throw Error("TetCut: tet " + std::to_string(firstBad) + " has point id " +
      std::to_string(bad) + " out of range [0, " + std::to_string(numPoints) + ")");
  }
#pragma omp parallel for schedule(static)
  for (std::int64_t t = 0; t < numTets; ++t)
  {
    if (keepTet[t])
    {
      for (int a = 0; a < 4; ++a)
      {
#pragma omp atomic write
        keepPoint[tets[4 * t + a]] = 1;
      }
    }
  }
}

/// Points ordered by their coordinates (x, then y, then z; then index): an
/// order of the vertices that does not depend on their numbering, so the
/// relaxation gives the same positions for any point order or partition.
struct CoordinateLess
{
  const std::vector<double>& Points;
  bool operator()(int a, int b) const
  {
    const double* p = &Points[3 * static_cast<std::size_t>(a)];
    const double* q = &Points[3 * static_cast<std::size_t>(b)];
    if (p[0] != q[0])
      return p[0] < q[0];
    if (p[1] != q[1])
      return p[1] < q[1];
    if (p[2] != q[2])
      return p[2] < q[2];
    return a < b;
  }
};

/// Cut, 3. The neighbourhood of the movable vertices: their tets (CSR,
/// tets ascending; only kept tets straddling the cut have any) and their
/// one-rings (unique neighbours through those tets).
struct MovableRings
{
  std::vector<int> Offsets, Incident;   ///< movable vertex j -> its tets
  std::vector<int> RingOffsets, Ring; ///< movable vertex j -> its neighbours
};

MovableRings BuildMovableRings(const std::vector<int>& tets, int m, int n,
  const std::vector<char>& isMovable, const std::vector<int>& movable,
  const CoordinateLess& less)
{
  MovableRings rings;
  std::vector<int>& offsets = rings.Offsets;
  std::vector<int>& incident = rings.Incident;
  std::vector<int>& ringOffsets = rings.RingOffsets;
  std::vector<int>& ring = rings.Ring;
  // The tets a movable vertex belongs to all straddle the cut (kept, with a
  // vertex on the removed side): only those are needed, in kept order.
  std::vector<char> isStraddling(m);
#pragma omp parallel for schedule(static)
  for (int t = 0; t < m; ++t)
  {
    const int* v = &tets[4 * static_cast<std::size_t>(t)];
    isStraddling[t] = isMovable[v[0]] || isMovable[v[1]] || isMovable[v[2]] || isMovable[v[3]];
  }
  const std::vector<int> straddling = Compact(isStraddling);
  // Movable vertex -> its tets (CSR over the movable vertices, tets ascending).
  std::vector<int> movableId(n, -1);
  for (std::size_t j = 0; j < movable.size(); ++j)
  {
    movableId[movable[j]] = static_cast<int>(j);
  }
  offsets.assign(movable.size() + 1, 0);
  for (int t : straddling)
  {
    for (int a = 0; a < 4; ++a)
    {
      const int j = movableId[tets[4 * static_cast<std::size_t>(t) + a]];
      if (j >= 0)
      {
        ++offsets[j + 1];
      }
    }
  }
  for (std::size_t j = 0; j < movable.size(); ++j)
  {
    offsets[j + 1] += offsets[j];
  }
  incident.assign(offsets.back(), 0);
  {
    std::vector<int> fill(offsets.begin(), offsets.end() - 1);
    for (int t : straddling)
    {
      for (int a = 0; a < 4; ++a)
      {
        const int j = movableId[tets[4 * static_cast<std::size_t>(t) + a]];
        if (j >= 0)
        {
          incident[fill[j]++] = t;
        }
      }
    }
  }
  // One-ring of each movable vertex (unique neighbours through its tets).
  ringOffsets.assign(movable.size() + 1, 0);
  for (std::size_t j = 0; j < movable.size(); ++j)
  {
    const int i = movable[j];
    const std::size_t begin = ring.size();
    for (int e = offsets[j]; e < offsets[j + 1]; ++e)
    {
      for (int a = 0; a < 4; ++a)
      {
        const int w = tets[4 * static_cast<std::size_t>(incident[e]) + a];
        if (w != i)
        {
          ring.push_back(w);
        }
      }
    }
    std::sort(ring.begin() + begin, ring.end());
    ring.erase(std::unique(ring.begin() + begin, ring.end()), ring.end());
    // Summed in the order of the coordinates: the same bits whatever the
    // point numbering.
    std::sort(ring.begin() + begin, ring.end(), less);
    ringOffsets[j + 1] = static_cast<int>(ring.size());
  }
  return rings;
}

/// Cut, 3. The relaxation sweeps (paper Sec. 5.1): each movable vertex
/// toward the mean of its one-ring by rho, unless that crosses the cutting
/// surface, inverts a tet or makes its smallest dihedral angle smaller than
/// minDihedral (degrees) and smaller than before. Returns the number of
/// vertices moved at least once; `blocked` counts the refusals of the last
/// sweep, `sweeps` the sweeps done.
int RelaxSweeps(std::vector<double>& points, const std::vector<int>& tets,
  const std::vector<int>& movable, const MovableRings& rings, const TetCut::SideFunction& F,
  double rho, int iterations, double minDihedral, int& blocked, int& sweeps)
{
  const std::vector<int>& offsets = rings.Offsets;
  const std::vector<int>& incident = rings.Incident;
  const std::vector<int>& ringOffsets = rings.RingOffsets;
  const std::vector<int>& ring = rings.Ring;
  const double minDihedralCosine = std::cos(minDihedral * Pi / 180.0);
  std::vector<char> everMoved(movable.size(), 0);
  auto P = [&points](int k) { return &points[3 * static_cast<std::size_t>(k)]; };
  for (int sweep = 0; sweep < iterations; ++sweep)
  {
    int movedThisSweep = 0;
    blocked = 0;
    for (std::size_t j = 0; j < movable.size(); ++j)
    {
      const int i = movable[j];
      double mean[3] = { 0.0, 0.0, 0.0 };
      const int count = ringOffsets[j + 1] - ringOffsets[j];
      for (int r = ringOffsets[j]; r < ringOffsets[j + 1]; ++r)
      {
        const double* q = P(ring[r]);
        mean[0] += q[0];
        mean[1] += q[1];
        mean[2] += q[2];
      }
      double* x = P(i);
      const double old[3] = { x[0], x[1], x[2] };
      double trial[3];
      for (int c = 0; c < 3; ++c)
      {
        trial[c] = old[c] + rho * (mean[c] / count - old[c]);
      }
      if (trial[0] == old[0] && trial[1] == old[1] && trial[2] == old[2])
      {
        continue; // at the mean already: nothing to do, not blocked
      }
      // Never cross the cutting surface. Angles are compared by their
      // cosines (acos is decreasing): the smallest dihedral angle has the
      // largest cosine.
      bool accept = F(trial) >= 0.0;
      for (int e = offsets[j]; accept && e < offsets[j + 1]; ++e)
      {
        const int* v = &tets[4 * static_cast<std::size_t>(incident[e])];
        std::copy_n(trial, 3, x);
        const double volume = TetCut::SignedVolume(P(v[0]), P(v[1]), P(v[2]), P(v[3]));
        const double after =
          volume > 0.0 ? TetCut::LargestDihedralCosine(P(v[0]), P(v[1]), P(v[2]), P(v[3])) : 1.0;
        std::copy_n(old, 3, x);
        accept = volume > 0.0 &&
          (after <= minDihedralCosine ||
            after <= TetCut::LargestDihedralCosine(P(v[0]), P(v[1]), P(v[2]), P(v[3])));
      }
      if (accept)
      {
        std::copy_n(trial, 3, x);
        everMoved[j] = 1;
        ++movedThisSweep;
      }
      else
      {
        ++blocked;
      }
    }
    ++sweeps;
    if (movedThisSweep == 0)
    {
      break;
    }
  }
  return static_cast<int>(std::count(everMoved.begin(), everMoved.end(), 1));
}
} // namespace


//------------------------------------------------------------------------------
void TetCut::Cut(const std::vector<double>& points, const std::vector<int>& tets,
  const std::vector<double>& side, const SideFunction& F)
{
  const int numPoints = static_cast<int>(points.size() / 3);
  const int numTets = static_cast<int>(tets.size() / 4);
  if (points.size() % 3 != 0 || tets.size() % 4 != 0)
  {
    throw Error("TetCut: points must hold 3 and tets 4 values per entry");
  }
  if (static_cast<int>(side.size()) != numPoints)
  {
    throw Error("TetCut: " + std::to_string(side.size()) + " side values for " +
      std::to_string(numPoints) + " points");
  }
  if (!(Rho_ >= 0.0 && Rho_ <= 1.0))
  {
    throw Error("TetCut: relaxation factor " + std::to_string(Rho_) + " is not in [0, 1]");
  }
  KeptTets_.clear();
  KeptPoints_.clear();
  Points_.clear();
  Tets_.clear();
  Movable_ = Moved_ = Blocked_ = Sweeps_ = 0;

  // 1. Delete the tets with all four vertices on the removed side (in
  // parallel; the first bad id, in tet order, is reported).
  std::vector<char> keepTet, keepPoint;
  MarkKept(numPoints, tets, side, keepTet, keepPoint);
  KeptTets_ = Compact(keepTet);
  // 2. Drop the orphan vertices and renumber (ids in input order).
  KeptPoints_ = Compact(keepPoint);
  const int n = static_cast<int>(KeptPoints_.size());
  const int m = static_cast<int>(KeptTets_.size());
  std::vector<int> newId(numPoints);
  Points_.resize(3 * static_cast<std::size_t>(n));
#pragma omp parallel for schedule(static)
  for (int k = 0; k < n; ++k)
  {
    newId[KeptPoints_[k]] = k;
    std::copy_n(&points[3 * static_cast<std::size_t>(KeptPoints_[k])], 3, &Points_[3 * static_cast<std::size_t>(k)]);
  }
  Tets_.resize(4 * static_cast<std::size_t>(m));
#pragma omp parallel for schedule(static)
  for (int k = 0; k < m; ++k)
  {
    const int* v = &tets[4 * static_cast<std::size_t>(KeptTets_[k])];
    for (int a = 0; a < 4; ++a)
    {
      Tets_[4 * static_cast<std::size_t>(k) + a] = newId[v[a]];
    }
  }

  // 3. Relax the remaining vertices of the removed side (paper Sec. 5.1).
  std::vector<char> isMovable(n);
#pragma omp parallel for schedule(static)
  for (int k = 0; k < n; ++k)
  {
    isMovable[k] = side[KeptPoints_[k]] > 0.0;
  }
  std::vector<int> movable = Compact(isMovable);
  Movable_ = static_cast<int>(movable.size());
  if (m == 0 || Iterations_ <= 0 || movable.empty())
  {
    return;
  }
  // Visited in the order of their coordinates (before any move), not of
  // their ids: the Gauss-Seidel sweep then gives the same positions for any
  // point order, e.g. a mesh redistributed over MPI ranks (CutFront).
  const CoordinateLess less{ Points_ };
  std::sort(movable.begin(), movable.end(), less);
  const MovableRings rings = BuildMovableRings(Tets_, m, n, isMovable, movable, less);
  Moved_ = RelaxSweeps(
    Points_, Tets_, movable, rings, F, Rho_, Iterations_, MinDihedral_, Blocked_, Sweeps_);
}

} // namespace translucency
