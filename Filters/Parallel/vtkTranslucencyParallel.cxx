#include "vtkTranslucencyParallel.h"

#include "vtkTranslucencyCommunicator.h"
#include "vtkTranslucencyGhosts.h"

#include <vtkAbstractArray.h>
#include <vtkAlgorithm.h>
#include <vtkCallbackCommand.h>
#include <vtkCellData.h>
#include <vtkCommand.h>
#include <vtkCompositeDataIterator.h>
#include <vtkCompositeDataSet.h>
#include <vtkDataArray.h>
#include <vtkDataObject.h>
#include <vtkDataSetAttributes.h>
#include <vtkFieldData.h>
#include <vtkIdList.h>
#include <vtkImageAppend.h>
#include <vtkImageData.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkMultiProcessController.h>
#include <vtkMultiProcessStream.h>
#include <vtkDataAssembly.h>
#include <vtkNew.h>
#include <vtkPartitionedDataSet.h>
#include <vtkPartitionedDataSetCollection.h>
#include <vtkPointData.h>
#include <vtkPointSet.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkTable.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <exception>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

namespace vtkTranslucencyParallel
{
namespace
{
/// Message tags of the scatter (point and cell arrays to rank r).
constexpr int PointArraysTag = 0x7a51;
constexpr int CellArraysTag = 0x7a52;

using Pieces = std::vector<vtkSmartPointer<vtkDataObject>>;

/// For the first input: where each rank's points and cells are in the merged
/// data set (-1: a point or ghost cell with no counterpart there).
struct PieceMaps
{
  std::vector<std::vector<vtkIdType>> Points;
  std::vector<std::vector<vtkIdType>> Cells;
};

bool IsEmpty(vtkDataObject* data)
{
  if (!data)
  {
    return true;
  }
  if (auto* ds = vtkDataSet::SafeDownCast(data))
  {
    return ds->GetNumberOfPoints() == 0 && ds->GetNumberOfCells() == 0;
  }
  if (auto* composite = vtkCompositeDataSet::SafeDownCast(data))
  {
    return composite->GetNumberOfPoints() == 0 && composite->GetNumberOfCells() == 0;
  }
  return false;
}

using vtkTranslucency::GhostCells;
using vtkTranslucency::IsGhostCell;

/// A point's identity across pieces: its global id, or its exact coordinates.
struct PointKey
{
  std::array<double, 3> X;
  bool operator==(const PointKey& o) const { return X == o.X; }
};
struct PointKeyHash
{
  size_t operator()(const PointKey& k) const
  {
    size_t h = 1469598103934665603ull;
    for (double v : k.X)
    {
      unsigned long long bits;
      std::memcpy(&bits, &v, sizeof bits);
      h = (h ^ bits) * 1099511628211ull;
    }
    return h;
  }
};

PointKey KeyOf(vtkPointSet* piece, vtkDataArray* globalIds, vtkIdType i)
{
  PointKey key;
  if (globalIds)
  {
    key.X = { globalIds->GetComponent(i, 0), 0.0, 0.0 };
  }
  else
  {
    piece->GetPoint(i, key.X.data());
  }
  for (double& v : key.X)
  {
    v += 0.0; // -0 and +0 are one coordinate
  }
  return key;
}

/// The pieces MergePointSets works on and what they have in common.
struct MergeInputs
{
  explicit MergeInputs(const Pieces& pieces)
    : PointFields(static_cast<int>(pieces.size()))
    , CellFields(static_cast<int>(pieces.size()))
  {
    for (const auto& p : pieces)
    {
      this->Sets.push_back(vtkPointSet::SafeDownCast(p));
      if (!this->Prototype && this->Sets.back() && !IsEmpty(this->Sets.back()))
      {
        this->Prototype = this->Sets.back();
      }
    }
    // Global ids only if every non-empty piece has them; the arrays common
    // to every non-empty piece; which piece is which input of the field
    // lists (the non-empty ones, in order).
    this->InputIndex.assign(this->Sets.size(), -1);
    int inputs = 0;
    for (size_t r = 0; r < this->Sets.size(); ++r)
    {
      vtkPointSet* s = this->Sets[r];
      if (!s || IsEmpty(s))
      {
        continue;
      }
      this->InputIndex[r] = inputs++;
      this->UseGlobalIds = this->UseGlobalIds && s->GetPointData()->GetGlobalIds() != nullptr;
      this->UseCellGlobalIds =
        this->UseCellGlobalIds && s->GetCellData()->GetGlobalIds() != nullptr;
      this->TotalPoints += s->GetNumberOfPoints();
      this->TotalCells += s->GetNumberOfCells();
      if (inputs == 1)
      {
        this->PointFields.InitializeFieldList(s->GetPointData());
        this->CellFields.InitializeFieldList(s->GetCellData());
      }
      else
      {
        this->PointFields.IntersectFieldList(s->GetPointData());
        this->CellFields.IntersectFieldList(s->GetCellData());
      }
    }
  }

  std::vector<vtkPointSet*> Sets;   ///< null for a piece that is not a point set
  vtkPointSet* Prototype = nullptr; ///< the first non-empty piece; null: all empty
  std::vector<int> InputIndex;      ///< index in the field lists; -1: empty piece
  bool UseGlobalIds = true;         ///< every non-empty piece has point GlobalIds
  bool UseCellGlobalIds = true;     ///< every non-empty piece has cell GlobalIds
  vtkIdType TotalPoints = 0, TotalCells = 0;
  vtkDataSetAttributes::FieldList PointFields;
  vtkDataSetAttributes::FieldList CellFields;
};

/// The attribute tuples a merge takes from each piece (source id -> merged
/// id), copied array by array at the end (vtkAbstractArray::InsertTuples:
/// one typed loop per array, where vtkDataSetAttributes::CopyData per tuple
/// visits every array for every tuple).
class TupleCopies
{
public:
  explicit TupleCopies(size_t pieces)
    : From(pieces)
    , To(pieces)
  {
  }
  void Add(size_t piece, vtkIdType from, vtkIdType to)
  {
    this->From[piece].push_back(from);
    this->To[piece].push_back(to);
  }
  /// Copy the recorded tuples of `attributes(piece)` into `output`, whose
  /// arrays `fields` allocated (CopyAllocate).
  template <class Attributes>
  void Apply(const vtkDataSetAttributes::FieldList& fields, const MergeInputs& in,
    Attributes attributes, vtkDataSetAttributes* output) const
  {
    vtkNew<vtkIdList> from, to;
    for (size_t r = 0; r < this->From.size(); ++r)
    {
      if (this->From[r].empty())
      {
        continue;
      }
      from->SetNumberOfIds(static_cast<vtkIdType>(this->From[r].size()));
      to->SetNumberOfIds(static_cast<vtkIdType>(this->To[r].size()));
      std::copy(this->From[r].begin(), this->From[r].end(), from->begin());
      std::copy(this->To[r].begin(), this->To[r].end(), to->begin());
      fields.TransformData(in.InputIndex[r], attributes(in.Sets[r]), output,
        [&](vtkAbstractArray* source, vtkAbstractArray* target)
        { target->InsertTuples(to, from, source); });
    }
  }

private:
  std::vector<std::vector<vtkIdType>> From, To;
};

/// The points of the merged set: those of owned cells, and points of no cell
/// at all (an orphan point is one in serial too), each once, in the order of
/// first occurrence or, with GlobalIds, of the ids; a point of ghost cells
/// only is matched to its owner's once every piece's points are in. Returns,
/// per piece, each point's merged id (-1: no counterpart).
std::vector<std::vector<vtkIdType>> MergePoints(MergeInputs& in, vtkPointSet* merged)
{
  const std::vector<vtkPointSet*>& sets = in.Sets;
  struct PointRef
  {
    size_t Piece;
    vtkIdType Id;
    double GlobalId;
  };
  std::vector<PointRef> unique;
  std::unordered_map<PointKey, vtkIdType, PointKeyHash> index;
  std::vector<std::vector<vtkIdType>> local(sets.size());
  vtkNew<vtkIdList> cellPoints;
  for (size_t r = 0; r < sets.size(); ++r)
  {
    vtkPointSet* s = sets[r];
    if (in.InputIndex[r] < 0)
    {
      continue;
    }
    vtkDataArray* globalIds = in.UseGlobalIds ? s->GetPointData()->GetGlobalIds() : nullptr;
    vtkUnsignedCharArray* ghosts = GhostCells(s);
    const vtkIdType n = s->GetNumberOfPoints();
    std::vector<char> owned(static_cast<size_t>(n), 0), used(static_cast<size_t>(n), 0);
    for (vtkIdType c = 0; c < s->GetNumberOfCells(); ++c)
    {
      s->GetCellPoints(c, cellPoints);
      const bool ghost = IsGhostCell(ghosts, c);
      for (vtkIdType k = 0; k < cellPoints->GetNumberOfIds(); ++k)
      {
        used[cellPoints->GetId(k)] = 1;
        if (!ghost)
        {
          owned[cellPoints->GetId(k)] = 1;
        }
      }
    }
    local[r].assign(static_cast<size_t>(n), -1);
    for (vtkIdType i = 0; i < n; ++i)
    {
      if (!owned[i] && used[i])
      {
        continue;
      }
      const PointKey key = KeyOf(s, globalIds, i);
      const auto inserted = index.emplace(key, static_cast<vtkIdType>(unique.size()));
      if (inserted.second)
      {
        unique.push_back({ r, i, key.X[0] });
      }
      local[r][i] = inserted.first->second;
    }
  }
  std::vector<vtkIdType> order(unique.size());
  for (size_t k = 0; k < order.size(); ++k)
  {
    order[k] = static_cast<vtkIdType>(k);
  }
  if (in.UseGlobalIds)
  {
    std::stable_sort(order.begin(), order.end(),
      [&unique](vtkIdType a, vtkIdType b) { return unique[a].GlobalId < unique[b].GlobalId; });
  }
  std::vector<vtkIdType> finalId(unique.size());
  vtkPoints* points = merged->GetPoints();
  points->SetNumberOfPoints(static_cast<vtkIdType>(unique.size()));
  TupleCopies copies(sets.size());
  for (size_t k = 0; k < order.size(); ++k)
  {
    const PointRef& p = unique[static_cast<size_t>(order[k])];
    finalId[static_cast<size_t>(order[k])] = static_cast<vtkIdType>(k);
    points->SetPoint(static_cast<vtkIdType>(k), sets[p.Piece]->GetPoint(p.Id));
    copies.Add(p.Piece, p.Id, static_cast<vtkIdType>(k));
  }
  copies.Apply(in.PointFields, in, [](vtkPointSet* s) { return s->GetPointData(); },
    merged->GetPointData());
  for (size_t r = 0; r < sets.size(); ++r)
  {
    vtkPointSet* s = sets[r];
    vtkDataArray* globalIds = s && in.UseGlobalIds ? s->GetPointData()->GetGlobalIds() : nullptr;
    for (size_t i = 0; i < local[r].size(); ++i)
    {
      vtkIdType& id = local[r][i];
      if (id >= 0)
      {
        id = finalId[static_cast<size_t>(id)];
        continue;
      }
      const auto found = index.find(KeyOf(s, globalIds, static_cast<vtkIdType>(i)));
      id = found == index.end() ? -1 : finalId[static_cast<size_t>(found->second)];
    }
  }
  return local;
}

/// Per merged point: whether more than one piece has it (`local`: each
/// piece's points' merged ids, -1 for none).
std::vector<char> SharedPoints(const std::vector<std::vector<vtkIdType>>& local, vtkIdType count)
{
  std::vector<char> shared(static_cast<size_t>(count), 0);
  std::vector<int> lastPiece(static_cast<size_t>(count), -1);
  for (size_t r = 0; r < local.size(); ++r)
  {
    for (vtkIdType id : local[r])
    {
      if (id < 0)
      {
        continue;
      }
      int& last = lastPiece[static_cast<size_t>(id)];
      if (last >= 0 && last != static_cast<int>(r))
      {
        shared[static_cast<size_t>(id)] = 1;
      }
      last = static_cast<int>(r);
    }
  }
  return shared;
}

/// A cell's identity: its type and sorted merged point ids.
std::string CellKey(int type, std::vector<vtkIdType> ids)
{
  std::sort(ids.begin(), ids.end());
  ids.push_back(type);
  return std::string(reinterpret_cast<const char*>(ids.data()), ids.size() * sizeof(vtkIdType));
}

/// The merged point ids of cell `c` of piece `r`.
void MergedCellPoints(const MergeInputs& in, const std::vector<std::vector<vtkIdType>>& local,
  size_t r, vtkIdType c, vtkIdList* cellPoints, std::vector<vtkIdType>& ids)
{
  in.Sets[r]->GetCellPoints(c, cellPoints);
  ids.resize(static_cast<size_t>(cellPoints->GetNumberOfIds()));
  for (size_t k = 0; k < ids.size(); ++k)
  {
    ids[k] = local[r][cellPoints->GetId(static_cast<vtkIdType>(k))];
  }
}

/// The cells of the merged set: the owned cells of each piece, in piece
/// order or, when every piece has cell GlobalIds, in id order. A cell that
/// another piece already brought (the same points: overlapping pieces not
/// marked as ghosts) is taken once; a ghost cell maps to the owned cell with
/// its points. Returns, per piece, each cell's merged id (-1: none).
std::vector<std::vector<vtkIdType>> MergeCells(MergeInputs& in,
  const std::vector<std::vector<vtkIdType>>& local, vtkPointSet* merged)
{
  const std::vector<vtkPointSet*>& sets = in.Sets;
  auto* mergedGrid = vtkUnstructuredGrid::SafeDownCast(merged);
  auto* mergedPoly = vtkPolyData::SafeDownCast(merged);
  struct CellRef
  {
    size_t Piece;
    vtkIdType Id;
    double GlobalId;
  };
  std::vector<CellRef> ownedCells;
  std::vector<std::vector<vtkIdType>> cellMaps(sets.size());
  bool anyGhost = false;
  for (size_t r = 0; r < sets.size(); ++r)
  {
    vtkPointSet* s = sets[r];
    if (!s)
    {
      continue;
    }
    cellMaps[r].assign(static_cast<size_t>(s->GetNumberOfCells()), -1);
    if (in.InputIndex[r] < 0)
    {
      continue;
    }
    vtkUnsignedCharArray* ghosts = GhostCells(s);
    vtkDataArray* cellIds = in.UseCellGlobalIds ? s->GetCellData()->GetGlobalIds() : nullptr;
    for (vtkIdType c = 0; c < s->GetNumberOfCells(); ++c)
    {
      if (IsGhostCell(ghosts, c))
      {
        anyGhost = true;
        continue;
      }
      ownedCells.push_back({ r, c, cellIds ? cellIds->GetComponent(c, 0) : 0.0 });
    }
  }
  if (in.UseCellGlobalIds)
  {
    std::stable_sort(ownedCells.begin(), ownedCells.end(),
      [](const CellRef& a, const CellRef& b) { return a.GlobalId < b.GlobalId; });
  }
  // Only a cell whose every point is in more than one piece can be another
  // piece's cell too (an overlap, or a ghost's owner): only those are keyed
  // (the partition faces' cells: O(N^(2/3)) of N at 1M tets).
  const std::vector<char> shared = SharedPoints(local, merged->GetNumberOfPoints());
  auto allShared = [&shared](const std::vector<vtkIdType>& cell)
  {
    return std::all_of(cell.begin(), cell.end(),
      [&shared](vtkIdType i) { return i >= 0 && shared[static_cast<size_t>(i)]; });
  };
  std::unordered_map<std::string, vtkIdType> cellIndex;
  std::vector<size_t> cellPiece;
  std::vector<vtkIdType> ids;
  vtkNew<vtkIdList> cellPoints;
  TupleCopies copies(sets.size());
  for (const CellRef& cell : ownedCells)
  {
    vtkPointSet* s = sets[cell.Piece];
    MergedCellPoints(in, local, cell.Piece, cell.Id, cellPoints, ids);
    const int type = s->GetCellType(cell.Id);
    if (allShared(ids))
    {
      const auto known = cellIndex.emplace(CellKey(type, ids), merged->GetNumberOfCells());
      if (!known.second && cellPiece[static_cast<size_t>(known.first->second)] != cell.Piece)
      {
        cellMaps[cell.Piece][cell.Id] = known.first->second; // brought by another piece
        continue;
      }
    }
    const vtkIdType id = mergedGrid
      ? mergedGrid->InsertNextCell(type, static_cast<vtkIdType>(ids.size()), ids.data())
      : mergedPoly->InsertNextCell(type, static_cast<vtkIdType>(ids.size()), ids.data());
    copies.Add(cell.Piece, cell.Id, id);
    cellMaps[cell.Piece][cell.Id] = id;
    cellPiece.push_back(cell.Piece);
  }
  copies.Apply(in.CellFields, in, [](vtkPointSet* s) { return s->GetCellData(); },
    merged->GetCellData());
  for (size_t r = 0; anyGhost && r < sets.size(); ++r)
  {
    vtkPointSet* s = sets[r];
    vtkUnsignedCharArray* ghosts = in.InputIndex[r] < 0 ? nullptr : GhostCells(s);
    for (vtkIdType c = 0; ghosts && c < s->GetNumberOfCells(); ++c)
    {
      if (!IsGhostCell(ghosts, c))
      {
        continue;
      }
      MergedCellPoints(in, local, r, c, cellPoints, ids);
      const auto found = cellIndex.find(CellKey(s->GetCellType(c), ids));
      cellMaps[r][c] = found == cellIndex.end() ? -1 : found->second;
    }
  }
  return cellMaps;
}

/// Merge point-set pieces (vtkUnstructuredGrid or vtkPolyData) into one:
/// ghost cells dropped, shared points merged (see the header), the arrays
/// common to every non-empty piece kept (ghost arrays removed).
vtkSmartPointer<vtkDataObject> MergePointSets(const Pieces& pieces, PieceMaps* maps)
{
  MergeInputs in(pieces);
  if (maps)
  {
    maps->Points.assign(pieces.size(), {});
    maps->Cells.assign(pieces.size(), {});
  }
  if (!in.Prototype)
  {
    vtkSmartPointer<vtkDataObject> empty;
    empty.TakeReference(pieces.front()->NewInstance());
    return empty;
  }
  vtkSmartPointer<vtkPointSet> merged;
  merged.TakeReference(in.Prototype->NewInstance());
  vtkNew<vtkPoints> points;
  points->SetDataType(
    in.Prototype->GetPoints() ? in.Prototype->GetPoints()->GetDataType() : VTK_DOUBLE);
  points->Allocate(in.TotalPoints);
  merged->SetPoints(points);
  merged->GetPointData()->CopyAllocate(in.PointFields, in.TotalPoints);
  merged->GetCellData()->CopyAllocate(in.CellFields, in.TotalCells);
  if (auto* mergedGrid = vtkUnstructuredGrid::SafeDownCast(merged))
  {
    mergedGrid->Allocate(in.TotalCells);
  }
  else if (auto* mergedPoly = vtkPolyData::SafeDownCast(merged))
  {
    mergedPoly->AllocateEstimate(in.TotalCells, 4);
  }

  std::vector<std::vector<vtkIdType>> local = MergePoints(in, merged);
  std::vector<std::vector<vtkIdType>> cellMaps = MergeCells(in, local, merged);
  if (maps)
  {
    for (size_t r = 0; r < in.Sets.size(); ++r)
    {
      maps->Points[r] = in.Sets[r] ? std::move(local[r]) : std::vector<vtkIdType>();
      if (in.Sets[r] && maps->Points[r].empty())
      {
        maps->Points[r].assign(static_cast<size_t>(in.Sets[r]->GetNumberOfPoints()), -1);
      }
      maps->Cells[r] = std::move(cellMaps[r]);
    }
  }

  merged->GetPointData()->RemoveArray(vtkDataSetAttributes::GhostArrayName());
  merged->GetCellData()->RemoveArray(vtkDataSetAttributes::GhostArrayName());
  merged->GetPointData()->Squeeze();
  merged->GetCellData()->Squeeze();
  merged->GetFieldData()->ShallowCopy(in.Prototype->GetFieldData());
  return merged;
}

vtkSmartPointer<vtkDataObject> Merge(const Pieces& pieces, PieceMaps* maps, std::string& error);

/// Image pieces put together by their extents; one piece that spans all the
/// others' (every rank read the whole image: Assign's Volume mode asks for
/// it) is taken as it is.
vtkSmartPointer<vtkDataObject> MergeImages(const Pieces& pieces)
{
  vtkNew<vtkImageAppend> append;
  append->PreserveExtentsOn();
  vtkSmartPointer<vtkDataObject> only;
  int count = 0;
  int all[6] = { VTK_INT_MAX, VTK_INT_MIN, VTK_INT_MAX, VTK_INT_MIN, VTK_INT_MAX, VTK_INT_MIN };
  for (const auto& p : pieces)
  {
    auto* image = vtkImageData::SafeDownCast(p);
    if (image && image->GetNumberOfPoints() > 0)
    {
      append->AddInputData(image);
      only = p;
      ++count;
      const int* e = image->GetExtent();
      for (int k = 0; k < 3; ++k)
      {
        all[2 * k] = std::min(all[2 * k], e[2 * k]);
        all[2 * k + 1] = std::max(all[2 * k + 1], e[2 * k + 1]);
      }
    }
  }
  for (const auto& p : pieces)
  {
    auto* image = vtkImageData::SafeDownCast(p);
    if (count > 1 && image && image->GetNumberOfPoints() > 0 &&
      std::equal(all, all + 6, image->GetExtent()))
    {
      return p;
    }
  }
  if (count <= 1)
  {
    if (!only)
    {
      only.TakeReference(pieces.front()->NewInstance());
    }
    return only;
  }
  append->Update();
  vtkSmartPointer<vtkDataObject> merged = append->GetOutputDataObject(0);
  return merged;
}

/// Partitioned pieces: partitioned data set k of every rank (all its
/// partitions, whatever their number per rank) merged into one partition.
vtkSmartPointer<vtkDataObject> MergePartitioned(const Pieces& pieces, std::string& error)
{
  auto partitionsOf = [](vtkPartitionedDataSet* set, Pieces& parts) {
    for (unsigned int j = 0; set && j < set->GetNumberOfPartitions(); ++j)
    {
      if (vtkDataObject* part = set->GetPartitionAsDataObject(j))
      {
        parts.emplace_back(part);
      }
    }
  };
  if (auto* first = vtkPartitionedDataSetCollection::SafeDownCast(pieces.front()))
  {
    unsigned int count = 0;
    for (const auto& p : pieces)
    {
      auto* collection = vtkPartitionedDataSetCollection::SafeDownCast(p);
      if (!collection)
      {
        error = "the ranks' pieces are not all partitioned data set collections";
        return nullptr;
      }
      count = std::max(count, collection->GetNumberOfPartitionedDataSets());
    }
    auto merged = vtkSmartPointer<vtkPartitionedDataSetCollection>::New();
    merged->SetNumberOfPartitionedDataSets(count);
    for (unsigned int k = 0; k < count; ++k)
    {
      Pieces parts;
      for (const auto& p : pieces)
      {
        auto* collection = vtkPartitionedDataSetCollection::SafeDownCast(p);
        if (k < collection->GetNumberOfPartitionedDataSets())
        {
          partitionsOf(collection->GetPartitionedDataSet(k), parts);
        }
      }
      if (!parts.empty())
      {
        vtkSmartPointer<vtkDataObject> leaf = Merge(parts, nullptr, error);
        if (!leaf)
        {
          return nullptr;
        }
        merged->SetPartition(k, 0, leaf);
      }
      if (k < first->GetNumberOfPartitionedDataSets() && first->HasMetaData(k))
      {
        merged->GetMetaData(k)->Copy(first->GetMetaData(k));
      }
    }
    merged->SetDataAssembly(first->GetDataAssembly());
    return merged;
  }
  Pieces parts;
  for (const auto& p : pieces)
  {
    partitionsOf(vtkPartitionedDataSet::SafeDownCast(p), parts);
  }
  auto merged = vtkSmartPointer<vtkPartitionedDataSet>::New();
  if (!parts.empty())
  {
    vtkSmartPointer<vtkDataObject> leaf = Merge(parts, nullptr, error);
    if (!leaf)
    {
      return nullptr;
    }
    merged->SetPartition(0, leaf);
  }
  return merged;
}

/// Composite pieces merged leaf by leaf (every rank has the same structure).
vtkSmartPointer<vtkDataObject> MergeComposite(const Pieces& pieces, std::string& error)
{
  if (vtkPartitionedDataSetCollection::SafeDownCast(pieces.front()) ||
    vtkPartitionedDataSet::SafeDownCast(pieces.front()))
  {
    return MergePartitioned(pieces, error);
  }
  auto* structure = vtkCompositeDataSet::SafeDownCast(pieces.front());
  vtkSmartPointer<vtkCompositeDataSet> merged;
  merged.TakeReference(structure->NewInstance());
  merged->CopyStructure(structure);
  vtkSmartPointer<vtkCompositeDataIterator> it;
  it.TakeReference(structure->NewIterator());
  it->SkipEmptyNodesOff();
  for (it->InitTraversal(); !it->IsDoneWithTraversal(); it->GoToNextItem())
  {
    Pieces leaves;
    for (const auto& p : pieces)
    {
      auto* composite = vtkCompositeDataSet::SafeDownCast(p);
      if (!composite)
      {
        error = "the ranks' pieces are not all composite data";
        return nullptr;
      }
      vtkDataObject* leaf = composite->GetDataSet(it);
      if (leaf)
      {
        leaves.emplace_back(leaf);
      }
    }
    if (!leaves.empty())
    {
      vtkSmartPointer<vtkDataObject> leaf = Merge(leaves, nullptr, error);
      if (!leaf)
      {
        return nullptr;
      }
      merged->SetDataSet(it, leaf);
    }
  }
  return merged;
}

vtkSmartPointer<vtkDataObject> Merge(const Pieces& pieces, PieceMaps* maps, std::string& error)
{
  vtkDataObject* first = nullptr;
  for (const auto& p : pieces)
  {
    if (p && (!first || IsEmpty(first)))
    {
      first = p;
    }
  }
  if (!first)
  {
    return nullptr;
  }
  if (vtkPointSet::SafeDownCast(first))
  {
    Pieces sets;
    for (const auto& p : pieces)
    {
      sets.push_back(vtkPointSet::SafeDownCast(p) ? p : nullptr);
    }
    if (!sets.front())
    {
      sets.front().TakeReference(first->NewInstance());
    }
    return MergePointSets(sets, maps);
  }
  if (vtkImageData::SafeDownCast(first))
  {
    return MergeImages(pieces);
  }
  if (vtkCompositeDataSet::SafeDownCast(first))
  {
    return MergeComposite(pieces, error);
  }
  // Anything else (a table, ...): rank 0's, else the first non-empty one.
  return pieces.front() ? pieces.front() : vtkSmartPointer<vtkDataObject>(first);
}

/// Arrays of `from`, tuple i taken from tuple map[i] (0 where map[i] < 0).
void MapArrays(vtkDataSetAttributes* from, const std::vector<vtkIdType>& map, vtkFieldData* to)
{
  const vtkIdType n = static_cast<vtkIdType>(map.size());
  for (int a = 0; a < from->GetNumberOfArrays(); ++a)
  {
    vtkAbstractArray* source = from->GetAbstractArray(a);
    if (!source || !source->GetName())
    {
      continue;
    }
    vtkSmartPointer<vtkAbstractArray> mapped;
    mapped.TakeReference(source->NewInstance());
    mapped->SetName(source->GetName());
    mapped->SetNumberOfComponents(source->GetNumberOfComponents());
    mapped->SetNumberOfTuples(n);
    if (auto* numeric = vtkDataArray::SafeDownCast(mapped))
    {
      for (int c = 0; c < numeric->GetNumberOfComponents(); ++c)
      {
        numeric->FillComponent(c, 0.0);
      }
    }
    for (vtkIdType i = 0; i < n; ++i)
    {
      if (map[i] >= 0)
      {
        mapped->SetTuple(i, map[i], source);
      }
    }
    to->AddArray(mapped);
  }
}

/// The field array (a vtkStringArray in the scattered field data) that lists
/// the serial run's pass-through field arrays (PassThroughFieldArrays).
constexpr const char* PassThroughName = "vtkTranslucencyPassThroughFieldArrays";

/// On rank 0: the names of the field arrays that the serial run passed from
/// its (merged) input to its output unchanged (the same array object). The
/// merged input's field data is one piece's: such an array may mean
/// something per piece (Paint's PaintedCellIds number the piece's cells), so
/// every rank keeps its own input piece's (ApplyArrays).
std::vector<std::string> PassThroughFieldArrays(vtkDataObject* mergedInput, vtkDataObject* serialOutput)
{
  std::vector<std::string> names;
  vtkFieldData* in = mergedInput ? mergedInput->GetFieldData() : nullptr;
  vtkFieldData* out = serialOutput ? serialOutput->GetFieldData() : nullptr;
  for (int a = 0; in && out && a < out->GetNumberOfArrays(); ++a)
  {
    vtkAbstractArray* array = out->GetAbstractArray(a);
    const char* name = array ? array->GetName() : nullptr;
    if (name && in->GetAbstractArray(name) == array)
    {
      names.emplace_back(name);
    }
  }
  return names;
}

/// Replace the output piece's arrays by the scattered ones. Field data: the
/// serial result's, but a pass-through array (PassThroughName's list) is the
/// piece's own when the piece has one.
void ApplyArrays(
  vtkDataSet* output, vtkTable* pointArrays, vtkTable* cellArrays, vtkDataObject* piece)
{
  vtkFieldData* pointData = pointArrays->GetRowData();
  for (int a = 0; a < pointData->GetNumberOfArrays(); ++a)
  {
    output->GetPointData()->AddArray(pointData->GetAbstractArray(a));
  }
  vtkFieldData* cellData = cellArrays->GetRowData();
  for (int a = 0; a < cellData->GetNumberOfArrays(); ++a)
  {
    output->GetCellData()->AddArray(cellData->GetAbstractArray(a));
  }
  // A field data object of its own (the shallow copy shares the input's).
  vtkNew<vtkFieldData> fieldData;
  fieldData->ShallowCopy(pointArrays->GetFieldData());
  auto* passThrough = vtkStringArray::SafeDownCast(fieldData->GetAbstractArray(PassThroughName));
  vtkFieldData* own = piece ? piece->GetFieldData() : nullptr;
  for (vtkIdType k = 0; passThrough && own && k < passThrough->GetNumberOfValues(); ++k)
  {
    if (vtkAbstractArray* mine = own->GetAbstractArray(passThrough->GetValue(k).c_str()))
    {
      fieldData->AddArray(mine);
    }
  }
  fieldData->RemoveArray(PassThroughName);
  output->SetFieldData(fieldData);
}

/// The body of a captured error message: the text after "<Class> (0x...): ".
std::string MessageBody(const std::string& text)
{
  std::string body = text;
  const size_t at = body.find("): ");
  if (at != std::string::npos)
  {
    body = body.substr(at + 3);
  }
  while (!body.empty() && (body.back() == '\n' || body.back() == ' '))
  {
    body.pop_back();
  }
  return body;
}

void CaptureError(vtkObject*, unsigned long, void* clientData, void* callData)
{
  auto* messages = static_cast<std::string*>(clientData);
  if (callData && messages->empty())
  {
    *messages = MessageBody(static_cast<const char*>(callData));
  }
}
/// Step 1 of RunGathered: every input port's pieces to rank 0, or to every
/// rank if `toEveryRank` (an unconnected port on every rank is skipped).
/// `local`: this rank's piece per port (an empty grid for a rank without one).
void GatherInputs(vtkMultiProcessController* controller, int numInputs,
  vtkInformationVector** inputVector, std::vector<Pieces>& gathered,
  std::vector<vtkSmartPointer<vtkDataObject>>& local, bool toEveryRank)
{
  gathered.assign(static_cast<size_t>(numInputs), {});
  local.assign(static_cast<size_t>(numInputs), nullptr);
  for (int port = 0; port < numInputs; ++port)
  {
    vtkDataObject* in = inputVector[port]->GetNumberOfInformationObjects() > 0
      ? vtkDataObject::GetData(inputVector[port], 0)
      : nullptr;
    int present = in ? 1 : 0, anyPresent = 0;
    controller->AllReduce(&present, &anyPresent, 1, vtkCommunicator::MAX_OP);
    if (!anyPresent)
    {
      continue;
    }
    local[port] = in;
    if (!in)
    {
      local[port] = vtkSmartPointer<vtkUnstructuredGrid>::New();
    }
    if (toEveryRank)
    {
      controller->AllGather(local[port], gathered[port]);
    }
    else
    {
      controller->Gather(local[port], gathered[port], 0);
    }
  }
}

/// On rank 0: the merged inputs as the serial RequestData's input
/// information vectors (one per port; empty for a skipped port). Returns
/// false with `error` set when a port's pieces cannot be merged.
bool MergeInputVectors(vtkInformationVector** inputVector, const std::vector<Pieces>& gathered,
  PieceMaps& maps, std::vector<vtkSmartPointer<vtkInformationVector>>& inputs,
  std::string& error)
{
  for (size_t port = 0; port < gathered.size(); ++port)
  {
    auto vector = vtkSmartPointer<vtkInformationVector>::New();
    if (!gathered[port].empty())
    {
      vtkSmartPointer<vtkDataObject> merged =
        Merge(gathered[port], port == 0 ? &maps : nullptr, error);
      if (!merged)
      {
        error = "cannot gather the pieces of input " + std::to_string(port) + " to one rank" +
          (error.empty() ? std::string() : ": " + error);
        return false;
      }
      vtkNew<vtkInformation> info;
      if (inputVector[port]->GetNumberOfInformationObjects() > 0)
      {
        info->Copy(inputVector[port]->GetInformationObject(0));
      }
      info->Set(vtkDataObject::DATA_OBJECT(), merged);
      vector->Append(info);
    }
    inputs.push_back(vector);
  }
  return true;
}

/// On rank 0: the filter's serial RequestData on the merged `inputs`, into
/// new instances of the real outputs (`serialOutputs`), alone (every filter
/// run here sees a communicator of size one). The filter's errors are
/// captured into `error` (reported on every rank by the caller). Returns the
/// serial path's status.
int RunSerialAlone(vtkAlgorithm* self, vtkInformation* request,
  std::vector<vtkSmartPointer<vtkInformationVector>>& inputs, vtkInformationVector* outputVector,
  const SerialRequest& serial, std::vector<vtkSmartPointer<vtkDataObject>>& serialOutputs,
  std::string& error, const vtkTranslucencyCommunicator& replicated)
{
  std::vector<vtkInformationVector*> inputPointers;
  for (auto& vector : inputs)
  {
    inputPointers.push_back(vector);
  }
  vtkNew<vtkInformationVector> outputs;
  for (int port = 0; port < outputVector->GetNumberOfInformationObjects(); ++port)
  {
    vtkInformation* realInfo = outputVector->GetInformationObject(port);
    vtkNew<vtkInformation> info;
    info->Copy(realInfo);
    vtkDataObject* real = realInfo->Get(vtkDataObject::DATA_OBJECT());
    serialOutputs[port].TakeReference(real->NewInstance());
    info->Set(vtkDataObject::DATA_OBJECT(), serialOutputs[port]);
    outputs->Append(info);
  }
  vtkNew<vtkCallbackCommand> capture;
  capture->SetCallback(CaptureError);
  capture->SetClientData(&error);
  const unsigned long observer = self->AddObserver(vtkCommand::ErrorEvent, capture);
  int status = 0;
  try
  {
    const vtkTranslucencyCommunicator::LocalScope alone;
    const vtkTranslucencyCommunicator::ReplicatedScope sharing(replicated);
    status = serial(request, inputPointers.data(), outputs);
  }
  catch (const std::exception& e)
  {
    status = 0;
    if (error.empty())
    {
      error = e.what();
    }
  }
  self->RemoveObserver(observer);
  return status;
}

/// SameMesh's check on rank 0: the first output must be the merged input's
/// mesh (same numbers of points and cells); else it stays on rank 0.
GatherMode CheckSameMesh(GatherMode mode, const std::vector<Pieces>& gathered,
  const std::vector<vtkSmartPointer<vtkInformationVector>>& inputs, vtkDataObject* serialOutput)
{
  if (mode != GatherMode::SameMesh)
  {
    return mode;
  }
  auto* out = vtkDataSet::SafeDownCast(serialOutput);
  auto* in = gathered[0].empty()
    ? nullptr
    : vtkDataSet::SafeDownCast(
        inputs[0]->GetInformationObject(0)->Get(vtkDataObject::DATA_OBJECT()));
  if (!out || !in || out->GetNumberOfPoints() != in->GetNumberOfPoints() ||
    out->GetNumberOfCells() != in->GetNumberOfCells())
  {
    return GatherMode::RankZero;
  }
  return mode;
}

/// SameMesh, output port 0: every rank's own piece gets the serial output's
/// arrays mapped to its points and cells (rank 0 sends, the others receive).
void ScatterArrays(vtkMultiProcessController* controller, vtkDataObject* piece,
  vtkDataObject* serialOutput, const PieceMaps& maps, const std::vector<std::string>& passThrough,
  vtkDataObject* out)
{
  const int rank = controller->GetLocalProcessId();
  auto* outSet = vtkDataSet::SafeDownCast(out);
  if (rank != 0)
  {
    vtkNew<vtkTable> pointArrays, cellArrays;
    controller->Receive(pointArrays, 0, PointArraysTag);
    controller->Receive(cellArrays, 0, CellArraysTag);
    outSet->ShallowCopy(piece);
    ApplyArrays(outSet, pointArrays, cellArrays, piece);
    return;
  }
  vtkNew<vtkStringArray> passThroughNames;
  passThroughNames->SetName(PassThroughName);
  for (const std::string& name : passThrough)
  {
    passThroughNames->InsertNextValue(name);
  }
  auto* serialOut = vtkDataSet::SafeDownCast(serialOutput);
  for (int r = controller->GetNumberOfProcesses() - 1; r >= 0; --r) // rank 0's last: its own
  {
    vtkNew<vtkTable> pointArrays, cellArrays;
    MapArrays(serialOut->GetPointData(), maps.Points[r], pointArrays->GetRowData());
    MapArrays(serialOut->GetCellData(), maps.Cells[r], cellArrays->GetRowData());
    pointArrays->GetFieldData()->ShallowCopy(serialOut->GetFieldData());
    pointArrays->GetFieldData()->AddArray(passThroughNames);
    if (r > 0)
    {
      controller->Send(pointArrays, r, PointArraysTag);
      controller->Send(cellArrays, r, CellArraysTag);
    }
    else
    {
      outSet->ShallowCopy(vtkDataSet::SafeDownCast(piece));
      ApplyArrays(outSet, pointArrays, cellArrays, piece);
    }
  }
}
} // namespace

//------------------------------------------------------------------------------
int RunGathered(vtkAlgorithm* self, vtkInformation* request, vtkInformationVector** inputVector,
  vtkInformationVector* outputVector, GatherMode mode, const SerialRequest& serial,
  const vtkTranslucencyCommunicator& comm, bool replicate)
{
  vtkMultiProcessController* controller = comm.GetController();
  const int rank = controller->GetLocalProcessId();
  const int numOutputs = self->GetNumberOfOutputPorts();

  // 1. Every input port's pieces to rank 0 (to every rank when replicated).
  std::vector<Pieces> gathered;
  std::vector<vtkSmartPointer<vtkDataObject>> local;
  GatherInputs(controller, self->GetNumberOfInputPorts(), inputVector, gathered, local, replicate);

  // 2. Rank 0 merges and runs the filter's serial RequestData.
  int status = 1;
  std::string error;
  PieceMaps maps;
  std::vector<std::string> passThrough; // rank 0: PassThroughFieldArrays
  std::vector<vtkSmartPointer<vtkDataObject>> serialOutputs(static_cast<size_t>(numOutputs));
  std::vector<vtkSmartPointer<vtkInformationVector>> inputs;
  if (replicate)
  {
    // 2'. Every rank merges the same pieces and runs the serial path
    // (sharing its work over the ranks); a failure anywhere is agreed.
    status = MergeInputVectors(inputVector, gathered, maps, inputs, error);
    const std::string merged = comm.AgreeOnError(status ? std::string() : error);
    if (status && !merged.empty())
    {
      status = 0;
      error = merged;
    }
    if (status)
    {
      status = RunSerialAlone(
        self, request, inputs, outputVector, serial, serialOutputs, error, comm);
      const std::string agreed =
        comm.AgreeOnError(status ? std::string() : error.empty() ? "failed" : error);
      if (status && !agreed.empty())
      {
        status = 0;
        error = agreed; // another rank's ("rank r: ...")
      }
    }
  }
  if (rank == 0 && !replicate)
  {
    status = MergeInputVectors(inputVector, gathered, maps, inputs, error) &&
      RunSerialAlone(self, request, inputs, outputVector, serial, serialOutputs, error,
        vtkTranslucencyCommunicator::Self());
  }
  if (rank == 0)
  {
    if (status)
    {
      mode = CheckSameMesh(mode, gathered, inputs, serialOutputs[0]);
      if (!gathered[0].empty())
      {
        passThrough = PassThroughFieldArrays(
          inputs[0]->GetInformationObject(0)->Get(vtkDataObject::DATA_OBJECT()),
          serialOutputs[0]);
      }
    }
  }

  // 3. The outcome, the same on every rank.
  vtkMultiProcessStream stream;
  if (rank == 0)
  {
    stream << status << static_cast<int>(mode) << error;
  }
  controller->Broadcast(stream, 0);
  int modeValue = 0;
  stream >> status >> modeValue >> error;
  mode = static_cast<GatherMode>(modeValue);
  if (!status)
  {
    for (int port = 0; port < numOutputs; ++port)
    {
      if (vtkDataObject* out = vtkDataObject::GetData(outputVector, port))
      {
        out->Initialize();
      }
    }
    if (!error.empty())
    {
      vtkErrorWithObjectMacro(self, << error);
    }
    return 0;
  }

  // 4. The outputs: arrays back to every rank's own piece (SameMesh, port
  // 0), else the serial output on rank 0 and empty outputs on the others.
  for (int port = 0; port < numOutputs; ++port)
  {
    vtkDataObject* out = vtkDataObject::GetData(outputVector, port);
    if (port == 0 && mode == GatherMode::SameMesh)
    {
      ScatterArrays(controller, local[0], serialOutputs[0], maps, passThrough, out);
    }
    else if (rank == 0)
    {
      out->ShallowCopy(serialOutputs[port]);
    }
    else
    {
      out->Initialize();
    }
  }
  return 1;
}
}
