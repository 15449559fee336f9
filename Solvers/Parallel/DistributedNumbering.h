/**
 * @file DistributedNumbering.h
 * @brief The global identity of a mesh distributed over MPI ranks: one
 * unknown per vertex shared by several pieces, an owner rank per vertex,
 * contiguous global rows per rank (hypre's layout), the physical boundary
 * (faces no tet of any rank shares), and the exchanges between a rank's
 * local points and the owners' rows.
 *
 * The Parallel layer is the core's only MPI-aware code (besides hypre in
 * LinearAlgebra); it has no VTK. Every function here is collective over the
 * communicator: every rank calls it, a rank with an empty piece too.
 *
 * Identity uses a rendezvous ("home") rank per key, hash(key) mod ranks, so
 * no rank ever holds more than its share of the keys: each rank sends its
 * keys to their homes, the homes match them and answer.
 */
#pragma once

#include "Communicator.h"

#include <mpi.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace translucency
{

/// The key of a global point id.
PointKey PointKeyFromId(std::int64_t id);
/// The key of exact coordinates (mm).
PointKey PointKeyFromCoordinates(const double* x);

/**
 * Every rank throws translucency::Error with the same message if any rank
 * has a non-empty `localError` (the lowest such rank's message, prefixed
 * "rank r: " when there are several ranks); returns otherwise. Collective.
 */
void AgreeOnError(MPI_Comm comm, const std::string& localError);

/**
 * The global numbering of the vertices of every rank's piece.
 *
 * Points with the same key on any ranks are one vertex. A vertex is
 * *used* if an owned tet of some rank has it; its owner is the lowest such
 * rank, and the owners number their vertices consecutively in rank order
 * (rows [RowBegin, RowEnd) on this rank). A vertex no rank uses has no row
 * (-1): no unknown (the serial solve gives such points fluence 0).
 */
class DistributedNumbering
{
public:
  /**
   * Collective. keys: one per local point; used: 1 if an owned tet of this
   * rank has the point.
   */
  void Build(MPI_Comm comm, const std::vector<PointKey>& keys, const std::vector<char>& used);

  int GetRowBegin() const { return RowBegin_; }
  int GetRowEnd() const { return RowEnd_; }
  int GetNumberOfOwnedRows() const { return RowEnd_ - RowBegin_; }
  long long GetNumberOfRows() const { return Rows_; }
  /// Global row of local point i (-1: no rank uses it).
  int GetRow(int i) const { return Row_[static_cast<std::size_t>(i)]; }
  const std::vector<int>& GetRows() const { return Row_; }
  /// Owner rank of local point i (-1 if no row).
  int GetOwner(int i) const { return Owner_[static_cast<std::size_t>(i)]; }
  bool IsOwned(int i) const { return Owner_[static_cast<std::size_t>(i)] == Rank_; }

  /**
   * Collective: for every owned row, the sum over every rank's local points
   * with that row of `values` (`components` per local point); rows of this
   * rank in order, `components` each. A row's own rank's points come
   * first, then the other ranks' in rank order (deterministic). Points
   * without a row are ignored; a row with several local points on one rank
   * (duplicate points) sums them all.
   */
  std::vector<double> SumToOwners(
    MPI_Comm comm, const std::vector<double>& values, int components) const;

  /**
   * Collective: the owners' values (`components` per owned row, rows in
   * order) at every local point (`components` each; 0 at points without a
   * row).
   */
  std::vector<double> FetchFromOwners(
    MPI_Comm comm, const std::vector<double>& owned, int components) const;

  /// Bytes held (per local point: row, owner).
  std::size_t GetMemoryBytes() const;

private:
  int Rank_ = 0;
  int Size_ = 1;
  int RowBegin_ = 0;
  int RowEnd_ = 0;
  long long Rows_ = 0;
  std::vector<int> Row_;
  std::vector<int> Owner_;
};

/**
 * Collective: for each local triangle (3 global rows each), how many
 * triangles with the same vertex set the ranks hold in total. A local
 * boundary face seen once is the object's boundary; twice, a face between
 * two ranks' pieces.
 */
std::vector<int> CountSharedTriangles(MPI_Comm comm, const std::vector<int>& triangleRows);

} // namespace translucency
