/**
 * @file HypreSolver.h
 * @brief The "hypre-amg" linear solver: hypre's BoomerAMG algebraic
 * multigrid as the preconditioner of hypre's PCG, a peer the bench compares
 * against. HypreBoomerAMGPCG is the single-matrix building block, usable on
 * any MPI communicator (the bench's 2-rank run, translucency-hypre-mpi, uses
 * it on MPI_COMM_WORLD); HypreSolver runs three of them in-process on
 * MPI_COMM_SELF.
 */
#pragma once

#include "DistributedLinearSolver.h"
#include "LinearSolver.h"

#include <mpi.h>

#include <cstdint>
#include <memory>
#include <vector>

namespace translucency
{

/// MPI_Init if nobody has initialised MPI yet (the in-process solver runs on
/// MPI_COMM_SELF; ParaView's VTK may already have initialised it), and
/// HYPRE_Init; both are finalised at exit if this call initialised them.
void EnsureHypreInitialized();

/// The MPI communicator of `comm` (MPI_COMM_SELF for none; initialises MPI
/// and hypre if nobody has).
MPI_Comm GetMPIComm(const Communicator& comm);
/// The Communicator of `*comm` (its rank and size; the MPI_Comm must outlive
/// every user of the result). Initialises MPI and hypre if nobody has.
Communicator MakeCommunicator(const MPI_Comm* comm);
/// Process-lifetime MPI_COMM_SELF and MPI_COMM_WORLD, for MakeCommunicator.
const MPI_Comm* GetSelfCommunicator();
const MPI_Comm* GetWorldCommunicator();

/**
 * BoomerAMG settings (hypre's codes). The defaults are the in-process
 * "hypre-amg" solver's; DistributedVertexSolver uses Tuned().
 */
struct BoomerAMGOptions
{
  int CoarsenType = 10;          ///< 10 = HMIS
  int InterpType = 6;            ///< 6 = extended+i
  int PMaxElmts = 4;             ///< interpolation truncation (entries per row)
  double StrongThreshold = 0.5;  ///< strength of connection
  int RelaxType = 8;             ///< 8 = l1-scaled hybrid symmetric Gauss-Seidel
  int NumSweeps = 1;             ///< sweeps down and up
  int RelaxDown = -1;            ///< the down cycle's relaxation (-1: RelaxType)
  int RelaxUp = -1;              ///< the up cycle's relaxation (-1: RelaxType)
  int AggNumLevels = 0;          ///< levels of aggressive coarsening
  int AggInterpType = 4;         ///< interpolation on those levels (4 = multipass)
  int KeepTranspose = 0;         ///< 1: keep P^T (restriction without a transposed product)

  /// The settings measured best on the bunny diffusion system
  /// (Documentation/Scaling.md): HMIS, strong threshold 0.25, one level of
  /// aggressive coarsening with multipass interpolation, extended+i
  /// elsewhere, Pmax 4, and one l1 hybrid Gauss-Seidel sweep forward on the
  /// way down (13) and backward on the way up (14): a symmetric V-cycle
  /// (hypre's own default pair) at half the sweeps of the l1 symmetric sweep
  /// (8) on both, convergent on any partition as the l1 smoothers are.
  static BoomerAMGOptions Tuned()
  {
    BoomerAMGOptions o;
    o.StrongThreshold = 0.25;
    o.AggNumLevels = 1;
    o.RelaxDown = 13;
    o.RelaxUp = 14;
    return o;
  }

  /// As options of HypreBoomerAMGPCG::SetOptions ("amg-coarsening",
  /// "amg-interpolation", "amg-pmax", "amg-strong-threshold",
  /// "amg-relaxation", "amg-sweeps", "amg-aggressive-levels",
  /// "amg-aggressive-interpolation", "amg-keep-transpose").
  SolverOptions ToOptions() const;
};

/**
 * One SPD matrix distributed by rows over `comm` (this rank holds rows
 * [rowBegin, rowEnd)) with BoomerAMG-preconditioned PCG. BoomerAMG settings
 * (hypre's recommendations for 3-D diffusion): HMIS coarsening, extended+i
 * interpolation with at most 4 entries per row, strength threshold 0.5,
 * one sweep of l1-scaled hybrid symmetric Gauss-Seidel down and up (a
 * symmetric cycle, as PCG needs), one V-cycle per preconditioner
 * application. PCG stops on the 2-norm: ||b - Ax|| <= tol ||b||.
 */
class HypreBoomerAMGPCG : public DistributedLinearSolver
{
public:
  explicit HypreBoomerAMGPCG(MPI_Comm comm, const BoomerAMGOptions& options = BoomerAMGOptions());
  ~HypreBoomerAMGPCG() override;

  std::string GetName() const override { return "cg/boomeramg"; }
  /// The BoomerAMG settings by name (BoomerAMGOptions::ToOptions), applied
  /// at the next Setup.
  void SetOptions(const SolverOptions& options) override;
  HypreBoomerAMGPCG(const HypreBoomerAMGPCG&) = delete;
  HypreBoomerAMGPCG& operator=(const HypreBoomerAMGPCG&) = delete;

  /**
   * The local rows: rowOffsets has rowEnd - rowBegin + 1 entries (from 0),
   * columns are global indices. Builds the hypre matrix and the AMG
   * hierarchy (from scratch: BoomerAMG has no values-only set-up).
   */
  void Setup(int rowBegin, int rowEnd, const int* rowOffsets, const int* columns,
    const double* values) override;

  /**
   * Values-only update (collective) after Setup: the same rows and columns,
   * new values written straight into the assembled ParCSR matrix (each
   * entry's place found once per pattern); the hierarchy is kept: its fine
   * level is this matrix, so
   * smoothing and residuals see the new values, and so do the fine
   * level's smoother norms (recomputed: GetFineSmootherNorms); the coarse
   * levels are the old matrix's (good while the change is small, a paint
   * stroke). Throws
   * translucency::Error if there is no Setup to update or an entry is not in
   * the matrix (a changed pattern).
   */
  void UpdateValues(const int* rowOffsets, const int* columns, const double* values) override;

  /**
   * UpdateValues of the changed rows only (collective; issue 32: a paint
   * stroke): their entries written to the places the first UpdateValues
   * after Setup found (hypre::ScatterRows; every row when none were found
   * yet), and those rows' smoother norms recomputed. The hierarchy is kept,
   * as with UpdateValues.
   */
  void UpdateRows(const int* rowOffsets, const int* columns, const double* values,
    const int* rows, int numRows) override;
  /// Each entry's place in the ParCSR blocks found now (hypre::FindPlaces).
  void PrepareUpdates(const int* rowOffsets, const int* columns) override;

  /**
   * The fine level's l1 norms of this channel's smoother on this rank's rows
   * (its own BoomerAMG's, or its own Galerkin levels' when it shares a
   * coarsening; empty for a smoother without them): what its V-cycle's l1
   * Gauss-Seidel sweeps divide a row's residual by. Set up from the matrix,
   * and recomputed from the new values by UpdateValues and (their rows)
   * UpdateRows, as BoomerAMG's set-up computes them (option 4 of
   * hypre_ParCSRComputeL1Norms). A diagnostic (tests).
   */
  std::vector<double> GetFineSmootherNorms() const;

  /**
   * The matrix of these rows on `donor`'s BoomerAMG coarsening (collective;
   * no coarsening or interpolation of its own): the donor's splitting and
   * interpolation P_l, and this matrix's own Galerkin levels
   * A_{l+1} = P_l^T A_l P_l, their l1 norms for the smoother and its own
   * coarsest matrix for the Gaussian elimination, swapped into the donor's
   * BoomerAMG for each V-cycle. So the cycle is BoomerAMG's on a hierarchy
   * of this matrix (an SPD preconditioner of it, whatever the donor's
   * values), at the price of the products P^T A P instead of a whole set-up.
   * False, with nothing built, if `donor` is not a set-up HypreBoomerAMGPCG
   * on the same rows or uses a relaxation whose set-up data this does not
   * rebuild (other than l1 Gauss-Seidel 8/13/14 in natural order, and
   * Gaussian elimination 9 on the coarsest level).
   */
  bool SetupShared(int rowBegin, int rowEnd, const int* rowOffsets, const int* columns,
    const double* values, const DistributedLinearSolver& donor) override;

  /**
   * Solve for the local part b (rowEnd - rowBegin values) into x; x is the
   * initial guess if `guess`, else zero. Returns the PCG iterations;
   * relativeResidual gets ||b - Ax|| / ||b||.
   */
  int Solve(const double* b, double* x, bool guess, double relTol, int maxIter,
    double& relativeResidual) override;

  /**
   * The three channels in one PCG (DistributedPCG.h) when every solvers[c]
   * given is a set-up HypreBoomerAMGPCG (else the per-channel default):
   * each channel's product hypre's (hypre_ParCSRMatrixMatvec on its matrix)
   * and its preconditioner one BoomerAMG V-cycle of its own or its shared
   * hierarchy (HYPRE_BoomerAMGSolve on its matrix: what hypre's PCG applies
   * in Solve), the channels' inner products in one MPI_Allreduce per
   * reduction point, convergence tested before the V-cycle, MinIter and the
   * change rule of `control`.
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

  /// Work of one PCG iteration in SpMVs with the fine matrix: 1 + the
  /// V-cycle's (3 sum_l nnz(A_l) + 2 sum_l nnz(P_l)) / nnz(A_0) (two
  /// smoothing sweeps and one residual per level, restriction and
  /// interpolation), summed over all ranks.
  double GetSpMVEquivalentsPerIteration() const { return IterationWork_; }
  /// sum_l nnz(A_l) / nnz(A_0) of the hierarchy.
  double GetOperatorComplexity() const override { return OperatorComplexity_; }
  int GetNumberOfLevels() const override { return Levels_; }
  /// Non-zeros of the fine matrix, summed over the ranks.
  long long GetNumberOfNonZeros() const override { return NonZeros_; }
  /// Wall times of the last Setup or UpdateValues on this rank (ms): the IJ matrix
  /// (values added, off-rank rows exchanged, assembled), then the vectors
  /// and the BoomerAMG hierarchy.
  double GetMatrixMilliseconds() const override { return MatrixMilliseconds_; }
  double GetHierarchyMilliseconds() const override { return HierarchyMilliseconds_; }
  std::size_t GetMemoryBytes() const override { return MemoryBytes_; }

private:
  void Free();
  /// The IJ matrix of these rows, assembled.
  void BuildMatrix(int rowBegin, int rowEnd, const int* rowOffsets, const int* columns,
    const double* values);
  /// Vectors, BoomerAMG (or `shared`'s, not owned) and PCG on the assembled
  /// matrix; work and memory.
  void BuildSolver(const HypreBoomerAMGPCG* shared = nullptr);

  MPI_Comm Comm_;
  BoomerAMGOptions Options_;
  struct Handles;
  std::unique_ptr<Handles> H_;
  int RowBegin_ = 0, RowEnd_ = 0;
  double IterationWork_ = 0.0;
  double OperatorComplexity_ = 0.0;
  int Levels_ = 0;
  long long NonZeros_ = 0;
  double MatrixMilliseconds_ = 0.0;
  double HierarchyMilliseconds_ = 0.0;
  std::size_t MemoryBytes_ = 0;
  /// UpdateValues: each entry's place in the ParCSR blocks (>= 0 diagonal
  /// block, -1 - k off-diagonal block), found once per Setup.
  std::vector<int> Places_;
  std::uint64_t PlacePattern_ = 0; ///< fingerprint of the pattern Places_ is of
};

/**
 * Three HypreBoomerAMGPCG (one per channel) on MPI_COMM_SELF. Setup()
 * rebuilds the hypre matrices and hierarchies whether or not the pattern
 * changed (BoomerAMG's set-up depends on the values). Debian's hypre is
 * built without OpenMP, so this runs on one core; see the bench's 2-rank
 * figure for MPI parallelism.
 */
class HypreSolver : public LinearSolver
{
public:
  HypreSolver();
  ~HypreSolver() override;

  std::string GetName() const override { return "hypre-amg"; }
  bool Solve(const DiffusionSystem& system, std::array<Eigen::VectorXd, NumberOfChannels>& x,
    bool warmStart, std::array<LinearSolveStats, NumberOfChannels>& stats) override;
  std::size_t GetMemoryBytes() const override;

protected:
  /// Everything (hypre matrices and BoomerAMG hierarchies): BoomerAMG's
  /// set-up depends on the values, so there is no structure-only part.
  void SetupValues(const DiffusionSystem& system, const TetMesh* mesh) override;

private:
  std::array<std::unique_ptr<HypreBoomerAMGPCG>, NumberOfChannels> Channels_;
};

} // namespace translucency
