#include "vtkTranslucencyDistributedPieces.h"

#include <vtkCellData.h>
#include <vtkCommunicator.h>
#include <vtkDataSetAttributes.h>
#include <vtkMultiProcessController.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>

#include <climits>
#include <vector>

namespace
{
vtkMultiProcessController* Controller()
{
  return vtkMultiProcessController::GetGlobalController();
}
}

bool vtkTranslucencyDistributedPieces::IsAvailable()
{
  vtkMultiProcessController* controller = Controller();
  return controller && controller->GetNumberOfProcesses() > 1;
}

int vtkTranslucencyDistributedPieces::GetRank()
{
  return Controller() ? Controller()->GetLocalProcessId() : 0;
}

long long vtkTranslucencyDistributedPieces::Sum(long long value)
{
  long long total = 0;
  Controller()->AllReduce(&value, &total, 1, vtkCommunicator::SUM_OP);
  return total;
}

long long vtkTranslucencyDistributedPieces::ExclusiveSum(long long value)
{
  vtkMultiProcessController* controller = Controller();
  std::vector<long long> all(static_cast<size_t>(controller->GetNumberOfProcesses()));
  controller->AllGather(&value, all.data(), 1);
  long long below = 0;
  for (int r = 0; r < controller->GetLocalProcessId(); ++r)
  {
    below += all[static_cast<size_t>(r)];
  }
  return below;
}

bool vtkTranslucencyDistributedPieces::Any(bool value)
{
  int mine = value ? 1 : 0, any = 0;
  Controller()->AllReduce(&mine, &any, 1, vtkCommunicator::MAX_OP);
  return any != 0;
}

std::string vtkTranslucencyDistributedPieces::AgreeOnError(const std::string& localError)
{
  vtkMultiProcessController* controller = Controller();
  const int rank = controller->GetLocalProcessId();
  int mine = localError.empty() ? INT_MAX : rank, first = INT_MAX;
  controller->AllReduce(&mine, &first, 1, vtkCommunicator::MIN_OP);
  if (first == INT_MAX)
  {
    return std::string();
  }
  int length = rank == first ? static_cast<int>(localError.size()) : 0;
  controller->Broadcast(&length, 1, first);
  std::vector<char> text(static_cast<size_t>(length) + 1, '\0');
  if (rank == first)
  {
    localError.copy(text.data(), localError.size());
  }
  controller->Broadcast(text.data(), length + 1, first);
  return "rank " + std::to_string(first) + ": " + std::string(text.data(), static_cast<size_t>(length));
}

bool vtkTranslucencyDistributedPieces::HasGhostCells(vtkUnstructuredGrid* piece)
{
  auto* ghosts = piece ? vtkUnsignedCharArray::SafeDownCast(piece->GetCellData()->GetArray(
                           vtkDataSetAttributes::GhostArrayName()))
                       : nullptr;
  if (!ghosts)
  {
    return false;
  }
  for (vtkIdType c = 0; c < ghosts->GetNumberOfTuples(); ++c)
  {
    if (ghosts->GetValue(c) & vtkDataSetAttributes::DUPLICATECELL)
    {
      return true;
    }
  }
  return false;
}
