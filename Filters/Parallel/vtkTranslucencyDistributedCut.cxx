#include "vtkTranslucencyDistributedCut.h"

#include "CutFront.h"
#include "Error.h"
#include "TetMesh.h"
#include "vtkTranslucencyCommunicator.h"
#include "vtkTranslucencyGhosts.h"

#include <vtkCellData.h>
#include <vtkCommunicator.h>
#include <vtkDataArray.h>
#include <vtkDataSetAttributes.h>
#include <vtkMultiProcessController.h>
#include <vtkPointData.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>

#include <algorithm>
#include <climits>
#include <cstdint>

namespace
{
vtkMultiProcessController* Controller()
{
  return vtkTranslucencyCommunicator::World().GetController();
}

/// All ranks' `local` values, concatenated in rank order; `counts` gets each
/// rank's number of values.
template <typename T>
std::vector<T> AllGatherV(const std::vector<T>& local, std::vector<vtkIdType>& counts)
{
  vtkMultiProcessController* controller = Controller();
  const int ranks = controller->GetNumberOfProcesses();
  counts.assign(static_cast<size_t>(ranks), 0);
  vtkIdType mine = static_cast<vtkIdType>(local.size());
  controller->AllGather(&mine, counts.data(), 1);
  std::vector<vtkIdType> offsets(static_cast<size_t>(ranks), 0);
  vtkIdType total = 0;
  for (int r = 0; r < ranks; ++r)
  {
    offsets[static_cast<size_t>(r)] = total;
    total += counts[static_cast<size_t>(r)];
  }
  std::vector<T> all(static_cast<size_t>(total));
  // (A rank without values still takes part: VTK's buffers must be valid.)
  T dummy{};
  controller->AllGatherV(local.empty() ? &dummy : local.data(), all.empty() ? &dummy : all.data(),
    mine, counts.data(), offsets.data());
  return all;
}
}

//------------------------------------------------------------------------------
bool vtkTranslucencyDistributedCut::ShareStroke(
  const std::vector<double>& local, std::vector<double>& shared)
{
  const vtkTranslucencyCommunicator comm = vtkTranslucencyCommunicator::World();
  vtkMultiProcessController* controller = comm.GetController();
  if (!controller)
  {
    shared = local; // one process: its own stroke
    return true;
  }
  const int rank = comm.GetRank();
  int mine = local.empty() ? INT_MAX : rank, first = INT_MAX;
  controller->AllReduce(&mine, &first, 1, vtkCommunicator::MIN_OP);
  shared.clear();
  if (first == INT_MAX)
  {
    return true;
  }
  long long length = rank == first ? static_cast<long long>(local.size()) : 0;
  controller->Broadcast(&length, 1, first);
  shared.assign(static_cast<size_t>(length), 0.0);
  if (rank == first)
  {
    shared = local;
  }
  controller->Broadcast(shared.data(), static_cast<vtkIdType>(length), first);
  return !vtkTranslucencyCommunicator::World().Any(!local.empty() && local != shared);
}

//------------------------------------------------------------------------------
bool vtkTranslucencyDistributedCut::RelaxFront(vtkUnstructuredGrid* piece,
  const translucency::TetMesh* mesh, const std::vector<double>& side,
  const translucency::TetCut& local, translucency::TetCut& relax,
  const translucency::TetCut::SideFunction& F, std::vector<double>& positions,
  FrontStatistics& statistics, std::string& error)
{
  statistics = FrontStatistics();
  const bool hasPoints = mesh && mesh->GetNumberOfPoints() > 0;
  vtkDataArray* ids = hasPoints && piece ? piece->GetPointData()->GetGlobalIds() : nullptr;
  // One rule on every rank: ids only if every rank with points has them.
  const bool byId = !vtkTranslucencyCommunicator::World().Any(hasPoints && !ids);

  // 1. This rank's front: its owned kept tets with a vertex of F > 0.
  std::vector<long long> frontIds, frontTets;
  std::vector<double> frontPoints;
  std::string localError;
  if (hasPoints)
  {
    std::vector<char> owned;
    vtkUnsignedCharArray* ghosts = vtkTranslucency::GhostCells(piece);
    if (ghosts && ghosts->GetNumberOfTuples() == mesh->GetNumberOfTets())
    {
      owned.resize(static_cast<size_t>(mesh->GetNumberOfTets()));
      for (vtkIdType c = 0; c < ghosts->GetNumberOfTuples(); ++c)
      {
        owned[static_cast<size_t>(c)] = !vtkTranslucency::IsGhostCell(ghosts, c);
      }
    }
    std::vector<int> points, tets;
    try
    {
      translucency::CutFront::ExtractFront(
        mesh->GetTets(), side, local.GetKeptTets(), owned, points, tets);
    }
    catch (const translucency::Error& e)
    {
      localError = e.what();
    }
    const std::vector<double>& x = mesh->GetPoints();
    for (int p : points)
    {
      frontPoints.insert(frontPoints.end(), &x[3 * static_cast<size_t>(p)],
        &x[3 * static_cast<size_t>(p)] + 3);
      if (byId)
      {
        frontIds.push_back(static_cast<long long>(ids->GetComponent(p, 0)));
      }
    }
    frontTets.assign(tets.begin(), tets.end());
  }
  error = vtkTranslucencyCommunicator::World().AgreeOnError(localError);
  if (!error.empty())
  {
    return false;
  }

  // 2. Every rank gets every front (rank order) and relaxes it as the serial
  // cut would: the same computation on the same data on every rank.
  std::vector<vtkIdType> pointCounts, tetCounts, idCounts;
  const std::vector<double> allPoints = AllGatherV(frontPoints, pointCounts);
  const std::vector<long long> allTets = AllGatherV(frontTets, tetCounts);
  const std::vector<long long> allIds =
    byId ? AllGatherV(frontIds, idCounts) : std::vector<long long>();
  statistics.Bytes = static_cast<long long>(allPoints.size() * sizeof(double) +
    (allTets.size() + allIds.size()) * sizeof(long long));
  translucency::CutFront front(byId);
  try
  {
    size_t pointAt = 0, tetAt = 0;
    for (size_t r = 0; r < pointCounts.size(); ++r)
    {
      const size_t n = static_cast<size_t>(pointCounts[r]) / 3;
      const size_t t = static_cast<size_t>(tetCounts[r]) / 4;
      const std::vector<std::int64_t> rankIds = byId
        ? std::vector<std::int64_t>(allIds.begin() + static_cast<std::ptrdiff_t>(pointAt),
            allIds.begin() + static_cast<std::ptrdiff_t>(pointAt + n))
        : std::vector<std::int64_t>();
      const std::vector<std::int64_t> rankTets(allTets.begin() + static_cast<std::ptrdiff_t>(tetAt),
        allTets.begin() + static_cast<std::ptrdiff_t>(tetAt + 4 * t));
      front.Add(byId ? rankIds.data() : nullptr, allPoints.data() + 3 * pointAt,
        static_cast<std::int64_t>(n), rankTets.data(), static_cast<std::int64_t>(t));
      pointAt += n;
      tetAt += 4 * t;
    }
    front.Relax(relax, F);
  }
  catch (const translucency::Error& e)
  {
    localError = e.what();
  }
  statistics.Points = front.GetNumberOfPoints();
  statistics.Tets = front.GetNumberOfTets();
  error = vtkTranslucencyCommunicator::World().AgreeOnError(localError);
  if (!error.empty())
  {
    return false;
  }

  // 3. This rank's kept points take their relaxed positions.
  const std::vector<int>& kept = local.GetKeptPoints();
  positions = local.GetPoints();
  if (hasPoints)
  {
    const std::vector<double>& x = mesh->GetPoints();
    for (size_t k = 0; k < kept.size(); ++k)
    {
      const int p = kept[k];
      const std::int64_t f = byId
        ? front.Find(static_cast<std::int64_t>(ids->GetComponent(p, 0)))
        : front.Find(&x[3 * static_cast<size_t>(p)]);
      if (f >= 0)
      {
        const double* moved = front.GetPosition(f);
        std::copy_n(moved, 3, &positions[3 * k]);
      }
    }
  }
  return true;
}
