#include "vtkTranslucencyMeshConversion.h"

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
#include <vtkSMPTools.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>

#include <cmath>
#include <deque>
#include <mutex>
#include <sstream>

namespace vtkTranslucency
{

bool ToTetMesh(vtkUnstructuredGrid* grid, translucency::TetMesh& mesh, std::string& error)
{
  if (!grid || grid->GetNumberOfPoints() == 0 || grid->GetNumberOfCells() == 0)
  {
    error = "the input mesh is empty (no points or no cells)";
    return false;
  }
  const vtkIdType numPoints = grid->GetNumberOfPoints();
  const vtkIdType numCells = grid->GetNumberOfCells();
  std::vector<double> points(3 * static_cast<size_t>(numPoints));
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
  std::vector<int> tets(4 * static_cast<size_t>(numCells));
  vtkUnsignedCharArray* types = grid->GetCellTypesArray();
  vtkCellArray* cells = grid->GetCells();
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
  }
  vtkSMPTools::For(0, numCells, [&](vtkIdType begin, vtkIdType end) {
    vtkIdType npts;
    const vtkIdType* ids;
    auto it = vtk::TakeSmartPointer(cells->NewIterator());
    for (vtkIdType c = begin; c < end; ++c)
    {
      it->GetCellAtId(c, npts, ids);
      for (int k = 0; k < 4; ++k)
      {
        tets[4 * c + k] = static_cast<int>(ids[k]);
      }
    }
  });
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

vtkDataArray* NewTripleArray(const char* name, const std::vector<double>& values)
{
  vtkDoubleArray* array = vtkDoubleArray::New();
  array->SetName(name);
  array->SetNumberOfComponents(3);
  array->SetNumberOfTuples(static_cast<vtkIdType>(values.size() / 3));
  std::copy(values.begin(), values.end(), array->GetPointer(0));
  return array;
}

std::shared_ptr<const translucency::TetMesh> AcquireTetMesh(
  vtkUnstructuredGrid* grid, std::string& error, bool* built)
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
  if (!ToTetMesh(grid, *mesh, error))
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
