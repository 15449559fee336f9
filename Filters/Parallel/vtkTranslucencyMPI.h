/**
 * @file   vtkTranslucencyMPI.h
 * @brief  The MPI handle of the one communicator (vtkTranslucencyCommunicator),
 *         for the distributed paths that call the core's MPI code
 *         (Solvers/Parallel). Private to the filters.
 */
#ifndef vtkTranslucencyMPI_h
#define vtkTranslucencyMPI_h

#include "Communicator.h" // translucency::Communicator
#include "vtkTranslucencyCommunicator.h"

#include <string>

#ifdef TRANSLUCENCY_HAVE_DISTRIBUTED_SOLVE
#include <vtkMPI.h>
#endif

namespace vtkTranslucency
{
/**
 * True if this build has the distributed paths (hypre and VTK's ParallelMPI)
 * and `comm` can run them: size one (a plan declared in one process) or an
 * MPI controller. False otherwise: those stages gather.
 */
bool CanDistribute(const vtkTranslucencyCommunicator& comm);

/**
 * The core's communicator for a serial path run replicated on every rank
 * (vtkTranslucencyCommunicator::Replicated(), when it is parallel and MPI
 * and this build has the distributed paths); else none (an in-process
 * solve).
 */
translucency::Communicator ReplicatedSolverCommunicator();

/**
 * Collective over `comm` (every rank calls it). Whether every rank can hold
 * a copy of `bytesPerCopy` bytes at once: on each node, the ranks on it
 * times the copy within the node's available memory (MemAvailable of
 * /proc/meminfo, or TRANSLUCENCY_REPLICATED_MEMORY GiB when that is set).
 * The same answer on every rank; when false, `why` says what would not fit
 * ("replicating ... on the N ranks of a node needs about X; the node has Y
 * available"). True in a build without MPI paths and for size one.
 */
bool ReplicationFits(
  const vtkTranslucencyCommunicator& comm, double bytesPerCopy, std::string& why);

#ifdef TRANSLUCENCY_HAVE_DISTRIBUTED_SOLVE
/// The MPI communicator of `comm`, or nullptr (size one, or a controller
/// that is not MPI).
MPI_Comm* MPIHandle(const vtkTranslucencyCommunicator& comm);
#endif
}

#endif
