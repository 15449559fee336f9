/**
 * @file   vtkTranslucencyThreads.h
 * @brief  OpenMP threads per rank for the duration of one filter request
 *         (Documentation/Parallel.md, "Threads per rank"). Private to the
 *         filters.
 *
 * The rule is the core's, written once: translucency::ThreadsPerRank
 * (Solvers/Common/Threads.h), cores / ranks on the node. On an MPI
 * communicator the scope is the core's translucency::ScopedRankThreads
 * (Solvers/Parallel/RankThreads.h: the ranks on the node counted by MPI,
 * the user's OMP_NUM_THREADS agreed over the ranks); in a build without the
 * distributed paths, or on a controller that is not MPI, the ranks are taken
 * to share one node. A user who set OMP_NUM_THREADS keeps it.
 */
#ifndef vtkTranslucencyThreads_h
#define vtkTranslucencyThreads_h

#include "vtkTranslucencyCommunicator.h"

#include <memory>

namespace translucency
{
class ScopedRankThreads;
}

namespace vtkTranslucency
{
/// Sets the team size of translucency::ThreadsPerRank for this thread's
/// parallel regions while in scope. Collective when `comm` is parallel.
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
  std::unique_ptr<translucency::ScopedRankThreads> Mpi;
  int Threads = 0;
  int Saved = 0;
};
}

#endif
