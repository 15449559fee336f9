#include "vtkTranslucencyThreads.h"

#include "vtkTranslucencyMPI.h"

#include <omp.h>

#include <algorithm>
#include <cstdlib>
#include <thread>

namespace
{
/// Ranks of `comm` sharing this node's memory (MPI_COMM_TYPE_SHARED), or the
/// communicator's size when it is not MPI's. Collective.
int CountRanksOnThisNode(const vtkTranslucencyCommunicator& comm)
{
#ifdef TRANSLUCENCY_HAVE_DISTRIBUTED_SOLVE
  if (MPI_Comm* handle = vtkTranslucency::MPIHandle(comm))
  {
    MPI_Comm node = MPI_COMM_NULL;
    if (MPI_Comm_split_type(*handle, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node) ==
        MPI_SUCCESS &&
      node != MPI_COMM_NULL)
    {
      int size = 1;
      MPI_Comm_size(node, &size);
      MPI_Comm_free(&node);
      return size;
    }
  }
#endif
  return comm.GetSize();
}
}

int vtkTranslucency::ThreadsPerRank(int cores, int available, int ranksOnNode, bool userSet)
{
  if (userSet || ranksOnNode <= 1)
  {
    return 0;
  }
  return std::max(1, std::min(available, cores / ranksOnNode));
}

int vtkTranslucency::RanksOnThisNode(const vtkTranslucencyCommunicator& comm)
{
  if (!comm.IsParallel())
  {
    return 1;
  }
  // A run's node layout does not change: counted at the first request, which
  // reaches here on every rank (as every later request does).
  static int worldSize = 0;
  static int ranksOnNode = 1;
  if (worldSize != comm.GetSize())
  {
    ranksOnNode = CountRanksOnThisNode(comm);
    worldSize = comm.GetSize();
  }
  return ranksOnNode;
}

vtkTranslucency::ThreadsPerRankScope::ThreadsPerRankScope(const vtkTranslucencyCommunicator& comm)
{
  if (!comm.IsParallel())
  {
    return;
  }
  const char* user = std::getenv("OMP_NUM_THREADS");
  const bool userSet = user && *user;
  const int ranks = RanksOnThisNode(comm); // collective: every rank, whatever userSet says
  const int cores = static_cast<int>(std::thread::hardware_concurrency());
  this->Threads =
    ThreadsPerRank(cores > 0 ? cores : omp_get_num_procs(), omp_get_num_procs(), ranks, userSet);
  if (this->Threads > 0)
  {
    this->Saved = omp_get_max_threads();
    omp_set_num_threads(this->Threads);
  }
}

vtkTranslucency::ThreadsPerRankScope::~ThreadsPerRankScope()
{
  if (this->Threads > 0)
  {
    omp_set_num_threads(this->Saved);
  }
}
