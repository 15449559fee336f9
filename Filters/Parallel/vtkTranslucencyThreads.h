/**
 * @file   vtkTranslucencyThreads.h
 * @brief  OpenMP threads per rank: cores / ranks on the node, for the
 *         duration of one filter request (Documentation/Parallel.md,
 *         "Threads per rank"). Private to the filters.
 *
 * N ranks on a node that each start OpenMP's default team (one thread per
 * core) run N x cores threads on the cores; OpenMP's spin-wait then burns
 * the CPU the other ranks need (5.7x the CPU time of one thread was
 * measured with 3 ranks x 2 threads on 2 cores). The dispatcher therefore
 * sets each rank's team to max(1, cores / ranks on this node) while a
 * request runs, and restores the previous setting after. A user who set
 * OMP_NUM_THREADS keeps it: an explicit choice wins.
 */
#ifndef vtkTranslucencyThreads_h
#define vtkTranslucencyThreads_h

#include "vtkTranslucencyCommunicator.h"

namespace vtkTranslucency
{
/// The OpenMP team size for one of `ranksOnNode` ranks sharing the node's
/// `cores`, of which `available` are in this rank's affinity mask (mpiexec
/// may bind a rank to one core): max(1, min(available, cores / ranksOnNode));
/// 0 (leave OpenMP's own setting) when the user set OMP_NUM_THREADS
/// (`userSet`) or there is one rank on the node.
int ThreadsPerRank(int cores, int available, int ranksOnNode, bool userSet);

/// The number of ranks of `comm` on this node (MPI_COMM_TYPE_SHARED when
/// the communicator is MPI's; else the communicator's size). Collective.
int RanksOnThisNode(const vtkTranslucencyCommunicator& comm);

/// Sets ThreadsPerRank() for this thread's parallel regions while in scope.
class ThreadsPerRankScope
{
public:
  explicit ThreadsPerRankScope(const vtkTranslucencyCommunicator& comm);
  ~ThreadsPerRankScope();
  ThreadsPerRankScope(const ThreadsPerRankScope&) = delete;
  ThreadsPerRankScope& operator=(const ThreadsPerRankScope&) = delete;
  /// The team size set (0: OpenMP's own setting left as it was).
  int GetThreads() const { return this->Threads; }

private:
  int Threads = 0;
  int Saved = 0;
};
}

#endif
