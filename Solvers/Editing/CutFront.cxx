#include "CutFront.h"

#include "Error.h"

#include <algorithm>
#include <numeric>
#include <string>

namespace translucency
{

//------------------------------------------------------------------------------
void CutFront::ExtractFront(const std::vector<int>& tets, const std::vector<double>& side,
  const std::vector<int>& keptTets, const std::vector<char>& owned, std::vector<int>& points,
  std::vector<int>& frontTets)
{
  points.clear();
  frontTets.clear();
  const std::size_t numTets = tets.size() / 4;
  if (!owned.empty() && owned.size() != numTets)
  {
    throw Error("CutFront: " + std::to_string(owned.size()) + " owned flags for " +
      std::to_string(numTets) + " tets");
  }
  std::vector<int> selected;
  for (int t : keptTets)
  {
    if (t < 0 || static_cast<std::size_t>(t) >= numTets)
    {
      throw Error("CutFront: kept tet " + std::to_string(t) + " out of range [0, " +
        std::to_string(numTets) + ")");
    }
    if (!owned.empty() && !owned[t])
    {
      continue;
    }
    const int* v = &tets[4 * static_cast<std::size_t>(t)];
    bool front = false;
    for (int a = 0; a < 4; ++a)
    {
      if (v[a] < 0 || static_cast<std::size_t>(v[a]) >= side.size())
      {
        throw Error("CutFront: tet " + std::to_string(t) + " has point id " +
          std::to_string(v[a]) + " out of range [0, " + std::to_string(side.size()) + ")");
      }
      front = front || side[v[a]] > 0.0;
    }
    if (front)
    {
      selected.push_back(t);
    }
  }
  std::vector<int> index(side.size(), -1);
  for (int t : selected)
  {
    for (int a = 0; a < 4; ++a)
    {
      index[tets[4 * static_cast<std::size_t>(t) + a]] = 0;
    }
  }
  for (std::size_t i = 0; i < index.size(); ++i)
  {
    if (index[i] == 0)
    {
      index[i] = static_cast<int>(points.size());
      points.push_back(static_cast<int>(i));
    }
  }
  frontTets.reserve(4 * selected.size());
  for (int t : selected)
  {
    for (int a = 0; a < 4; ++a)
    {
      frontTets.push_back(index[tets[4 * static_cast<std::size_t>(t) + a]]);
    }
  }
}

//------------------------------------------------------------------------------
void CutFront::Add(const std::int64_t* ids, const double* coordinates, std::int64_t numPoints,
  const std::int64_t* tets, std::int64_t numTets)
{
  std::vector<std::int64_t> local(static_cast<std::size_t>(numPoints));
  for (std::int64_t i = 0; i < numPoints; ++i)
  {
    const double* x = coordinates + 3 * i;
    const std::int64_t next = GetNumberOfPoints();
    bool inserted = false;
    std::int64_t at = next;
    if (ById_)
    {
      const auto found = IdIndex_.emplace(ids[i], next);
      inserted = found.second;
      at = found.first->second;
    }
    else
    {
      // -0 and +0 are one coordinate (as the gather's point keys).
      const Coordinates key = { x[0] + 0.0, x[1] + 0.0, x[2] + 0.0 };
      const auto found = CoordinateIndex_.emplace(key, next);
      inserted = found.second;
      at = found.first->second;
    }
    if (inserted)
    {
      Coordinates_.insert(Coordinates_.end(), x, x + 3);
      if (ById_)
      {
        Ids_.push_back(ids[i]);
      }
    }
    local[static_cast<std::size_t>(i)] = at;
  }
  for (std::int64_t t = 0; t < numTets; ++t)
  {
    std::array<std::int64_t, 4> v;
    for (int a = 0; a < 4; ++a)
    {
      const std::int64_t k = tets[4 * t + a];
      if (k < 0 || k >= numPoints)
      {
        throw Error("CutFront: front tet " + std::to_string(t) + " has point index " +
          std::to_string(k) + " out of range [0, " + std::to_string(numPoints) + ")");
      }
      v[a] = local[static_cast<std::size_t>(k)];
    }
    std::array<std::int64_t, 4> sorted = v;
    std::sort(sorted.begin(), sorted.end());
    if (SeenTets_.insert(sorted).second)
    {
      Tets_.insert(Tets_.end(), v.begin(), v.end());
    }
  }
}

//------------------------------------------------------------------------------
std::int64_t CutFront::Find(std::int64_t id) const
{
  const auto found = IdIndex_.find(id);
  return found == IdIndex_.end() ? -1 : found->second;
}

std::int64_t CutFront::Find(const double* x) const
{
  const auto found = CoordinateIndex_.find({ x[0] + 0.0, x[1] + 0.0, x[2] + 0.0 });
  return found == CoordinateIndex_.end() ? -1 : found->second;
}

//------------------------------------------------------------------------------
void CutFront::Relax(TetCut& cut, const TetCut::SideFunction& F)
{
  const std::int64_t n = GetNumberOfPoints();
  if (n > static_cast<std::int64_t>(2147483647 / 3) || GetNumberOfTets() > 2147483647 / 4)
  {
    throw Error("CutFront: the front has " + std::to_string(n) + " points and " +
      std::to_string(GetNumberOfTets()) + " tets, more than one TetCut can hold");
  }
  // The global order: by id, or the order of first appearance.
  std::vector<std::int64_t> order(static_cast<std::size_t>(n));
  std::iota(order.begin(), order.end(), std::int64_t(0));
  if (ById_)
  {
    std::sort(order.begin(), order.end(),
      [this](std::int64_t a, std::int64_t b) { return Ids_[a] < Ids_[b]; });
  }
  std::vector<int> rank(static_cast<std::size_t>(n));
  std::vector<double> points(3 * static_cast<std::size_t>(n));
  std::vector<double> side(static_cast<std::size_t>(n));
  for (std::int64_t k = 0; k < n; ++k)
  {
    const std::int64_t p = order[static_cast<std::size_t>(k)];
    rank[static_cast<std::size_t>(p)] = static_cast<int>(k);
    std::copy_n(GetPosition(p), 3, &points[3 * static_cast<std::size_t>(k)]);
    side[static_cast<std::size_t>(k)] = F(&points[3 * static_cast<std::size_t>(k)]);
  }
  std::vector<int> tets(Tets_.size());
  for (std::size_t e = 0; e < Tets_.size(); ++e)
  {
    tets[e] = rank[static_cast<std::size_t>(Tets_[e])];
  }
  cut.Cut(points, tets, side, F);
  // Every front tet has a vertex with F <= 0 (it was kept): all are kept, and
  // so is every point; the kept points are listed in the global order.
  const std::vector<int>& kept = cut.GetKeptPoints();
  const std::vector<double>& moved = cut.GetPoints();
  for (std::size_t j = 0; j < kept.size(); ++j)
  {
    const std::int64_t p = order[static_cast<std::size_t>(kept[j])];
    std::copy_n(&moved[3 * j], 3, &Coordinates_[3 * static_cast<std::size_t>(p)]);
  }
}

} // namespace translucency
