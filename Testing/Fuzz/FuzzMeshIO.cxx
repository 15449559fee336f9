// libFuzzer target: the mesh entry of the command line (Apps/MeshIO
// ReadMesh, then GridToCoreArrays). The first line of the input is the file
// extension (ply, stl, obj, vtp, vtu), the rest the file; so every reader
// ReadMesh dispatches to is fuzzed through it.
#include "FuzzSupport.h"

#include "Error.h"
#include "MeshIO.h"

#include <vtkPolyData.h>

#include <string>
#include <string_view>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
  using namespace translucency_fuzz;
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  const size_t eol = input.find('\n');
  if (eol == std::string_view::npos)
  {
    Tally("skipped");
    return 0;
  }
  const std::string ext(input.substr(0, eol));
  if (ext != "ply" && ext != "stl" && ext != "obj" && ext != "vtp" && ext != "vtu")
  {
    Tally("skipped");
    return -1; // not added to the corpus
  }
  const std::string path = WriteInput("mesh." + ext, data + eol + 1, size - eol - 1);
  vtkSmartPointer<vtkPolyData> surface;
  vtkSmartPointer<vtkUnstructuredGrid> grid;
  std::string error;
  if (!translucency_app::ReadMesh(path, surface, grid, error))
  {
    Check(!error.empty(), "a failed read says why");
    Tally("clean error", ext);
    return 0;
  }
  Check(surface || grid, "a successful read gives a surface or a grid");
  // GridToCoreArrays takes tetrahedral grids (the callers give it filter
  // outputs); a read grid is checked for that first, as the CLI does.
  bool allTets = grid != nullptr;
  for (vtkIdType c = 0; allTets && c < grid->GetNumberOfCells(); ++c)
  {
    allTets = grid->GetCellType(c) == VTK_TETRA;
  }
  if (allTets)
  {
    std::vector<double> points;
    std::vector<int> tets;
    try
    {
      translucency_app::GridToCoreArrays(grid, points, tets);
    }
    catch (const translucency::Error&)
    {
      Tally("clean error", ext);
      return 0;
    }
  }
  Tally("success", ext);
  return 0;
}
