/**
 * @file SchwarzAggregation.h
 * @brief The distributed variant of "multigrid-agg" (registry composition
 * "cg/aggregation"): conjugate gradient on the whole distributed matrix
 * (hypre's ParCSR PCG: the global product and the global 2-norm stopping
 * rule, as "cg/boomeramg"), preconditioned by additive Schwarz without
 * overlap, i.e. block Jacobi over the ranks: each rank applies one cycle of
 * the project's aggregation multigrid (AggregationMultigrid.h: the same
 * aggregation, l1-Jacobi/Chebyshev smoother, over-corrected coarse
 * correction, W-cycle below level 0 and LDL^T on the coarsest level) to its
 * owned diagonal block, the couplings to other ranks' columns dropped (in
 * the preconditioner only; the product keeps them). The preconditioner is a
 * fixed symmetric positive definite operator (block diagonal, each block an
 * SPD cycle), so CG stays valid.
 *
 * On one rank this is the serial multigrid-agg CG, one channel at a time.
 * On N ranks there is no coarse space across the ranks, so the iterations
 * grow with the number of ranks (Documentation/Scaling.md: measured at 2
 * and 3 ranks); for many ranks "cg/boomeramg" stays available by name.
 */
#pragma once

#include "DistributedLinearSolver.h"

#include <mpi.h>

#include <cstdint>
#include <memory>
#include <vector>

namespace translucency
{

class AggregationMultigridSolver;

class SchwarzAggregationPCG : public DistributedLinearSolver
{
public:
  explicit SchwarzAggregationPCG(MPI_Comm comm);
  ~SchwarzAggregationPCG() override;
  SchwarzAggregationPCG(const SchwarzAggregationPCG&) = delete;
  SchwarzAggregationPCG& operator=(const SchwarzAggregationPCG&) = delete;

  std::string GetName() const override { return "cg/aggregation"; }

  /**
   * "agg-coarse-scale" (factor of the coarse correction, in (0, 2), default
   * 1.4), "agg-cycle-index" (1 = V-cycle, 2 = W-cycle below level 0, the
   * default), "agg-coarsest-size" (coarsen until a level has at most this
   * many vertices, >= 1, default 300), "agg-threads" (OpenMP threads of the
   * block's cycle and set-up, 0 = OpenMP's default team, which the
   * distributed solver sets to the rank's share of the cores). Others are
   * left unused (SolverOptions::GetUnused). Applied at the next Setup.
   */
  void SetOptions(const SolverOptions& options) override;

  void SetCoordinates(const double* xyz, int rows) override;

  /// The hypre matrix of these rows, the block's aggregation hierarchy and
  /// its values (Galerkin operators, smoother, coarsest factorisation).
  void Setup(int rowBegin, int rowEnd, const int* rowOffsets, const int* columns,
    const double* values) override;

  /**
   * New values on the same pattern: written into the hypre matrix (each
   * entry's place found once per pattern), and the block's values set up
   * again on the kept aggregation (Galerkin operators, smoother and coarsest
   * factorisation of the new matrix: as the serial multigrid-agg's
   * values-only set-up, so the preconditioner is the new matrix's).
   * Throws translucency::Error before Setup or for a changed pattern.
   */
  void UpdateValues(const int* rowOffsets, const int* columns, const double* values) override;

  /**
   * UpdateValues where only `rows` changed: those rows written into the
   * hypre matrix (hypre::ScatterRows, the pattern not fingerprinted again),
   * the block's values set up again on the kept aggregation as UpdateValues
   * does (every level: no row update of the block hierarchy yet).
   */
  void UpdateRows(const int* rowOffsets, const int* columns, const double* values,
    const int* rows, int numRows) override;
  /// Each entry's place in the hypre matrix found now (hypre::FindPlaces).
  void PrepareUpdates(const int* rowOffsets, const int* columns) override;

  /**
   * As Setup, with `donor`'s aggregation (the hierarchy's structure: the
   * three channels share one pattern) and this matrix's own values: no
   * aggregation of its own, and the same preconditioner quality as Setup.
   * False if `donor` is not a set-up SchwarzAggregationPCG on the same rows
   * and block pattern.
   */
  bool SetupShared(int rowBegin, int rowEnd, const int* rowOffsets, const int* columns,
    const double* values, const DistributedLinearSolver& donor) override;

  /// PCG (hypre) to ||b - A x|| <= relTol ||b|| (global 2-norms); returns
  /// the iterations, relativeResidual the final relative residual.
  int Solve(const double* b, double* x, bool guess, double relTol, int maxIter,
    double& relativeResidual) override;

  /**
   * The three channels in one PCG (DistributedPCG.h) when every solvers[c]
   * given is a set-up SchwarzAggregationPCG (else the per-channel default):
   * hypre's product on each channel's matrix, its block cycle
   * (ApplyPreconditioner) as the preconditioner, the rules of `control`.
   */
  void SolveChannels(const std::array<DistributedLinearSolver*, NumberOfChannels>& solvers,
    const std::array<const double*, NumberOfChannels>& b, const std::array<double*, NumberOfChannels>& x,
    const std::array<bool, NumberOfChannels>& guess, const DistributedSolveControl& control,
    std::array<DistributedChannelStats, NumberOfChannels>& stats) override;
  void GetRows(int& rowBegin, int& rowEnd) const override
  {
    rowBegin = RowBegin_;
    rowEnd = RowEnd_;
  }
  void SumOverRanks(double* values, int count) const override;

  /// The levels of this rank's block hierarchy (at least 1 once set up).
  int GetNumberOfLevels() const override;
  /// sum_l nnz(A_l) / nnz(A_0) of this rank's block hierarchy.
  double GetOperatorComplexity() const override;
  long long GetNumberOfNonZeros() const override { return NonZeros_; }
  double GetMatrixMilliseconds() const override { return MatrixMilliseconds_; }
  double GetHierarchyMilliseconds() const override { return HierarchyMilliseconds_; }
  /// The block hierarchy (patterns, shared ones included once per sharer's
  /// values) and its values on this rank; the hypre matrix not included.
  std::size_t GetMemoryBytes() const override;

  /// z = B r on this rank's rows (the block cycle), for tests; r and z hold
  /// rowEnd - rowBegin values.
  void ApplyPreconditioner(const double* r, double* z) const;

  struct Block;   ///< the owned block's hierarchy values and cycle
  struct Handles; ///< hypre's objects

private:
  void Free();
  void BuildMatrix(int rowBegin, int rowEnd, const int* rowOffsets, const int* columns,
    const double* values);
  /// The owned block's CSR (local columns) and its entries' places in the
  /// rows given to Setup.
  void ExtractBlock(const int* rowOffsets, const int* columns);
  /// The block's values of `values` (the rows given to Setup), set up on
  /// the current structure.
  void SetBlockValues(const double* values);
  void BuildSolver();

  MPI_Comm Comm_;
  std::unique_ptr<Handles> H_;
  std::unique_ptr<Block> B_;
  /// The aggregation (structure only), shared with SetupShared's sharers.
  std::shared_ptr<const AggregationMultigridSolver> Structure_;
  bool OwnsStructure_ = false; ///< built here (not a donor's)
  std::vector<double> Coordinates_;
  int RowBegin_ = 0, RowEnd_ = 0;
  double CoarseScale_ = 1.4;
  int CycleIndex_ = 2;
  int CoarsestSize_ = 300;
  int Threads_ = 0;
  long long NonZeros_ = 0;
  double MatrixMilliseconds_ = 0.0;
  double HierarchyMilliseconds_ = 0.0;
  /// The block's pattern: offsets, local columns, and each block entry's
  /// index among the rows' entries (k of Setup's arrays).
  std::vector<int> BlockOffsets_, BlockColumns_, BlockEntries_;
  std::uint64_t BlockPattern_ = 0; ///< fingerprint of the block pattern
  /// UpdateValues: each entry's place in the ParCSR blocks (>= 0 diagonal
  /// block, -1 - k off-diagonal block), found once per pattern.
  std::vector<int> Places_;
  std::uint64_t PlacePattern_ = 0;
};

} // namespace translucency
