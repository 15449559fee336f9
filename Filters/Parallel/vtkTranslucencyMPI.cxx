#include "vtkTranslucencyMPI.h"

#ifdef TRANSLUCENCY_HAVE_DISTRIBUTED_SOLVE
#include "HypreSolver.h" // MakeCommunicator: the MPI side of translucency::Communicator

#include <vtkMPICommunicator.h>
#include <vtkMultiProcessController.h>

MPI_Comm* vtkTranslucency::MPIHandle(const vtkTranslucencyCommunicator& comm)
{
  vtkMultiProcessController* controller = comm.GetController();
  auto* communicator =
    controller ? vtkMPICommunicator::SafeDownCast(controller->GetCommunicator()) : nullptr;
  if (!communicator || !communicator->GetMPIComm())
  {
    return nullptr;
  }
  return communicator->GetMPIComm()->GetHandle();
}

bool vtkTranslucency::CanDistribute(const vtkTranslucencyCommunicator& comm)
{
  return !comm.IsParallel() || MPIHandle(comm) != nullptr;
}

translucency::Communicator vtkTranslucency::ReplicatedSolverCommunicator()
{
  const vtkTranslucencyCommunicator shared = vtkTranslucencyCommunicator::Replicated();
  const MPI_Comm* handle = shared.IsParallel() ? MPIHandle(shared) : nullptr;
  return handle ? translucency::MakeCommunicator(handle) : translucency::Communicator();
}
#else
bool vtkTranslucency::CanDistribute(const vtkTranslucencyCommunicator&)
{
  return false;
}

translucency::Communicator vtkTranslucency::ReplicatedSolverCommunicator()
{
  return translucency::Communicator();
}
#endif
