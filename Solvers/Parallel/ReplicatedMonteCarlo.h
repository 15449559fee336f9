/**
 * @file ReplicatedMonteCarlo.h
 * @brief The Monte Carlo reference with its photons split over MPI ranks,
 * the whole mesh replicated on every rank (issue 32).
 *
 * Every rank calls Solve with the same whole problem (the mesh, material
 * and lights: the filters gather the pieces and broadcast them,
 * Filters/Parallel/vtkTranslucencyParallel). Rank r of P traces the batches
 * b with b % P == r of the one-process plan (the same photons: each has its
 * own random stream, a function of the seed, channel and photon index), and
 * one MPI_Allreduce per tally adds the batch sums over the ranks
 * (MonteCarloSolver::SumOverShare). Every rank thus gets the estimates and
 * standard errors of all the batches: the one-process results up to the
 * order of the additions (1e-15 relative), independent of the number of
 * ranks. At most NumberOfBatches ranks have photons to trace.
 *
 * The limit: every rank holds the whole mesh, the walk structure and the
 * tallies (one tet and point tally per busy thread, and the sums), i.e.
 * the one-process Monte Carlo's memory on every rank.
 *
 * Every call that traces is collective; an abort asked for on one rank (the
 * progress callback) is every rank's (the outputs then stay unchanged).
 * The registry's distributed variant of "montecarlo" (trait Replicated,
 * DiffusionSolverFactory.h); none as the communicator means MPI_COMM_SELF.
 */
#pragma once

#include "HypreSolver.h" // GetMPIComm: the MPI side of Communicator
#include "MonteCarlo.h"

#include <mpi.h>

namespace translucency
{

class ReplicatedMonteCarloSolver : public MonteCarloSolver
{
public:
  ReplicatedMonteCarloSolver();
  /// The ranks of `comm` share the photons (none: MPI_COMM_SELF, one rank).
  void SetCommunicator(const Communicator& comm) override;

protected:
  void SumOverShare(double* values, std::size_t count) const override;

private:
  MPI_Comm Comm_ = MPI_COMM_NULL;
};

} // namespace translucency
