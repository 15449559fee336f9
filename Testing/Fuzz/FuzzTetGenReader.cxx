// libFuzzer target: vtkTetGenReader on a .node/.ele/.face triple. The input
// holds the three files separated by the two bytes "@@" (the .face part is
// optional); the output must be a well-formed tetrahedral grid or empty.
#include "FuzzSupport.h"

#include "vtkTetGenReader.h"

#include <vtkCellArray.h>
#include <vtkFieldData.h>
#include <vtkIntArray.h>

#include <string>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
  using namespace translucency_fuzz;
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  std::string_view parts[3];
  size_t start = 0;
  for (int p = 0; p < 3; ++p)
  {
    const size_t end = p < 2 ? input.find("@@", start) : std::string_view::npos;
    parts[p] = input.substr(start, end == std::string_view::npos ? std::string_view::npos : end - start);
    if (end == std::string_view::npos)
    {
      break;
    }
    start = end + 2;
  }
  const char* ext[3] = { "mesh.node", "mesh.ele", "mesh.face" };
  std::string nodePath;
  for (int p = 0; p < 3; ++p)
  {
    const std::string path = WriteInput(
      ext[p], reinterpret_cast<const uint8_t*>(parts[p].data()), parts[p].size());
    if (p == 0)
    {
      nodePath = path;
    }
  }

  vtkNew<vtkTetGenReader> reader;
  reader->SetFileName(nodePath.c_str());
  reader->CanReadFile(nodePath.c_str());
  reader->Update();
  vtkUnstructuredGrid* grid = reader->GetOutput();
  const vtkIdType nPoints = grid->GetNumberOfPoints();
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c)
  {
    Check(grid->GetCellType(c) == VTK_TETRA, "every cell is a tetrahedron");
    vtkIdType npts;
    const vtkIdType* pts;
    grid->GetCellPoints(c, npts, pts);
    Check(npts == 4, "four points per tetrahedron");
    for (vtkIdType i = 0; i < npts; ++i)
    {
      Check(pts[i] >= 0 && pts[i] < nPoints, "tetrahedron point ids in range");
    }
  }
  if (auto* faces = vtkIntArray::SafeDownCast(grid->GetFieldData()->GetArray("TetGenFaces")))
  {
    for (vtkIdType v = 0; v < faces->GetNumberOfValues(); ++v)
    {
      Check(faces->GetValue(v) >= 0 && faces->GetValue(v) < nPoints, "face point ids in range");
    }
  }
  Tally(grid->GetNumberOfCells() > 0 ? "success" : "clean error");
  return 0;
}
