#include "vtkTranslucencyMPI.h"

#ifdef TRANSLUCENCY_HAVE_DISTRIBUTED_SOLVE
#include "HypreSolver.h" // MakeCommunicator: the MPI side of translucency::Communicator
#include "RankThreads.h" // RanksOnThisNode
#include "ResourceLimits.h" // FormatBytes

#include <vtkMPICommunicator.h>
#include <vtkMultiProcessController.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

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

namespace
{
/// The memory a node offers new copies (bytes), and where the figure comes
/// from; NaN with `source` naming the problem when the override is invalid.
double AvailableNodeMemory(std::string& source)
{
  if (const char* text = std::getenv("TRANSLUCENCY_REPLICATED_MEMORY"))
  {
    char* end = nullptr;
    errno = 0;
    const double gib = std::strtod(text, &end);
    if (end == text || *end != '\0' || errno != 0 || !std::isfinite(gib) || gib <= 0.0)
    {
      source = std::string("TRANSLUCENCY_REPLICATED_MEMORY='") + text +
        "' is not a number of GiB > 0";
      return std::nan("");
    }
    source = "TRANSLUCENCY_REPLICATED_MEMORY";
    return gib * 1024.0 * 1024.0 * 1024.0;
  }
  std::ifstream meminfo("/proc/meminfo");
  std::string line;
  while (std::getline(meminfo, line))
  {
    std::istringstream fields(line);
    std::string key;
    double kib = 0.0;
    if (fields >> key >> kib && key == "MemAvailable:")
    {
      source = "MemAvailable";
      return kib * 1024.0;
    }
  }
  source = "unknown (no MemAvailable in /proc/meminfo)";
  return HUGE_VAL; // nothing to check against: assume it fits
}
}

bool vtkTranslucency::ReplicationFits(
  const vtkTranslucencyCommunicator& comm, double bytesPerCopy, std::string& why)
{
  why.clear();
  const MPI_Comm* handle = comm.IsParallel() ? MPIHandle(comm) : nullptr;
  if (!handle)
  {
    return true;
  }
  const int ranks = translucency::RanksOnThisNode(*handle); // collective (the first time)
  std::string source;
  const double available = AvailableNodeMemory(source);
  const double needed = ranks * bytesPerCopy;
  const bool fits = needed <= available; // false for NaN
  if (!fits)
  {
    std::ostringstream text;
    if (std::isnan(available))
    {
      text << source;
    }
    else
    {
      text << "a copy of the whole mesh on each of the " << ranks
           << " ranks of this node needs about " << translucency::FormatBytes(needed)
           << "; the node has " << translucency::FormatBytes(available) << " (" << source
           << ")";
    }
    why = text.str();
  }
  // The lowest rank that does not fit says why, on every rank.
  why = comm.AgreeOnError(why);
  return why.empty();
}
#else
bool vtkTranslucency::ReplicationFits(const vtkTranslucencyCommunicator&, double, std::string& why)
{
  why.clear();
  return true;
}

bool vtkTranslucency::CanDistribute(const vtkTranslucencyCommunicator&)
{
  return false;
}

translucency::Communicator vtkTranslucency::ReplicatedSolverCommunicator()
{
  return translucency::Communicator();
}
#endif
