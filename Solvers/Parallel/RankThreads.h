/**
 * @file RankThreads.h
 * @brief OpenMP threads per MPI rank: the cores of a node shared by the
 * ranks on it (issue 32), so that N ranks on one machine do not each start
 * one thread per core (N times oversubscribed).
 */
#pragma once

#include <mpi.h>

namespace translucency
{

/**
 * Collective over `comm`. The threads each rank of `comm` should use: the
 * processors OpenMP sees on this rank's node (omp_get_num_procs) divided by
 * the ranks of `comm` on that node (MPI_Comm_split_type, shared memory),
 * rounded down, at least 1.
 */
int ThreadsPerRank(MPI_Comm comm);

/**
 * While alive, OpenMP's default team size on the calling thread is
 * ThreadsPerRank(comm) when `comm` has more than one rank and no rank's user
 * chose (OMP_NUM_THREADS unset or empty on every rank); otherwise it changes
 * nothing. The previous default is restored on destruction. Collective (one
 * MPI_Allreduce; the first time on a communicator also the node split, whose
 * result is kept per process).
 */
class ScopedRankThreads
{
public:
  explicit ScopedRankThreads(MPI_Comm comm);
  ~ScopedRankThreads();
  ScopedRankThreads(const ScopedRankThreads&) = delete;
  ScopedRankThreads& operator=(const ScopedRankThreads&) = delete;
  /// The team size set (0: unchanged).
  int GetThreads() const { return Threads_; }

private:
  int Previous_ = 0;
  int Threads_ = 0;
};

} // namespace translucency
