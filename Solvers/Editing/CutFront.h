/**
 * @file CutFront.h
 * @brief The cut front: what TetCut's relaxation reads, collected from the
 * pieces of a partitioned mesh so the relaxation can run as in serial.
 *
 * TetCut's relaxation moves the kept vertices on the removed side (F > 0,
 * "movable"); the mean of a movable vertex uses its one-ring, its guard the
 * tets around it. Every tet around a movable vertex is a kept tet with a
 * vertex on the removed side (a "front" tet), so the relaxation reads the
 * front tets and their vertices only, nothing else. CutFront gathers them:
 *  1. each piece extracts its front (ExtractFront: its owned kept tets with a
 *     vertex of F > 0, and their points, in the piece's point order);
 *  2. the fronts of all pieces are added in rank order (Add), a point shared
 *     by pieces is one point, matched by its global id or, without ids, by
 *     its exact coordinates; a tet brought by two pieces is taken once;
 *  3. Relax() runs TetCut on the front (points in the order of the ids, or
 *     without ids of first appearance). TetCut visits the vertices and sums
 *     their one-rings in the order of their coordinates, so the moves are the
 *     serial ones, bit for bit, with or without ids and for any partition
 *     (same sweep order, same summation order, same guard on the same tets);
 *  4. each piece looks its points up (Find) and takes the new positions.
 *
 * Serial and deterministic: every rank that adds the same fronts in the same
 * order gets the same positions. Throws translucency::Error on inconsistent input.
 */
#pragma once

#include "TetCut.h"

#include <array>
#include <cstdint>
#include <map>
#include <set>
#include <unordered_map>
#include <vector>

namespace translucency
{

class CutFront
{
public:
  /**
   * The front of one piece: of `tets` (4 point ids each), the kept ones
   * (`keptTets`, ids into `tets`; TetCut::GetKeptTets) that are owned
   * (`owned[t]` != 0; empty: all) and have a vertex with `side` > 0.
   * `points` gets their vertices (ids into the piece, ascending), `frontTets`
   * the tets (4 indices into `points` each, the tets' vertex order).
   */
  static void ExtractFront(const std::vector<int>& tets, const std::vector<double>& side,
    const std::vector<int>& keptTets, const std::vector<char>& owned, std::vector<int>& points,
    std::vector<int>& frontTets);

  /// Match points by global id (true) or by exact coordinates (false). Default true.
  explicit CutFront(bool byId = true)
    : ById_(byId)
  {
  }

  /**
   * Add one piece's front: `numPoints` points (`ids`: their global ids, ignored
   * without ids; `coordinates`: 3 each, mm) and `numTets` tets (4 indices into
   * these points each). Pieces are added in rank order.
   */
  void Add(const std::int64_t* ids, const double* coordinates, std::int64_t numPoints,
    const std::int64_t* tets, std::int64_t numTets);

  /**
   * Relax the front: `cut` (its factor, iterations, dihedral bound) runs on
   * the front tets in the global point order with side function F. The
   * statistics of `cut` are then those of the whole mesh's relaxation.
   */
  void Relax(TetCut& cut, const TetCut::SideFunction& F);

  /// Points of the front (after all Add calls).
  std::int64_t GetNumberOfPoints() const { return static_cast<std::int64_t>(Coordinates_.size() / 3); }
  /// Tets of the front (each once).
  std::int64_t GetNumberOfTets() const { return static_cast<std::int64_t>(Tets_.size() / 4); }
  /// Index of the front point with global id `id` (by-id mode), or -1.
  std::int64_t Find(std::int64_t id) const;
  /// Index of the front point at exactly `x` (coordinate mode), or -1.
  std::int64_t Find(const double* x) const;
  /// Coordinates of front point k (after Relax: the relaxed ones; mm).
  const double* GetPosition(std::int64_t k) const { return &Coordinates_[3 * static_cast<std::size_t>(k)]; }

private:
  using Coordinates = std::array<double, 3>;
  bool ById_ = true;
  std::unordered_map<std::int64_t, std::int64_t> IdIndex_;
  std::map<Coordinates, std::int64_t> CoordinateIndex_;
  std::vector<std::int64_t> Ids_;     ///< global id per front point (by-id mode)
  std::vector<double> Coordinates_;  ///< 3 per front point, in order of first appearance
  std::vector<std::int64_t> Tets_;    ///< 4 per front tet, indices into the points
  std::set<std::array<std::int64_t, 4>> SeenTets_; ///< sorted vertices of the tets taken
};

} // namespace translucency
