/**
 * @file vtkTranslucencyGlobalCommunicator.h
 * @brief The MPI communicator of ParaView's global controller, for the
 * distributed paths (Solve Diffusion, Surface Irradiance). Private header.
 */
#ifndef vtkTranslucencyGlobalCommunicator_h
#define vtkTranslucencyGlobalCommunicator_h

#ifdef TRANSLUCENCY_HAVE_DISTRIBUTED_SOLVE
#include <vtkMPI.h>
#include <vtkMPICommunicator.h>
#include <vtkMultiProcessController.h>

namespace vtkTranslucency
{
/// The global controller's MPI communicator when it has more than one
/// process, else nullptr (one process, or a controller that is not MPI).
inline MPI_Comm* GlobalCommunicator()
{
  vtkMultiProcessController* controller = vtkMultiProcessController::GetGlobalController();
  if (!controller || controller->GetNumberOfProcesses() <= 1)
  {
    return nullptr;
  }
  auto* communicator = vtkMPICommunicator::SafeDownCast(controller->GetCommunicator());
  if (!communicator || !communicator->GetMPIComm())
  {
    return nullptr;
  }
  return communicator->GetMPIComm()->GetHandle();
}
}
#endif

#endif
