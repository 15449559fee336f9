#include "MeshIO.h"
#include "Utilities.h"

#include "Error.h"

#include "vtkTetGenReader.h"

#include <vtkAlgorithm.h>
#include <vtkOBJReader.h>
#include <vtkPLYReader.h>
#include <vtkPolyData.h>
#include <vtkSTLReader.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <fstream>

namespace translucency_app
{

/// Read a surface or tet mesh. Returns a polydata (to tetrahedralize) or a grid.
bool ReadMesh(const std::string& path, vtkSmartPointer<vtkPolyData>& surface,
  vtkSmartPointer<vtkUnstructuredGrid>& grid, std::string& error)
{
  std::ifstream probe(path);
  if (!probe)
  {
    error = "cannot open mesh file '" + path + "'";
    return false;
  }
  const std::string ext = Extension(path);
  MessageCollector messages;
  vtkSmartPointer<vtkAlgorithm> reader;
  if (ext == "ply")
  {
    auto r = vtkSmartPointer<vtkPLYReader>::New();
    r->SetFileName(path.c_str());
    reader = r;
  }
  else if (ext == "stl")
  {
    auto r = vtkSmartPointer<vtkSTLReader>::New();
    r->SetFileName(path.c_str());
    reader = r;
  }
  else if (ext == "obj")
  {
    auto r = vtkSmartPointer<vtkOBJReader>::New();
    r->SetFileName(path.c_str());
    reader = r;
  }
  else if (ext == "vtp")
  {
    auto r = vtkSmartPointer<vtkXMLPolyDataReader>::New();
    r->SetFileName(path.c_str());
    reader = r;
  }
  else if (ext == "vtu")
  {
    auto r = vtkSmartPointer<vtkXMLUnstructuredGridReader>::New();
    r->SetFileName(path.c_str());
    reader = r;
  }
  else if (ext == "node" || ext == "ele")
  {
    auto r = vtkSmartPointer<vtkTetGenReader>::New();
    r->SetFileName(path.c_str());
    reader = r;
  }
  else
  {
    error = "unknown mesh format '." + ext + "' of '" + path +
      "' (use .ply, .stl, .obj, .vtp, .vtu, .node or .ele)";
    return false;
  }
  messages.Watch(reader);
  reader->Update();
  vtkDataObject* data = reader->GetOutputDataObject(0);
  if (!messages.Errors.empty())
  {
    error = "cannot read '" + path + "': " + messages.Last();
    return false;
  }
  if (auto* poly = vtkPolyData::SafeDownCast(data))
  {
    surface = poly;
  }
  else if (auto* ug = vtkUnstructuredGrid::SafeDownCast(data))
  {
    grid = ug;
  }
  if ((surface && surface->GetNumberOfCells() == 0) || (grid && grid->GetNumberOfCells() == 0) ||
    (!surface && !grid))
  {
    error = "'" + path + "' holds no cells";
    return false;
  }
  return true;
}

void GridToCoreArrays(vtkUnstructuredGrid* grid, std::vector<double>& points, std::vector<int>& tets)
{
  points.resize(3 * grid->GetNumberOfPoints());
  for (vtkIdType i = 0; i < grid->GetNumberOfPoints(); ++i)
    grid->GetPoint(i, &points[3 * i]);
  tets.resize(4 * grid->GetNumberOfCells());
  const vtkIdType* ids;
  vtkIdType npts;
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c)
  {
    grid->GetCellPoints(c, npts, ids);
    if (npts != 4)
    {
      // A .vtu may declare a VTK_TETRA cell with another number of points.
      throw translucency::Error("cell " + std::to_string(c) + " has " + std::to_string(npts) +
        " points: a tetrahedron needs 4");
    }
    for (int k = 0; k < 4; ++k)
      tets[4 * c + k] = static_cast<int>(ids[k]);
  }
}

} // namespace translucency_app
