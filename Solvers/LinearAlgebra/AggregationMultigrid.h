/**
 * @file AggregationMultigrid.h
 * @brief "multigrid-agg": conjugate gradient preconditioned by an
 * aggregation V-cycle whose coarse vertices are chosen exactly as in the
 * TransCut hierarchy (TransCut, Sec. 4.1.1: parallel independent sets
 * from hashed random codes with the vertex index in the low bits), built to
 * be cheap to set up (see Documentation/Multiresolution.md):
 *
 * - every dropped vertex joins the aggregate of ONE retained neighbour, the
 *   one with the largest eq. 16 weight lambda_ij = 1 / |x_i - x_j| (the
 *   nearest), so the prolongation P is piecewise constant (one 1 per row);
 * - the coarse operator P^T A P is then a plain sum of fine entries into
 *   (aggregate, aggregate) slots: one O(nnz) pass through a precomputed
 *   fine-entry -> coarse-slot map, parallel over coarse rows (deterministic);
 *   its pattern (the aggregate graph) is built with per-thread marker arrays;
 * - smoothing: Chebyshev polynomial in D_l1^-1 A (D_l1 = row sums of |a_ij|),
 *   whose spectrum lies in (0, 1] by Gershgorin, so no eigenvalue estimate is
 *   needed; single-precision values in the smoother and the residuals;
 * - the coarse correction is scaled by a factor (over-correction, the usual
 *   remedy for the weak energy of piecewise-constant prolongation), and the
 *   levels below level 0 are visited twice per cycle (W-cycle);
 * - a sparse LDL^T (Eigen, symbolic analysis kept between values-only
 *   set-ups) on the coarsest level.
 *
 * Unlike "multigrid-cg" it does not build the paper's coarse graph E^{l+1}
 * (2-ring), the graph enhancement of Sec. 4.1.3 or the full eq. 16
 * interpolation: the coarse graphs are the aggregate graphs (the pattern of
 * P^T A P). The three channels are solved together (one pass over the shared
 * pattern per product). Results do not depend on the number of threads.
 */
#pragma once

#include "LinearSolver.h"
#include "MultiresHierarchy.h"

#include <Eigen/SparseCore>

#include <memory>

namespace translucency
{

class AggregationMultigridSolver : public LinearSolver
{
public:
  AggregationMultigridSolver();
  ~AggregationMultigridSolver() override;

  std::string GetName() const override { return "multigrid-agg"; }
  bool Solve(const DiffusionSystem& system, std::array<Eigen::VectorXd, NumberOfChannels>& x,
    bool warmStart, std::array<LinearSolveStats, NumberOfChannels>& stats) override;
  std::size_t GetMemoryBytes() const override;

  ///@{
  /// Levels including level 0 (0 = automatic, default: coarsen until a level
  /// has at most GetCoarsestSize() vertices or coarsening stalls, i.e. a level
  /// keeps more than 90 % of its vertices; at most 25 levels). Take effect at
  /// the next Setup with patternChanged.
  void SetMaxLevels(int n) { MaxLevels_ = n; }
  int GetMaxLevels() const { return MaxLevels_; }
  void SetCoarsestSize(int n) { CoarsestSize_ = n; }
  int GetCoarsestSize() const { return CoarsestSize_; }
  ///@}
  /// Chebyshev degree of each pre-/post-smoothing (default 1).
  void SetSmootherDegree(int degree) { Degree_ = degree; }
  int GetSmootherDegree() const { return Degree_; }
  /// Lower end of the Chebyshev interval on the spectrum (0, 1] of
  /// D_l1^-1 A (default 0.2; with degree 1 the smoother is l1-Jacobi with
  /// weight 1 / (0.5 (1 + fraction)) = 1.67). 0.2 with the scale 1.4 below
  /// (before: 0.3 and 1.5) gives a smaller error after 3 and 4 iterations
  /// from zero on the 1M-tet bunny for marble, skin, ketchup and two light
  /// directions (Notes/Performance.md, "3-channel assembly input checks
  /// and the multigrid-agg defaults"), and no more iterations to 1e-3 or 1e-6.
  void SetSmootherFraction(double f) { Fraction_ = f; }
  /// Factor of the coarse correction x += s P x_c, in (0, 2) (default 1.4).
  void SetCoarseCorrectionScale(double s) { CorrectionScale_ = s; }
  double GetCoarseCorrectionScale() const { return CorrectionScale_; }
  /// Cycles per visit of each level below level 0 other than the coarsest:
  /// 1 = V-cycle, 2 = W-cycle (default 2: the coarse levels cost ~17 % of
  /// level 0, and two cycles there make up for part of the weak
  /// piecewise-constant prolongation; see Multiresolution.md).
  void SetCycleIndex(int gamma) { CycleIndex_ = gamma; }
  int GetCycleIndex() const { return CycleIndex_; }
  /// CG's own products with the level-0 matrix (the initial residual and one
  /// product per iteration) use its single-precision copy (interleaved, 42 MB
  /// per product instead of 74 MB at 1M tets) when RelTol >= this tolerance
  /// (default 1e-5), and the double values for tighter tolerances. With the
  /// single copy A_f, CG solves A_f x = b: the relative residual it reports
  /// is that of A_f, and b - A x differs from it by (A - A_f) x, about 1e-7
  /// |A| |x| (see Multiresolution.md for the measured floor). 0: always
  /// single, infinity: always double.
  void SetSinglePrecisionProductTolerance(double tol) { SingleProductTol_ = tol; }
  double GetSinglePrecisionProductTolerance() const { return SingleProductTol_; }
  /// Whether the next Solve uses the single-precision product (RelTol and a
  /// hierarchy with more than one level; a one-level hierarchy has no copy).
  bool UsesSinglePrecisionProduct() const;
  /// OpenMP threads of the hierarchy build (0 = OpenMP's default).
  void SetNumberOfThreads(int n) override
  {
    LinearSolver::SetNumberOfThreads(n);
    Threads_ = n;
  }

  ///@{
  /// The hierarchy of the last Setup.
  int GetNumberOfLevels() const;
  int GetLevelSize(int l) const;
  /// Level l -> l + 1: the aggregate (coarse vertex id) of every vertex of
  /// level l (empty on the coarsest level).
  const std::vector<int>& GetAggregates(int l) const;
  /// Level-0 (mesh) vertex id of every vertex of level l.
  const std::vector<int>& GetMeshIds(int l) const;
  /// Pattern of level l (level 0: the system's).
  const CsrPattern& GetPattern(int l) const;
  /// Members of each aggregate of level l (offsets into GetMembers(l);
  /// ascending fine ids) and, per non-zero k of level l's pattern, its slot in
  /// level l + 1's pattern (the Galerkin sum); empty on the coarsest level.
  const std::vector<int>& GetMemberOffsets(int l) const;
  const std::vector<int>& GetMembers(int l) const;
  const std::vector<int>& GetCoarseSlots(int l) const;
  /// Non-zeros of all levels divided by those of level 0.
  double GetOperatorComplexity() const;
  /// The Galerkin operator P^T A P of level l >= 1, channel c (double values).
  Eigen::SparseMatrix<double, Eigen::RowMajor, int> GetCoarseMatrix(int l, int c) const;
  ///@}

  /**
   * Setup(system, mesh, true) with the hierarchy of `donor` in place of a
   * new build: for a system with the donor's pattern on the donor's mesh
   * (e.g. the other diagonal block of a block system, SP3's A22 beside
   * A11). The aggregation reads only the pattern and the points (TransCut
   * Sec. 4.1.1 on the graph, the nearest retained neighbour), so the
   * hierarchy it would build is the donor's: its levels' patterns,
   * aggregates and Galerkin slots are copied (HierarchyMilliseconds: the
   * copy; not a hierarchy build), then this system's values set up. The
   * hierarchy options are then the donor's (SetMaxLevels, SetCoarsestSize);
   * the cycle's options stay this solver's. Throws translucency::Error (and
   * leaves this solver not set up) when the donor has no successful Setup,
   * is this solver, or its level-0 pattern is not the system's.
   */
  void SetupSharedHierarchy(
    const AggregationMultigridSolver& donor, const DiffusionSystem& system, const TetMesh* mesh);
  /// Setups that copied a donor's hierarchy (SetupSharedHierarchy).
  int GetNumberOfSharedHierarchySetups() const { return SharedSetups_; }

  /**
   * The aggregation hierarchy (patterns of every level, no values) of
   * `system`'s pattern (NumberOfUnknowns, RowOffsets, ColumnIndices; the
   * values are not read) with vertex i at points[3 i .. 3 i + 2], without a
   * mesh and without making this solver ready to Solve: the structure the
   * distributed additive Schwarz preconditioner ("cg/aggregation" on an MPI
   * communicator, SchwarzAggregationPCG) builds on one rank's block. Throws
   * translucency::Error for a bad pattern or a non-finite point.
   */
  void BuildStructure(const DiffusionSystem& system, const std::vector<double>& points);

  /// Milliseconds of the last hierarchy build and of the last value set-up.
  double GetHierarchyMilliseconds() const { return HierarchyMs_; }
  double GetValuesMilliseconds() const { return ValuesMs_; }
  int GetNumberOfHierarchyBuilds() const { return Builds_; }
  /// Value set-ups of every level (Setup, and row updates past the limit).
  int GetNumberOfSetups() const { return Setups_; }
  /// Row updates (SetupChangedRows) that kept the coarse levels.
  int GetNumberOfRowSetups() const { return RowSetups_; }

  /// SetupChangedRows refreshes only the level-0 single-precision values and
  /// l1 diagonal of the changed rows and keeps the coarse levels (their
  /// Galerkin values then belong to the matrix of the last full set-up: the
  /// V-cycle stays symmetric positive definite, only its quality changes),
  /// until the distinct rows changed since the last full set-up exceed this
  /// fraction of the unknowns; that update recomputes every level. Default
  /// 0.1; 0: every row update is a full values set-up.
  void SetCoarseRefreshFraction(double f) { CoarseRefreshFraction_ = f; }
  double GetCoarseRefreshFraction() const { return CoarseRefreshFraction_; }
  /// Distinct rows changed since the last full values set-up.
  int GetNumberOfStaleRows() const;

  /// Warm solves with single-precision products (RelTol >= the single
  /// product tolerance) start from the A-norm-best combination of the given
  /// x and the last k solutions of the same matrices (SolutionRecycler: a
  /// light being dragged); forgotten at every Setup. Default 0 (off), at
  /// most SolutionRecycler::MaxCapacity.
  void SetRecycledSolutions(int k);
  int GetRecycledSolutions() const;
  /// Forget the kept solutions (e.g. before timing a solve).
  void ClearRecycledSolutions();
  /// Keep the recycled solutions in double precision (default false:
  /// single). Then they are used at every tolerance, also with the
  /// double-precision products: the projection is exact up to round-off
  /// (the time stepper's sequence of solves, TimeResolved.h). Forgets the
  /// kept solutions.
  void SetRecycleInDoublePrecision(bool on);
  bool GetRecycleInDoublePrecision() const;

  /// One V-cycle z = B r on the three channels (interleaved, 3 values per
  /// vertex) — the preconditioner, exposed for tests. The cycle works on
  /// single-precision vectors (r and z are double).
  void ApplyPreconditioner(const Eigen::VectorXd& r, Eigen::VectorXd& z) const;
  /// The LinearSolver hook: true once set up (the cycle is a fixed symmetric
  /// positive definite operator, so CG and COCG stay valid with it).
  bool HasPreconditioner() const override { return Ready_; }
  /// z = B r, one cycle on 3 n interleaved values (LinearSolver's hook).
  void ApplyPreconditioner(const double* r, double* z) const override;

protected:
  /// The system must live on `mesh` (the aggregation reads its positions).
  void CheckSetup(const DiffusionSystem& system, const TetMesh* mesh) const override;
  /// Builds the aggregation hierarchy (patterns of every level).
  void SetupStructure(const DiffusionSystem& system, const TetMesh* mesh) override;
  /// Recomputes the Galerkin values and the smoothers.
  void SetupValues(const DiffusionSystem& system, const TetMesh* mesh) override;
  /// Refreshes the level-0 smoother of `rows` (SetCoarseRefreshFraction).
  void SetupRows(
    const DiffusionSystem& system, const TetMesh* mesh, const std::vector<int>& rows) override;

private:
  /// z = B r (3n values each); returns r.z per channel (deterministic sums).
  std::array<double, NumberOfChannels> Precondition(const double* r, double* z) const;
  void BuildHierarchy(const DiffusionSystem& system, const std::vector<double>& points);
  void ComputeValues(const DiffusionSystem& system);
  void CheckSystem(const DiffusionSystem& system) const;

  struct Internals;
  std::unique_ptr<Internals> Internal_;
  int MaxLevels_ = 0;
  int CoarsestSize_ = 300;
  int Degree_ = 1;
  double Fraction_ = 0.2;
  double CorrectionScale_ = 1.4;
  double SingleProductTol_ = 1e-5;
  int CycleIndex_ = 2;
  int Threads_ = 0;
  double HierarchyMs_ = 0.0, ValuesMs_ = 0.0;
  double CoarseRefreshFraction_ = 0.1;
  int Builds_ = 0, Setups_ = 0, RowSetups_ = 0, SharedSetups_ = 0;
};

} // namespace translucency
