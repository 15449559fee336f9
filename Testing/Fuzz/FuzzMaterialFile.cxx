// libFuzzer target: the --material JSON file of the command line (a single
// material or a material table, Apps/JsonInputs), then the filter it
// configures on a small grid. Bad input must be a translucency::Error.
#include "FuzzSupport.h"

#include "Error.h"
#include "JsonInputs.h"
#include "vtkAssignScatteringCoefficients.h"

#include <vtkCellData.h>
#include <vtkIntArray.h>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
  using namespace translucency_fuzz;
  const std::string path = WriteInput("material.json", data, size);
  static vtkSmartPointer<vtkUnstructuredGrid> grid = []
  {
    auto g = SmallTetGrid();
    vtkNew<vtkIntArray> ids;
    ids->SetName("MaterialId");
    for (vtkIdType c = 0; c < g->GetNumberOfCells(); ++c)
    {
      ids->InsertNextValue(1 + static_cast<int>(c % 3));
    }
    g->GetCellData()->AddArray(ids);
    return g;
  }();
  // A table needs --material-ids, a single material must not have it: try
  // both, as a user may. One outcome per input: a success if either loads.
  bool loaded = false;
  for (const char* ids : { "", "MaterialId" })
  {
    vtkNew<vtkAssignScatteringCoefficients> assign;
    try
    {
      translucency_app::ApplyMaterial(assign, path, ids);
    }
    catch (const translucency::Error&)
    {
      continue;
    }
    assign->SetInputData(grid);
    assign->Update();
    loaded = true;
  }
  Tally(loaded ? "success" : "clean error");
  return 0;
}
