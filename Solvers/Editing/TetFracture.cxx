#include "TetFracture.h"

#include "Error.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

namespace translucency
{

namespace
{
/// Check the sizes and ids of (points, tets); throw naming the first problem.
void CheckMesh(const std::vector<double>& points, const std::vector<int>& tets)
{
  if (points.size() % 3 != 0)
  {
    throw Error("points: " + std::to_string(points.size()) + " coordinates, not a multiple of 3");
  }
  if (tets.size() % 4 != 0)
  {
    throw Error("tets: " + std::to_string(tets.size()) + " ids, not a multiple of 4");
  }
  const int numPoints = static_cast<int>(points.size() / 3);
  for (std::size_t k = 0; k < tets.size(); ++k)
  {
    if (tets[k] < 0 || tets[k] >= numPoints)
    {
      throw Error("tet " + std::to_string(k / 4) + " uses point " + std::to_string(tets[k]) +
        ", out of range [0, " + std::to_string(numPoints) + ")");
    }
  }
}

void Centroid(const std::vector<double>& points, const int* tet, double* c)
{
  for (int d = 0; d < 3; ++d)
  {
    c[d] = 0.25 *
      (points[3 * tet[0] + d] + points[3 * tet[1] + d] + points[3 * tet[2] + d] +
        points[3 * tet[3] + d]);
  }
}

/// SplitMix64: a fixed generator, identical on every platform.
std::uint64_t Next(std::uint64_t& state)
{
  std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}
}

//------------------------------------------------------------------------------
std::vector<double> TetFracture::RandomSeeds(const std::vector<double>& points,
  const std::vector<int>& tets, int count, std::uint64_t seed)
{
  CheckMesh(points, tets);
  const int numTets = static_cast<int>(tets.size() / 4);
  count = std::max(0, std::min(count, numTets));
  // Partial Fisher-Yates shuffle of the tet ids.
  std::vector<int> order(numTets);
  std::iota(order.begin(), order.end(), 0);
  std::uint64_t state = seed;
  std::vector<double> seeds(3 * static_cast<std::size_t>(count));
  for (int k = 0; k < count; ++k)
  {
    const int j = k + static_cast<int>(Next(state) % static_cast<std::uint64_t>(numTets - k));
    std::swap(order[k], order[j]);
    Centroid(points, &tets[4 * static_cast<std::size_t>(order[k])], &seeds[3 * k]);
  }
  return seeds;
}

//------------------------------------------------------------------------------
void TetFracture::Split(const std::vector<double>& points, const std::vector<int>& tets)
{
  CheckMesh(points, tets);
  if (Seeds_.empty() || Seeds_.size() % 3 != 0)
  {
    throw Error("no seed points: at least one seed (3 coordinates) is needed, got " +
      std::to_string(Seeds_.size()) + " coordinates");
  }
  for (double s : Seeds_)
  {
    if (!std::isfinite(s))
    {
      throw Error("a seed point has a non-finite coordinate");
    }
  }
  const int numSeeds = static_cast<int>(Seeds_.size() / 3);
  const int numTets = static_cast<int>(tets.size() / 4);
  const int numPoints = static_cast<int>(points.size() / 3);

  // Nearest seed of every tet centroid.
  TetSeed_.assign(numTets, 0);
  std::vector<int> count(numSeeds, 0);
  for (int t = 0; t < numTets; ++t)
  {
    double c[3];
    Centroid(points, &tets[4 * static_cast<std::size_t>(t)], c);
    double best = std::numeric_limits<double>::infinity();
    int bestSeed = 0;
    for (int s = 0; s < numSeeds; ++s)
    {
      const double dx = c[0] - Seeds_[3 * s], dy = c[1] - Seeds_[3 * s + 1],
                   dz = c[2] - Seeds_[3 * s + 2];
      const double d2 = dx * dx + dy * dy + dz * dz;
      if (d2 < best)
      {
        best = d2;
        bestSeed = s;
      }
    }
    TetSeed_[t] = bestSeed;
    ++count[bestSeed];
  }

  // Pieces in seed order, empty cells skipped.
  std::vector<int> pieceOfSeed(numSeeds, -1);
  PieceSeed_.clear();
  for (int s = 0; s < numSeeds; ++s)
  {
    if (count[s] > 0)
    {
      pieceOfSeed[s] = static_cast<int>(PieceSeed_.size());
      PieceSeed_.push_back(s);
    }
  }
  const int numPieces = static_cast<int>(PieceSeed_.size());
  PieceTets_.assign(numPieces, {});
  PiecePoints_.assign(numPieces, {});
  PieceConnectivity_.assign(numPieces, {});
  for (int t = 0; t < numTets; ++t)
  {
    PieceTets_[pieceOfSeed[TetSeed_[t]]].push_back(t);
  }
  std::vector<int> local(numPoints, -1);
  std::vector<int> stamp(numPoints, -1);
  for (int k = 0; k < numPieces; ++k)
  {
    std::vector<int>& piecePoints = PiecePoints_[k];
    for (int t : PieceTets_[k])
    {
      for (int v = 0; v < 4; ++v)
      {
        const int i = tets[4 * static_cast<std::size_t>(t) + v];
        if (stamp[i] != k)
        {
          stamp[i] = k;
          piecePoints.push_back(i);
        }
      }
    }
    std::sort(piecePoints.begin(), piecePoints.end());
    for (std::size_t j = 0; j < piecePoints.size(); ++j)
    {
      local[piecePoints[j]] = static_cast<int>(j);
    }
    std::vector<int>& connectivity = PieceConnectivity_[k];
    connectivity.reserve(4 * PieceTets_[k].size());
    for (int t : PieceTets_[k])
    {
      for (int v = 0; v < 4; ++v)
      {
        connectivity.push_back(local[tets[4 * static_cast<std::size_t>(t) + v]]);
      }
    }
  }
}

} // namespace translucency
