/**
 * @file RankThreads.h
 * @brief OpenMP threads per MPI rank: the cores of a node shared by the
 * ranks on it (issue 32), so that N ranks on one machine do not each start
 * one thread per core (N times oversubscribed). The rule itself is
 * translucency::ThreadsPerRank (Solvers/Common/Threads.h); this is its MPI
 * side, used by the distributed solver and by the filters' dispatcher
 * (Filters/Parallel/vtkTranslucencyThreads.h).
 */
#pragma once

#include <mpi.h>

namespace translucency
{

/**
 * Collective over `comm`: the ranks of `comm` sharing this rank's node
 * (MPI_Comm_split_type, shared memory). Counted once per communicator and
 * kept: a run's node layout does not change.
 */
int RanksOnThisNode(MPI_Comm comm);

/**
 * While alive, OpenMP's default team size on the calling thread is
 * ThreadsPerRank(hardware threads, processors OpenMP may use, ranks of
 * `comm` on this node) when `comm` has more than one rank and no rank's user
 * chose (OMP_NUM_THREADS unset or empty on every rank); otherwise it changes
 * nothing. The previous default is restored on destruction. Collective (one
 * MPI_Allreduce; the first time on a communicator also the node split).
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
