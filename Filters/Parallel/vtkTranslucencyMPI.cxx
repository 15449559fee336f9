#include "vtkTranslucencyMPI.h"

#ifdef TRANSLUCENCY_HAVE_DISTRIBUTED_SOLVE
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
#else
bool vtkTranslucency::CanDistribute(const vtkTranslucencyCommunicator&)
{
  return false;
}
#endif
