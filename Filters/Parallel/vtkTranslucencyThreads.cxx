#include "vtkTranslucencyThreads.h"

#include "Threads.h"
#include "vtkTranslucencyMPI.h"

#ifdef TRANSLUCENCY_HAVE_DISTRIBUTED_SOLVE
#include "RankThreads.h"
#endif

#include <omp.h>

#include <cstdlib>
#include <thread>

vtkTranslucency::ThreadsPerRankScope::ThreadsPerRankScope(const vtkTranslucencyCommunicator& comm)
{
  if (!comm.IsParallel())
  {
    return;
  }
#ifdef TRANSLUCENCY_HAVE_DISTRIBUTED_SOLVE
  if (MPI_Comm* handle = MPIHandle(comm))
  {
    this->Mpi = std::make_unique<translucency::ScopedRankThreads>(*handle);
    this->Threads = this->Mpi->GetThreads();
    return;
  }
#endif
  // No MPI handle: every rank of `comm` is taken to share this node.
  const char* user = std::getenv("OMP_NUM_THREADS");
  const int cores = static_cast<int>(std::thread::hardware_concurrency());
  this->Threads = translucency::ThreadsPerRank(cores > 0 ? cores : omp_get_num_procs(),
    omp_get_num_procs(), comm.GetSize(), user && *user);
  if (this->Threads > 0)
  {
    this->Saved = omp_get_max_threads();
    omp_set_num_threads(this->Threads);
  }
}

vtkTranslucency::ThreadsPerRankScope::~ThreadsPerRankScope()
{
  if (!this->Mpi && this->Threads > 0)
  {
    omp_set_num_threads(this->Saved);
  }
}
