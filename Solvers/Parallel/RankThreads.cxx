#include "RankThreads.h"

#include <omp.h>

#include <algorithm>
#include <cstdlib>

namespace translucency
{

int ThreadsPerRank(MPI_Comm comm)
{
  MPI_Comm node;
  MPI_Comm_split_type(comm, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node);
  int ranksOnNode = 1;
  MPI_Comm_size(node, &ranksOnNode);
  MPI_Comm_free(&node);
  return std::max(1, omp_get_num_procs() / std::max(1, ranksOnNode));
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
  static int cached = 0;
  static MPI_Comm cachedComm = MPI_COMM_NULL;
  if (cached == 0 || cachedComm != comm)
  {
    cached = ThreadsPerRank(comm);
    cachedComm = comm;
  }
  Previous_ = omp_get_max_threads();
  Threads_ = cached;
  omp_set_num_threads(Threads_);
}

ScopedRankThreads::~ScopedRankThreads()
{
  if (Threads_ > 0)
  {
    omp_set_num_threads(Previous_);
  }
}

} // namespace translucency
