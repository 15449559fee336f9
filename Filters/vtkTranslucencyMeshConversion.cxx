#include "vtkTranslucencyMeshConversion.h"

#include "vtkTranslucencyGhosts.h"

#include "Error.h"

#include <vtkCellArray.h>
#include <vtkCellArrayIterator.h>
#include <vtkCellData.h>
#include <vtkCellTypes.h>
#include <vtkDataArray.h>
#include <vtkDataSetAttributes.h>
#include <vtkDoubleArray.h>
#include <vtkIdTypeArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSMPTools.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <deque>
#include <mutex>
#include <sstream>

namespace vtkTranslucency
{

namespace
{
/// A warning naming coincident points that both carry tets (at most five
/// pairs), or "" if there is none.
std::string CoincidentPointsWarning(
  const std::vector<double>& points, const std::vector<int>& tets, vtkIdType numPoints)
{
  std::vector<char> used(static_cast<size_t>(numPoints), 0);
  for (int id : tets)
  {
    used[id] = 1;
  }
  std::vector<int> order;
  for (vtkIdType i = 0; i < numPoints; ++i)
  {
    if (used[i])
    {
      order.push_back(static_cast<int>(i));
    }
  }
  auto less = [&](int a, int b) {
    for (int k = 0; k < 3; ++k)
    {
      if (points[3 * a + k] != points[3 * b + k])
      {
        return points[3 * a + k] < points[3 * b + k];
      }
    }
    return a < b;
  };
  std::sort(order.begin(), order.end(), less);
  std::ostringstream os;
  size_t pairs = 0;
  for (size_t i = 1; i < order.size(); ++i)
  {
    const int a = order[i - 1], b = order[i];
    if (points[3 * a] == points[3 * b] && points[3 * a + 1] == points[3 * b + 1] &&
      points[3 * a + 2] == points[3 * b + 2])
    {
      if (pairs < 5)
      {
        os << (pairs ? ", " : "") << a << " and " << b << " at (" << points[3 * a] << ", "
           << points[3 * a + 1] << ", " << points[3 * a + 2] << ")";
      }
      ++pairs;
    }
  }
  if (pairs == 0)
  {
    return std::string();
  }
  std::ostringstream msg;
  msg << pairs << " pair(s) of coincident points both carry tets (points " << os.str()
      << (pairs > 5 ? ", ..." : "")
      << "): the mesh is cracked there and the crack is treated as boundary; merge the points "
         "(e.g. vtkStaticCleanUnstructuredGrid) unless the crack is intended";
  return msg.str();
}
} // namespace

bool CheckSurfacePointsAndIds(vtkPolyData* input, double maxCoordinate, std::string& error)
{
  const double limit = maxCoordinate;
  const vtkIdType np = input->GetNumberOfPoints();
  for (vtkIdType i = 0; i < np; ++i)
  {
    double p[3];
    input->GetPoints()->GetPoint(i, p);
    for (int k = 0; k < 3; ++k)
    {
      if (!std::isfinite(p[k]))
      {
        error = "point " + std::to_string(i) + " has the non-finite coordinate " +
          std::string(1, "xyz"[k]) + " = " + std::to_string(p[k]);
        return false;
      }
      if (std::abs(p[k]) >= limit)
      {
        std::ostringstream os;
        os << "point " << i << " has the coordinate " << "xyz"[k] << " = " << p[k]
           << " mm, beyond the supported magnitude " << limit << " mm";
        error = os.str();
        return false;
      }
    }
  }
  vtkCellArray* arrays[4] = { input->GetVerts(), input->GetLines(), input->GetPolys(),
    input->GetStrips() };
  const char* kinds[4] = { "vertex cell", "line", "polygon", "triangle strip" };
  vtkIdType cellId = 0;
  for (int a = 0; a < 4; ++a)
  {
    vtkCellArray* cells = arrays[a];
    if (!cells)
    {
      continue;
    }
    vtkDataArray* offsets = cells->GetOffsetsArray();
    vtkDataArray* connectivity = cells->GetConnectivityArray();
    const vtkIdType numOffsets = offsets ? offsets->GetNumberOfValues() : 0;
    const vtkIdType numIds = connectivity ? connectivity->GetNumberOfValues() : 0;
    if (numOffsets == 0)
    {
      continue;
    }
    if (offsets->GetNumberOfComponents() != 1 || connectivity->GetNumberOfComponents() != 1 ||
      offsets->GetComponent(0, 0) != 0 ||
      offsets->GetComponent(numOffsets - 1, 0) != static_cast<double>(numIds))
    {
      error = std::string("the ") + kinds[a] + " cell array is inconsistent (its offsets do not "
        "start at 0 and end at the connectivity's size)";
      return false;
    }
    double previous = 0;
    for (vtkIdType c = 0; c + 1 < numOffsets; ++c, ++cellId)
    {
      const double end = offsets->GetComponent(c + 1, 0);
      if (!(end >= previous) || end > static_cast<double>(numIds))
      {
        error = "cell " + std::to_string(cellId) + " (" + kinds[a] + ") has the offset " +
          std::to_string(end) + " out of order";
        return false;
      }
      for (vtkIdType k = static_cast<vtkIdType>(previous); k < static_cast<vtkIdType>(end); ++k)
      {
        const double id = connectivity->GetComponent(k, 0);
        if (!(id >= 0) || !(id < static_cast<double>(np)))
        {
          std::ostringstream os;
          // Ids are read as doubles: print them as whole numbers.
          os << kinds[a] << " " << c << " uses point id " << std::fixed << std::setprecision(0)
             << id << ", out of range [0, " << np << ") (cell " << cellId << ")";
          error = os.str();
          return false;
        }
      }
      previous = end;
    }
  }
  return true;
}

std::vector<vtkIdType> OwnedTets(
  vtkUnstructuredGrid* grid, const std::vector<int>& cells, std::vector<int>& tets)
{
  const vtkIdType numCells = grid ? grid->GetNumberOfCells() : 0;
  vtkUnsignedCharArray* ghosts = numCells > 0 ? vtkTranslucency::GhostCells(grid) : nullptr;
  std::vector<vtkIdType> kept;
  for (vtkIdType c = 0; c < numCells; ++c)
  {
    if (!vtkTranslucency::IsGhostCell(ghosts, c))
    {
      kept.push_back(c);
      tets.insert(tets.end(), cells.begin() + 4 * c, cells.begin() + 4 * c + 4);
    }
  }
  return kept;
}

bool ToTetArrays(vtkUnstructuredGrid* grid, std::vector<double>& points, std::vector<int>& tets,
  std::string& error)
{
  if (!grid)
  {
    error = "no input mesh";
    return false;
  }
  const vtkIdType numPoints = grid->GetNumberOfPoints(); // 0 without vtkPoints
  const vtkIdType numCells = grid->GetNumberOfCells();
  points.assign(3 * static_cast<size_t>(numPoints), 0.0);
  if (numPoints > 0)
  {
    vtkDataArray* coords = grid->GetPoints()->GetData();
    vtkSMPTools::For(0, numPoints, [&](vtkIdType begin, vtkIdType end) {
      for (vtkIdType i = begin; i < end; ++i)
      {
        for (int k = 0; k < 3; ++k)
        {
          points[3 * i + k] = coords->GetComponent(i, k);
        }
      }
    });
  }
  for (vtkIdType i = 0; i < numPoints; ++i)
  {
    if (!std::isfinite(points[3 * i]) || !std::isfinite(points[3 * i + 1]) ||
      !std::isfinite(points[3 * i + 2]))
    {
      std::ostringstream os;
      os << "point " << i << " has a non-finite coordinate (" << points[3 * i] << ", "
         << points[3 * i + 1] << ", " << points[3 * i + 2] << ")";
      error = os.str();
      return false;
    }
  }
  if (numPoints > std::numeric_limits<int>::max() ||
    numCells > std::numeric_limits<int>::max() / 4)
  {
    error = "the input mesh has too many points or cells for 32-bit point ids";
    return false;
  }
  tets.assign(4 * static_cast<size_t>(numCells), 0);
  vtkUnsignedCharArray* types = grid->GetCellTypesArray();
  vtkCellArray* cells = grid->GetCells();
  if (!types || !cells || types->GetNumberOfTuples() < numCells ||
    cells->GetNumberOfCells() < numCells)
  {
    error = "the input mesh's cell arrays are inconsistent (fewer cell types or cells than "
            "NumberOfCells)";
    return false;
  }
  // Every cell is checked (type, number of points, point ids) before its ids
  // are read: a short cell must not shift the ids of the next ones.
  vtkIdType npts;
  const vtkIdType* ids;
  auto it = vtk::TakeSmartPointer(cells->NewIterator());
  for (vtkIdType c = 0; c < numCells; ++c)
  {
    if (types->GetValue(c) != VTK_TETRA)
    {
      std::ostringstream os;
      os << "cell " << c << " is a " << vtkCellTypes::GetClassNameFromTypeId(types->GetValue(c))
         << ", not a linear tetrahedron: tetrahedralize the input first "
            "(vtkTetrahedralizeSurface on its surface, or vtkDataSetTriangleFilter)";
      error = os.str();
      return false;
    }
    it->GetCellAtId(c, npts, ids);
    if (npts != 4)
    {
      std::ostringstream os;
      os << "cell " << c << " is a tetrahedron with " << npts << " point ids; a tetrahedron has 4";
      error = os.str();
      return false;
    }
    for (int k = 0; k < 4; ++k)
    {
      if (ids[k] < 0 || ids[k] >= numPoints)
      {
        std::ostringstream os;
        os << "cell " << c << " uses point id " << ids[k] << ", outside [0, " << numPoints - 1
           << "]";
        error = os.str();
        return false;
      }
      tets[4 * c + k] = static_cast<int>(ids[k]);
    }
  }
  return true;
}

bool ToTetMesh(
  vtkUnstructuredGrid* grid, translucency::TetMesh& mesh, std::string& error, std::string* warning)
{
  if (!grid || grid->GetNumberOfPoints() == 0 || grid->GetNumberOfCells() == 0)
  {
    error = "the input mesh is empty (no points or no cells)";
    return false;
  }
  std::vector<double> points;
  std::vector<int> tets;
  if (!ToTetArrays(grid, points, tets, error))
  {
    return false;
  }
  const vtkIdType numPoints = grid->GetNumberOfPoints();
  if (warning)
  {
    *warning = CoincidentPointsWarning(points, tets, numPoints);
  }
  try
  {
    mesh.SetGeometry(std::move(points), std::move(tets));
  }
  catch (const translucency::Error& e)
  {
    error = e.what();
    return false;
  }
  return true;
}

namespace
{
/// Copy array `name` of `attributes` (cell or point data, `kind` names it in
/// messages) into `values`, checking presence and number of components.
bool ReadArray(vtkDataSetAttributes* attributes, const char* kind, const char* name,
  int components, std::vector<double>& values, std::string& error)
{
  vtkDataArray* array = attributes->GetArray(name);
  if (!array)
  {
    error = std::string("the input has no ") + kind + " array '" + name + "'";
    return false;
  }
  if (array->GetNumberOfComponents() != components)
  {
    std::ostringstream os;
    os << kind << " array '" << name << "' has " << array->GetNumberOfComponents()
       << " components; expected " << components;
    error = os.str();
    return false;
  }
  const vtkIdType n = array->GetNumberOfTuples();
  values.resize(static_cast<size_t>(n) * components);
  if (vtkDoubleArray* doubles = vtkDoubleArray::FastDownCast(array))
  {
    // The arrays the filters write (contiguous doubles): one copy, no
    // virtual call per value (7M of them for a 1M-tet material).
    const double* source = doubles->GetPointer(0);
    vtkSMPTools::For(0, n, [&](vtkIdType begin, vtkIdType end) {
      std::copy(source + components * begin, source + components * end,
        values.data() + components * begin);
    });
    return true;
  }
  vtkSMPTools::For(0, n, [&](vtkIdType begin, vtkIdType end) {
    for (vtkIdType i = begin; i < end; ++i)
    {
      for (int k = 0; k < components; ++k)
      {
        values[components * i + k] = array->GetComponent(i, k);
      }
    }
  });
  return true;
}

bool ReadCellArray(vtkUnstructuredGrid* grid, const char* name, int components,
  std::vector<double>& values, std::string& error)
{
  if (!ReadArray(grid->GetCellData(), "cell", name, components, values, error))
  {
    if (!grid->GetCellData()->GetArray(name))
    {
      error += ": assign coefficients first (vtkAssignScatteringCoefficients)";
    }
    return false;
  }
  return true;
}
}

bool ToOpticalProperties(
  vtkUnstructuredGrid* grid, translucency::OpticalProperties& material, std::string& error)
{
  if (!ReadCellArray(grid, AbsorptionName, 3, material.AbsorptionCoefficient, error) ||
    !ReadCellArray(grid, ScatteringName, 3, material.ReducedScatteringCoefficient, error) ||
    !ReadCellArray(grid, RefractiveIndexName, 1, material.RefractiveIndex, error))
  {
    return false;
  }
  try
  {
    material.Validate(static_cast<int>(grid->GetNumberOfCells()));
  }
  catch (const translucency::Error& e)
  {
    error = e.what();
    return false;
  }
  return true;
}

CoefficientValues CoefficientArraysInPlace(vtkUnstructuredGrid* grid, vtkIdType tuples)
{
  auto values = [&](const char* name, int components) -> const double* {
    vtkDoubleArray* array =
      grid ? vtkDoubleArray::FastDownCast(grid->GetCellData()->GetArray(name)) : nullptr;
    if (!array || array->GetNumberOfComponents() != components ||
      array->GetNumberOfTuples() != tuples || tuples == 0)
    {
      return nullptr;
    }
    return array->GetPointer(0);
  };
  return { values(AbsorptionName, 3), values(ScatteringName, 3), values(RefractiveIndexName, 1) };
}

bool ReadPointArray(vtkUnstructuredGrid* grid, const char* name, int components,
  std::vector<double>& values, std::string& error)
{
  return ReadArray(grid->GetPointData(), "point", name, components, values, error);
}

bool ReadRefractiveIndex(vtkUnstructuredGrid* grid, std::vector<double>& values, std::string& error)
{
  if (!ReadCellArray(grid, RefractiveIndexName, 1, values, error))
  {
    return false;
  }
  for (size_t t = 0; t < values.size(); ++t)
  {
    if (!(values[t] > 0.0) || !std::isfinite(values[t]))
    {
      std::ostringstream os;
      os << "RefractiveIndex of tet " << t << " is " << values[t] << ": must be finite and > 0";
      error = os.str();
      return false;
    }
  }
  return true;
}

void SetTets(vtkUnstructuredGrid* grid, const std::vector<int>& tets)
{
  const vtkIdType numTets = static_cast<vtkIdType>(tets.size() / 4);
  vtkNew<vtkIdTypeArray> offsets;
  vtkNew<vtkIdTypeArray> connectivity;
  offsets->SetNumberOfTuples(numTets + 1);
  connectivity->SetNumberOfTuples(4 * numTets);
  for (vtkIdType t = 0; t <= numTets; ++t)
  {
    offsets->SetValue(t, 4 * t);
  }
  for (vtkIdType k = 0; k < 4 * numTets; ++k)
  {
    connectivity->SetValue(k, tets[k]);
  }
  vtkNew<vtkCellArray> cells;
  cells->SetData(offsets, connectivity);
  grid->SetCells(VTK_TETRA, cells);
}

//------------------------------------------------------------------------------
void CopyAttributes(vtkDataSetAttributes* in, vtkDataSetAttributes* out,
  const std::vector<int>& kept, const char* name)
{
  vtkDataArray* previous = in->GetArray(name);
  const vtkIdType n = static_cast<vtkIdType>(kept.size());
  out->CopyAllocate(in, n);
  for (vtkIdType k = 0; k < n; ++k)
  {
    out->CopyData(in, kept[k], k);
  }
  out->RemoveArray(name);
  vtkNew<vtkIdTypeArray> ids;
  ids->SetName(name);
  ids->SetNumberOfTuples(n);
  for (vtkIdType k = 0; k < n; ++k)
  {
    ids->SetValue(k,
      previous ? static_cast<vtkIdType>(previous->GetComponent(kept[k], 0)) : kept[k]);
  }
  out->AddArray(ids);
}

void SetRGBComponentNames(vtkDataArray* array)
{
  static const char* const names[3] = { "R", "G", "B" };
  for (int c = 0; c < 3; ++c)
  {
    array->SetComponentName(c, names[c]);
  }
}

vtkDataArray* NewTripleArray(const char* name, const std::vector<double>& values)
{
  vtkDoubleArray* array = vtkDoubleArray::New();
  array->SetName(name);
  array->SetNumberOfComponents(3);
  SetRGBComponentNames(array);
  array->SetNumberOfTuples(static_cast<vtkIdType>(values.size() / 3));
  std::copy(values.begin(), values.end(), array->GetPointer(0));
  return array;
}

std::shared_ptr<const translucency::TetMesh> AcquireTetMesh(
  vtkUnstructuredGrid* grid, std::string& error, bool* built, std::string* warning)
{
  if (built)
  {
    *built = false;
  }
  if (!grid || !grid->GetPoints() || !grid->GetCells())
  {
    error = "the input mesh is empty (no points or no cells)";
    return nullptr;
  }
  std::ostringstream os;
  os << static_cast<const void*>(grid->GetPoints()) << ':' << grid->GetPoints()->GetMTime() << ':'
     << grid->GetPoints()->GetData()->GetMTime() << ':' << static_cast<const void*>(grid->GetCells())
     << ':' << grid->GetCells()->GetMTime() << ':' << grid->GetNumberOfPoints() << ':'
     << grid->GetNumberOfCells();
  const std::string key = os.str();

  static std::mutex mutex;
  static std::deque<std::pair<std::string, std::shared_ptr<const translucency::TetMesh>>> cache;
  {
    std::lock_guard<std::mutex> lock(mutex);
    for (const auto& entry : cache)
    {
      if (entry.first == key)
      {
        return entry.second;
      }
    }
  }
  auto mesh = std::make_shared<translucency::TetMesh>();
  if (!ToTetMesh(grid, *mesh, error, warning))
  {
    return nullptr;
  }
  if (built)
  {
    *built = true;
  }
  std::lock_guard<std::mutex> lock(mutex);
  cache.emplace_front(key, mesh);
  if (cache.size() > 4)
  {
    cache.pop_back();
  }
  return mesh;
}

}
