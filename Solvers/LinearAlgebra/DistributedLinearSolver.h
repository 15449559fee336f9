/**
 * @file DistributedLinearSolver.h
 * @brief The distributed member of the linear-solver family: one SPD matrix
 * distributed by rows over the ranks of a communicator, set up once per
 * pattern and solved for many right-hand sides. The registry
 * (LinearSolver.h) composes it as it composes the in-process solvers
 * (Krylov method x preconditioner, model: PETSc's KSP x PC): an entry whose
 * traits have CreateDistributed has a distributed variant, created by
 * CreateDistributedLinearSolver("cg/boomeramg" or its alias "hypre-amg";
 * "cg/aggregation" or "multigrid-agg": CG with additive Schwarz, one
 * aggregation cycle on each rank's owned block, SchwarzAggregation.h).
 * The distributed diffusion solver (Solvers/Parallel) takes its linear
 * solver from there, so no diffusion solver calls hypre itself.
 */
#pragma once

#include "Communicator.h"
#include "OpticalProperties.h" // NumberOfChannels
#include "SolverOptions.h"

#include <array>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace translucency
{

/**
 * The stopping rules of DistributedLinearSolver::SolveChannels (the serial
 * blocked PCG's, BlockedKernels.h: StartChannels, UpdateChannels,
 * ChangeRule).
 */
struct DistributedSolveControl
{
  /// A channel converged when ||b - A x||_2 <= RelTol ||b||_2 (global norms).
  double RelTol = 1e-6;
  int MaxIter = 2000;
  /// Per channel: at least this many iterations unless the residual is
  /// exactly zero (LinearSolver::SetMinIter: 1 after a paint stroke, so that
  /// a warm start within RelTol still sees the new matrix).
  std::array<int, NumberOfChannels> MinIter{};
  /**
   * The change rule (LinearSolver::SetChangeRule) when > 0 and ChangeRows is
   * not null: after iteration k >= max(3, MinIter), with Delta_k = ||x_k -
   * x_{k-1}|| / ||x_k|| over the rows ChangeRows of every rank (global sums)
   * and rho the larger of the last two ratios Delta_k / Delta_{k-1}, a
   * channel also stops (converged, StoppedByChange) when Delta_k rho / (1 -
   * rho) <= ChangeTol. 0: RelTol alone.
   */
  double ChangeTol = 0.0;
  /// This rank's observed rows (0 .. rowEnd - rowBegin - 1; may be empty on
  /// some ranks): the distributed solver's owned boundary rows.
  const std::vector<int>* ChangeRows = nullptr;
  /**
   * The three channels' iterations interleaved, their inner products in one
   * MPI_Allreduce per reduction point (3 per iteration for the three), or
   * (false, the default) one channel's PCG after the other's (3 per
   * iteration and channel). The same iterates either way. Measured at 1M
   * tets on 2 ranks of this project's 2-core machine (Documentation/
   * Scaling.md, "Session 31"): interleaved ~25 % slower per iteration to
   * RelTol 1e-8 (more time in Open MPI's progress engine), equal at the
   * interactive RelTol.
   */
  bool FuseChannels = false;
};

/// How one channel of DistributedLinearSolver::SolveChannels ended (the
/// same on every rank).
struct DistributedChannelStats
{
  int Iterations = 0;
  double RelativeResidual = 0.0; ///< ||b - A x|| / ||b|| (PCG's recursive residual)
  bool Converged = false;
  /// Stopped by the change rule (DistributedSolveControl::ChangeTol), not by
  /// RelTol; Converged is then true too.
  bool StoppedByChange = false;
};

class DistributedLinearSolver
{
public:
  virtual ~DistributedLinearSolver() = default;

  /// The registry's composition, e.g. "cg/boomeramg".
  virtual std::string GetName() const = 0;

  /**
   * Solver-specific settings by name (before Setup; a later change applies
   * at the next Setup). Each solver reads those it knows, checks them
   * (translucency::Error naming the option and the value) and leaves the
   * others unused (SolverOptions::GetUnused). Default: reads none.
   */
  virtual void SetOptions(const SolverOptions& options) { (void)options; }

  /**
   * The positions of this rank's rows (3 per row, the rows of the next
   * Setup, in order), for a preconditioner that aggregates by distance
   * ("cg/aggregation": each vertex joins its nearest retained neighbour).
   * Before Setup or SetupShared; kept until the next call. Default: unused.
   * Without positions such a preconditioner still works, aggregating by
   * neighbour order instead (more iterations).
   */
  virtual void SetCoordinates(const double* xyz, int rows) { (void)xyz, (void)rows; }

  /**
   * Collective: this rank's rows [rowBegin, rowEnd) as CSR (rowOffsets has
   * rowEnd - rowBegin + 1 entries from 0; global column indices, sorted in
   * each row), every row whole (the partial rows of other ranks already
   * summed). Builds the matrix and the preconditioner from scratch.
   */
  virtual void Setup(int rowBegin, int rowEnd, const int* rowOffsets, const int* columns,
    const double* values) = 0;

  /**
   * Collective: the same rows and columns as the last Setup with new values;
   * the preconditioner is kept (built for the old values: good while the
   * change is small, a paint stroke). Throws translucency::Error if there is
   * no Setup or the pattern differs.
   */
  virtual void UpdateValues(const int* rowOffsets, const int* columns, const double* values) = 0;

  /**
   * Collective: UpdateValues where only this rank's rows `rows` (numRows
   * row numbers local to this rank, 0 .. rowEnd - rowBegin - 1, any order;
   * none is allowed) changed since the last Setup, UpdateValues or
   * UpdateRows; `values` holds every row's current values (the unchanged
   * rows' too) on the pattern of the last Setup. A solver that can write
   * only those rows does (HypreBoomerAMGPCG and SchwarzAggregationPCG:
   * hypre::ScatterRows); the default calls UpdateValues with every row. The preconditioner is kept,
   * as with UpdateValues. Issue 32: a paint stroke changes ~1 % of the rows.
   */
  virtual void UpdateRows(const int* rowOffsets, const int* columns, const double* values,
    const int* rows, int numRows)
  {
    (void)rows, (void)numRows;
    UpdateValues(rowOffsets, columns, values);
  }

  /**
   * After Setup or SetupShared (the same rows and columns): prepares what
   * UpdateValues and UpdateRows need (the hypre solvers: each entry's place
   * in the ParCSR blocks, hypre::FindPlaces), so that the first update
   * after a set-up (a paint) costs what the next ones do; a caller that
   * will update values calls it, one that sets up again at every change
   * need not. Default: nothing.
   */
  virtual void PrepareUpdates(const int* rowOffsets, const int* columns)
  {
    (void)rowOffsets, (void)columns;
  }

  /**
   * Collective: as Setup (the same rows, the matrix built from scratch), but
   * with the structure of `donor`'s preconditioner instead of one of its own
   * (issue 32: one BoomerAMG coarsening for the three colour channels, whose
   * matrices differ only by mu_a and sigma_s'; each sharer keeps its own
   * values on it: cg/boomeramg its Galerkin levels, cg/aggregation its
   * aggregates' values). Solve still iterates on this matrix to relTol, so
   * only the convergence rate depends on how close the two matrices are. `donor` must be set up on the same rows and stay so
   * while this solver is used: a new Setup of the donor needs a new
   * SetupShared here. Returns false, with nothing built, when this solver
   * cannot share with `donor` (the default: then call Setup).
   */
  virtual bool SetupShared(int rowBegin, int rowEnd, const int* rowOffsets, const int* columns,
    const double* values, const DistributedLinearSolver& donor)
  {
    (void)rowBegin, (void)rowEnd, (void)rowOffsets, (void)columns, (void)values, (void)donor;
    return false;
  }

  /**
   * Collective: solves for the local part b (rowEnd - rowBegin values) into
   * x, from x if `guess` (else from zero), until ||b - A x|| <= relTol ||b||
   * (global 2-norms) or maxIter iterations. Returns the iterations;
   * relativeResidual gets ||b - A x|| / ||b|| (the same on every rank). Not
   * converging is not an error (the caller reads the residual).
   */
  virtual int Solve(const double* b, double* x, bool guess, double relTol, int maxIter,
    double& relativeResidual) = 0;

  /**
   * Collective: the three channels' solves at once. solvers[c] (null: channel
   * c is not solved, its stats untouched) are set up on the same rows and
   * communicator (e.g. one per channel, this one among them); b[c] and x[c]
   * hold rowEnd - rowBegin values, x[c] the initial guess if guess[c] (else
   * it is zeroed). The rules of `control`; b = 0 gives x = 0, converged.
   * Not converging (maxIter, a breakdown) is not an error: stats[c] says so.
   *
   * The default solves the channels one after the other with Solve (hypre's
   * PCG for the hypre solvers: the preconditioner applied before each
   * convergence test, MinIter and the change rule not honoured).
   * HypreBoomerAMGPCG and SchwarzAggregationPCG override it with the
   * three-channel PCG of DistributedPCG.h: convergence tested before the
   * preconditioner, MinIter and the change rule, and with FuseChannels the
   * inner products of the three channels in one MPI_Allreduce per
   * reduction point.
   */
  virtual void SolveChannels(const std::array<DistributedLinearSolver*, NumberOfChannels>& solvers,
    const std::array<const double*, NumberOfChannels>& b, const std::array<double*, NumberOfChannels>& x,
    const std::array<bool, NumberOfChannels>& guess, const DistributedSolveControl& control,
    std::array<DistributedChannelStats, NumberOfChannels>& stats)
  {
    SolveChannelsOneByOne(solvers, b, x, guess, control, stats);
  }

  /**
   * The default SolveChannels, callable on any solver (the test hook that
   * keeps the per-channel path reachable: DistributedVertexSolver::
   * SetThreeChannelPCG(false)): per channel, ||b|| summed over the ranks
   * (b = 0: x = 0, converged), then Solve.
   */
  void SolveChannelsOneByOne(const std::array<DistributedLinearSolver*, NumberOfChannels>& solvers,
    const std::array<const double*, NumberOfChannels>& b, const std::array<double*, NumberOfChannels>& x,
    const std::array<bool, NumberOfChannels>& guess, const DistributedSolveControl& control,
    std::array<DistributedChannelStats, NumberOfChannels>& stats)
  {
    int rowBegin = 0, rowEnd = 0;
    GetRows(rowBegin, rowEnd);
    const int rows = rowEnd - rowBegin;
    std::array<double, NumberOfChannels> norms{};
    for (int c = 0; c < NumberOfChannels; ++c)
      for (int r = 0; solvers[c] && r < rows; ++r)
        norms[c] += b[c][r] * b[c][r];
    SumOverRanks(norms.data(), NumberOfChannels);
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      if (!solvers[c])
        continue;
      stats[c] = DistributedChannelStats();
      if (norms[c] == 0.0)
      {
        for (int r = 0; r < rows; ++r)
          x[c][r] = 0.0;
        stats[c].Converged = true;
        continue;
      }
      if (!guess[c])
        for (int r = 0; r < rows; ++r)
          x[c][r] = 0.0;
      double residual = 0.0;
      stats[c].Iterations =
        solvers[c]->Solve(b[c], x[c], guess[c], control.RelTol, control.MaxIter, residual);
      stats[c].RelativeResidual = residual;
      stats[c].Converged = residual <= control.RelTol;
    }
  }

  /// This rank's rows [rowBegin, rowEnd) of the last Setup (0, 0 before).
  virtual void GetRows(int& rowBegin, int& rowEnd) const { rowBegin = rowEnd = 0; }
  /// Collective: values[0 .. count) summed over the solver's ranks, in
  /// place (one MPI_Allreduce). Default: one rank, nothing to do.
  virtual void SumOverRanks(double* values, int count) const { (void)values, (void)count; }

  /// Levels and operator complexity of the preconditioner (1 and 1 without
  /// a hierarchy); non-zeros of the matrix summed over the ranks.
  virtual int GetNumberOfLevels() const { return 1; }
  virtual double GetOperatorComplexity() const { return 1.0; }
  virtual long long GetNumberOfNonZeros() const = 0;
  /// Wall times of the last Setup or UpdateValues on this rank (ms): the
  /// matrix, then the preconditioner (0 for UpdateValues).
  virtual double GetMatrixMilliseconds() const = 0;
  virtual double GetHierarchyMilliseconds() const = 0;
  /// Bytes of the preconditioner on this rank (the matrix not included).
  virtual std::size_t GetMemoryBytes() const { return 0; }
};

/**
 * A new distributed linear solver on `comm` by registry name or
 * composition ("cg/boomeramg", or its alias "hypre-amg"; "cg/aggregation", or
 * its alias "multigrid-agg"; case-insensitive).
 * Throws translucency::Error for an unknown name, a solver this build lacks
 * (its remedy) or one without a distributed variant, naming those with one.
 */
std::unique_ptr<DistributedLinearSolver> CreateDistributedLinearSolver(
  const std::string& name, const Communicator& comm);

} // namespace translucency
