/**
 * @file TetCut.h
 * @brief Cut a tet mesh with a signed side function (TransCut, Sec. 5.1).
 *
 * The caller gives the mesh (points, mm, and positively oriented tets) and a
 * side function F: F(x) > 0 is the removed side, F(x) <= 0 is kept, F = 0 is
 * the cutting surface. Cut():
 *  1. deletes every tet whose four vertices have F > 0;
 *  2. drops the vertices no remaining tet uses, renumbering the rest;
 *  3. relaxes the remaining vertices with F > 0 toward the cross-section:
 *     x_i <- x_i + rho (x'_i - x_i), x'_i the uniform mean of the one-ring of
 *     x_i in the cut mesh (Sec. 5.1, with rho = 0.1 in the paper). A move is
 *     rejected (the vertex stays) if the new position has F < 0 (it would
 *     cross the cutting surface: a vertex stays on the removed side or on the
 *     surface), if a tet around the vertex would get a non-positive volume, or
 *     if it would get a minimum dihedral angle below the bound while lowering
 *     that tet's minimum dihedral angle (a tet that was already worse than the
 *     bound may only improve). Vertices are visited in the order of their
 *     coordinates (x, then y, then z) and each move is seen by the next one
 *     (Gauss-Seidel), the one-ring summed in that order too; the sweep is
 *     repeated for the given number of iterations or until no vertex moves.
 *     The moved positions therefore do not depend on the point numbering
 *     (a renumbered or partitioned mesh gets the same bits).
 *
 * Serial and deterministic. Throws translucency::Error on inconsistent input.
 */
#pragma once

#include <functional>
#include <vector>

namespace translucency
{

class TetCut
{
public:
  /// F(x) for x = 3 coordinates (mm); F > 0 is the removed side.
  using SideFunction = std::function<double(const double* x)>;

  /// Relaxation step rho (0..1). Default 0.1 (paper Sec. 5.1).
  void SetRelaxationFactor(double rho) { Rho_ = rho; }
  double GetRelaxationFactor() const { return Rho_; }
  /// Number of relaxation sweeps. Default 10; 0 disables the relaxation.
  void SetNumberOfIterations(int n) { Iterations_ = n; }
  int GetNumberOfIterations() const { return Iterations_; }
  /// Minimum dihedral angle (degrees) a move may produce. Default 0.5.
  void SetMinimumDihedralAngle(double degrees) { MinDihedral_ = degrees; }
  double GetMinimumDihedralAngle() const { return MinDihedral_; }

  /**
   * Cut `tets` (4 ids each, positive volume) of `points` (3 per point) with
   * F. `side` holds F at every input point (so the caller may evaluate it in
   * parallel); F itself is evaluated at trial positions during relaxation.
   */
  void Cut(const std::vector<double>& points, const std::vector<int>& tets,
    const std::vector<double>& side, const SideFunction& F);

  /// Input ids of the kept tets, in input order (output tet k is input tet KeptTets[k]).
  const std::vector<int>& GetKeptTets() const { return KeptTets_; }
  /// Input ids of the kept points, in input order.
  const std::vector<int>& GetKeptPoints() const { return KeptPoints_; }
  /// Coordinates of the kept points after relaxation (3 per kept point, mm).
  const std::vector<double>& GetPoints() const { return Points_; }
  /// Kept tets with renumbered point ids (4 per tet, input vertex order).
  const std::vector<int>& GetTets() const { return Tets_; }
  /// Kept vertices on the removed side (the ones the relaxation may move).
  int GetNumberOfMovableVertices() const { return Movable_; }
  /// Vertices moved at least once.
  int GetNumberOfMovedVertices() const { return Moved_; }
  /// Movable vertices whose move was rejected in the last sweep.
  int GetNumberOfBlockedVertices() const { return Blocked_; }
  /// Sweeps performed (<= the number of iterations: stops when nothing moves).
  int GetNumberOfSweeps() const { return Sweeps_; }

  /// Signed volume of the tet (a, b, c, d) (mm^3).
  static double SignedVolume(const double* a, const double* b, const double* c, const double* d);
  /// Smallest of the six dihedral angles of a tet (degrees).
  static double MinimumDihedralAngle(
    const double* a, const double* b, const double* c, const double* d);
  /// Cosine of the smallest dihedral angle of a tet (the largest of the six
  /// cosines; 1 for a degenerate tet).
  static double LargestDihedralCosine(const double* a, const double* b, const double* c, const double* d);

private:
  double Rho_ = 0.1;
  int Iterations_ = 10;
  double MinDihedral_ = 0.5;
  std::vector<int> KeptTets_;
  std::vector<int> KeptPoints_;
  std::vector<double> Points_;
  std::vector<int> Tets_;
  int Movable_ = 0;
  int Moved_ = 0;
  int Blocked_ = 0;
  int Sweeps_ = 0;
};

} // namespace translucency
