/**
 * @file TetLocator.h
 * @brief Point location in a tetrahedral mesh through a uniform grid of bins
 * (no VTK): which tet contains a point.
 */
#pragma once

#include <vector>

namespace translucency
{

class TetMesh;

/**
 * A uniform grid of bins over the bounding box of the tets; each bin lists,
 * in increasing id order, the tets whose bounding box overlaps it. About one
 * bin per tet (at most 2^24 bins), so a query tests a handful of tets.
 *
 * Locate() returns the lowest-numbered tet whose barycentric coordinates at
 * the point are all >= -Tolerance (default 1e-12): a point on a face shared
 * by two tets gets the lower id, whatever the thread, so results do not
 * depend on the number of threads. Points on the mesh surface (within the
 * tolerance) count as inside.
 *
 * Thread safety: Locate() keeps no state, so any number of threads may query
 * one locator at once. Build() must not run concurrently with queries. The
 * locator keeps a pointer to the mesh: the mesh must outlive it and not move
 * its points between Build() and the queries.
 */
class TetLocator
{
public:
  /// Build the bins for the tets of mesh (serial; O(tets)). An empty mesh
  /// gives a locator that finds nothing.
  void Build(const TetMesh& mesh);

  /// The containing tet of x (mm), or -1 if x is in no tet.
  int Locate(const double x[3]) const;

  /**
   * Barycentric coordinates of x in tet t (4 values summing to 1, in the
   * order of TetMesh::GetTet(t)); false for a degenerate tet.
   */
  bool Barycentric(int t, const double x[3], double lambda[4]) const;

  /// Slack on the barycentric coordinates (dimensionless, >= 0).
  void SetTolerance(double tolerance) { Tolerance_ = tolerance; }
  double GetTolerance() const { return Tolerance_; }

  /// Bins along x, y, z (0 before Build or for an empty mesh).
  const int* GetDimensions() const { return Dims_; }
  /// Bounding box of the tets: min x, y, z, max x, y, z (mm).
  const double* GetBounds() const { return Bounds_; }

private:
  const TetMesh* Mesh_ = nullptr;
  double Bounds_[6] = { 0, 0, 0, 0, 0, 0 };
  double BinSize_[3] = { 1, 1, 1 };
  int Dims_[3] = { 0, 0, 0 };
  std::vector<int> BinOffsets_; ///< CSR over bins
  std::vector<int> BinTets_;
  double Tolerance_ = 1e-12;
};

} // namespace translucency
