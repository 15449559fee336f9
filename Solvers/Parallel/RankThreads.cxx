#include "RankThreads.h"

#include "Threads.h"

#include <omp.h>

#include <cstdlib>
#include <thread>

namespace translucency
{

int RanksOnThisNode(MPI_Comm comm)
{
  static int cached = 0;
  static MPI_Comm cachedComm = MPI_COMM_NULL;
  if (cached == 0 || cachedComm != comm)
  {
    MPI_Comm node = MPI_COMM_NULL;
    int ranksOnNode = 1;
    if (MPI_Comm_split_type(comm, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node) ==
        MPI_SUCCESS &&
      node != MPI_COMM_NULL)
    {
      MPI_Comm_size(node, &ranksOnNode);
      MPI_Comm_free(&node);
    }
    else
    {
      MPI_Comm_size(comm, &ranksOnNode);
    }
    cached = ranksOnNode;
    cachedComm = comm;
  }
  return cached;
}

ScopedRankThreads::ScopedRankThreads(MPI_Comm comm)
{
  int size = 1;
  MPI_Comm_size(comm, &size);
  if (size <= 1)
  {
    return;
  }
  // The user's choice on any rank keeps every rank's default (agreed, so
  // that every rank takes part in the node split below or none does).
  const char* chosen = std::getenv("OMP_NUM_THREADS");
  int userChoice = chosen && *chosen ? 1 : 0;
  MPI_Allreduce(MPI_IN_PLACE, &userChoice, 1, MPI_INT, MPI_MAX, comm);
  if (userChoice)
  {
    return;
  }
  const int cores = static_cast<int>(std::thread::hardware_concurrency());
  Threads_ = ThreadsPerRank(cores > 0 ? cores : omp_get_num_procs(), omp_get_num_procs(),
    RanksOnThisNode(comm), false);
  if (Threads_ > 0)
  {
    Previous_ = omp_get_max_threads();
    omp_set_num_threads(Threads_);
  }
}

ScopedRankThreads::~ScopedRankThreads()
{
  if (Threads_ > 0)
  {
    omp_set_num_threads(Previous_);
  }
}

} // namespace translucency
