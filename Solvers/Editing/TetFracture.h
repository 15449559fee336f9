/**
 * @file TetFracture.h
 * @brief Split a tet mesh into pieces: the Voronoi cells of seed points
 * (Documentation/Pipeline.md, "Interactions": Fracture).
 *
 * Each tet goes to the seed nearest its centroid (Euclidean distance, mm; a
 * tie goes to the seed with the smaller index). Every non-empty Voronoi cell
 * becomes one piece with its own compact points: the input points its tets
 * use, in increasing input id, and its tets renumbered to them (vertex order
 * kept, so orientation is kept). Pieces are numbered in seed order, empty
 * cells skipped. A piece is a set of whole tets of the input, so its
 * boundary surface is closed (every boundary edge is shared by an even
 * number of boundary triangles); it may have several connected components.
 *
 * Serial and deterministic. Throws translucency::Error on inconsistent input.
 */
#pragma once

#include <cstdint>
#include <vector>

namespace translucency
{

class TetFracture
{
public:
  /// Seed points (3 coordinates each, mm). At least one is needed by Split().
  void SetSeeds(const std::vector<double>& seeds) { Seeds_ = seeds; }
  const std::vector<double>& GetSeeds() const { return Seeds_; }

  /**
   * `count` seeds chosen among the tet centroids of (`points`, `tets`),
   * without repetition, reproducibly from `seed` (a fixed 64-bit generator,
   * the same on every platform). `count` is clamped to the number of tets.
   */
  static std::vector<double> RandomSeeds(const std::vector<double>& points,
    const std::vector<int>& tets, int count, std::uint64_t seed);

  /// Assign every tet of `tets` (4 ids each into `points`, 3 per point) to
  /// its nearest seed and build the pieces.
  void Split(const std::vector<double>& points, const std::vector<int>& tets);

  /// Seed index of every input tet (valid after Split()).
  const std::vector<int>& GetTetSeeds() const { return TetSeed_; }
  /// Number of non-empty pieces.
  int GetNumberOfPieces() const { return static_cast<int>(PieceSeed_.size()); }
  /// Seed index of piece k.
  int GetPieceSeed(int k) const { return PieceSeed_[k]; }
  /// Input ids of the tets of piece k, increasing.
  const std::vector<int>& GetPieceTets(int k) const { return PieceTets_[k]; }
  /// Input ids of the points of piece k, increasing (piece point j is input point [j]).
  const std::vector<int>& GetPiecePoints(int k) const { return PiecePoints_[k]; }
  /// Tets of piece k with piece-local point ids (4 per tet, input vertex order).
  const std::vector<int>& GetPieceConnectivity(int k) const { return PieceConnectivity_[k]; }

private:
  std::vector<double> Seeds_;
  std::vector<int> TetSeed_;
  std::vector<int> PieceSeed_;
  std::vector<std::vector<int>> PieceTets_;
  std::vector<std::vector<int>> PiecePoints_;
  std::vector<std::vector<int>> PieceConnectivity_;
};

} // namespace translucency
