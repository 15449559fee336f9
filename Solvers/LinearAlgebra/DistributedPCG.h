/**
 * @file DistributedPCG.h
 * @brief The preconditioned conjugate gradient of the three colour
 * channels of a distributed solve (issue 32), what the distributed linear
 * solvers' SolveChannels run: each channel its own matrix and
 * preconditioner, given as operations on the channel's work vectors, and
 * the serial blocked PCG's stopping rules (BlockedKernels.h: StartChannels,
 * UpdateChannels, ChangeRule) with global sums:
 *
 * - three reduction points per iteration (p.Ap; r.r with the change rule's
 *   sums; r.z), each one MPI_Allreduce: of the three channels together with
 *   DistributedSolveControl::FuseChannels (the channels' iterations
 *   interleaved), else of one channel (one channel's PCG after the
 *   other's, the default: faster on this project's machine);
 * - convergence, ||b - A x||_2 <= RelTol ||b||_2 (the recursive residual,
 *   as hypre's PCG with the two-norm), tested before the preconditioner,
 *   also at the start (a warm start within RelTol costs no iteration unless
 *   MinIter asks for one), so a converged channel costs no V-cycle;
 * - channels drop out as they converge, stop by the change rule or break
 *   down (p.Ap <= 0, r.z <= 0 with r != 0, a non-finite value: stopped, not
 *   converged, x the last finite iterate, the iteration it happened in
 *   counted, so at least one: DiffusionFrontEnd takes a channel with no
 *   iteration for one that needed none) or reach MaxIter.
 *
 * Internal to the LinearAlgebra layer (MPI).
 */
#pragma once

#include "DistributedLinearSolver.h"

#include <mpi.h>

#include <array>
#include <functional>

namespace translucency
{

/// One channel of SolveChannelsPCG: its work vectors (this rank's rows
/// each, e.g. the local data of hypre ParVectors) and the two collective
/// operations on them.
struct DistributedPCGChannel
{
  double* R = nullptr;
  double* Z = nullptr;
  double* P = nullptr;
  double* Q = nullptr;
  /// Q = A P (collective over the channels' communicator).
  std::function<void()> Multiply;
  /// Z = M R, the preconditioner (collective); Z on entry is unspecified.
  std::function<void()> Precondition;
};

/**
 * Collective: PCG on the channels with a non-null channels[c] (every rank
 * the same ones), `rows` values per vector on this rank, the rules of
 * `control` (DistributedSolveControl); stats[c] of those channels. b[c] and
 * x[c] as DistributedLinearSolver::SolveChannels. An exception of Multiply
 * or Precondition on any rank stops every rank at the next reduction; the
 * ranks where one was thrown rethrow it (translucency::Error), the others
 * return with those channels not converged (the caller's AgreeOnError then
 * reports it everywhere).
 */
void SolveChannelsPCG(MPI_Comm comm, int rows,
  const std::array<DistributedPCGChannel*, NumberOfChannels>& channels,
  const std::array<const double*, NumberOfChannels>& b, const std::array<double*, NumberOfChannels>& x,
  const std::array<bool, NumberOfChannels>& guess, const DistributedSolveControl& control,
  std::array<DistributedChannelStats, NumberOfChannels>& stats);

} // namespace translucency
