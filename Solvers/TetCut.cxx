#include "TetCut.h"

#include "Error.h"

#include <algorithm>
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
      return 0.0;
    }
    for (int j = 0; j < 3; ++j)
    {
      n[k][j] *= s / len;
    }
  }
  // The dihedral angle at the edge shared by faces k and l is pi minus the
  // angle between their outward normals.
  double smallest = 180.0;
  for (int k = 0; k < 4; ++k)
  {
    for (int l = k + 1; l < 4; ++l)
    {
      const double cosine = std::max(-1.0, std::min(1.0, -Dot(n[k], n[l])));
      smallest = std::min(smallest, std::acos(cosine) * 180.0 / Pi);
    }
  }
  return smallest;
}

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

  // 1. Delete the tets with all four vertices on the removed side.
  std::vector<int> newId(numPoints, -1);
  for (int t = 0; t < numTets; ++t)
  {
    const int* v = &tets[4 * static_cast<std::size_t>(t)];
    bool removed = true;
    for (int a = 0; a < 4; ++a)
    {
      if (v[a] < 0 || v[a] >= numPoints)
      {
        throw Error("TetCut: tet " + std::to_string(t) + " has point id " +
          std::to_string(v[a]) + " out of range [0, " + std::to_string(numPoints) + ")");
      }
      removed = removed && side[v[a]] > 0.0;
    }
    if (!removed)
    {
      KeptTets_.push_back(t);
      for (int a = 0; a < 4; ++a)
      {
        newId[v[a]] = 0;
      }
    }
  }
  // 2. Drop the orphan vertices and renumber.
  for (int i = 0; i < numPoints; ++i)
  {
    if (newId[i] == 0)
    {
      newId[i] = static_cast<int>(KeptPoints_.size());
      KeptPoints_.push_back(i);
    }
  }
  const int n = static_cast<int>(KeptPoints_.size());
  Points_.resize(3 * static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k)
  {
    std::copy_n(&points[3 * static_cast<std::size_t>(KeptPoints_[k])], 3, &Points_[3 * k]);
  }
  Tets_.reserve(4 * KeptTets_.size());
  for (int t : KeptTets_)
  {
    for (int a = 0; a < 4; ++a)
    {
      Tets_.push_back(newId[tets[4 * static_cast<std::size_t>(t) + a]]);
    }
  }
  const int m = static_cast<int>(KeptTets_.size());

  // 3. Relax the remaining vertices of the removed side (paper Sec. 5.1).
  std::vector<int> movable;
  for (int k = 0; k < n; ++k)
  {
    if (side[KeptPoints_[k]] > 0.0)
    {
      movable.push_back(k);
    }
  }
  Movable_ = static_cast<int>(movable.size());
  if (m == 0 || Iterations_ <= 0 || movable.empty())
  {
    return;
  }
  // Point -> tets of the cut mesh (CSR).
  std::vector<int> offsets(n + 1, 0);
  for (int v : Tets_)
  {
    ++offsets[v + 1];
  }
  for (int k = 0; k < n; ++k)
  {
    offsets[k + 1] += offsets[k];
  }
  std::vector<int> incident(offsets[n]);
  {
    std::vector<int> fill(offsets.begin(), offsets.end() - 1);
    for (int t = 0; t < m; ++t)
    {
      for (int a = 0; a < 4; ++a)
      {
        incident[fill[Tets_[4 * t + a]]++] = t;
      }
    }
  }
  // One-ring of each movable vertex (unique neighbours through its tets).
  std::vector<int> ringOffsets(movable.size() + 1, 0);
  std::vector<int> ring;
  for (std::size_t j = 0; j < movable.size(); ++j)
  {
    const int i = movable[j];
    const std::size_t begin = ring.size();
    for (int e = offsets[i]; e < offsets[i + 1]; ++e)
    {
      for (int a = 0; a < 4; ++a)
      {
        const int w = Tets_[4 * incident[e] + a];
        if (w != i)
        {
          ring.push_back(w);
        }
      }
    }
    std::sort(ring.begin() + begin, ring.end());
    ring.erase(std::unique(ring.begin() + begin, ring.end()), ring.end());
    ringOffsets[j + 1] = static_cast<int>(ring.size());
  }

  std::vector<char> everMoved(movable.size(), 0);
  auto P = [this](int k) { return &Points_[3 * static_cast<std::size_t>(k)]; };
  for (int sweep = 0; sweep < Iterations_; ++sweep)
  {
    int movedThisSweep = 0;
    Blocked_ = 0;
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
        trial[c] = old[c] + Rho_ * (mean[c] / count - old[c]);
      }
      if (trial[0] == old[0] && trial[1] == old[1] && trial[2] == old[2])
      {
        continue; // at the mean already: nothing to do, not blocked
      }
      // Never cross the cutting surface.
      bool accept = F(trial) >= 0.0;
      for (int e = offsets[i]; accept && e < offsets[i + 1]; ++e)
      {
        const int* v = &Tets_[4 * incident[e]];
        const double before =
          MinimumDihedralAngle(P(v[0]), P(v[1]), P(v[2]), P(v[3]));
        std::copy_n(trial, 3, x);
        const double volume = SignedVolume(P(v[0]), P(v[1]), P(v[2]), P(v[3]));
        const double after =
          volume > 0.0 ? MinimumDihedralAngle(P(v[0]), P(v[1]), P(v[2]), P(v[3])) : 0.0;
        std::copy_n(old, 3, x);
        accept = volume > 0.0 && (after >= MinDihedral_ || after >= before);
      }
      if (accept)
      {
        std::copy_n(trial, 3, x);
        everMoved[j] = 1;
        ++movedThisSweep;
      }
      else
      {
        ++Blocked_;
      }
    }
    ++Sweeps_;
    if (movedThisSweep == 0)
    {
      break;
    }
  }
  Moved_ = static_cast<int>(std::count(everMoved.begin(), everMoved.end(), 1));
}

} // namespace translucency
