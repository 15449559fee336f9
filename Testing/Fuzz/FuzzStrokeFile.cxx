// libFuzzer target: the --cut-stroke JSON file of the command line
// (Apps/JsonInputs), then vtkStrokeCut on a small grid.
#include "FuzzSupport.h"

#include "Error.h"
#include "JsonInputs.h"
#include "vtkStrokeCut.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
  using namespace translucency_fuzz;
  const std::string path = WriteInput("stroke.json", data, size);
  static vtkSmartPointer<vtkUnstructuredGrid> grid = SmallTetGrid();
  vtkNew<vtkStrokeCut> cut;
  try
  {
    translucency_app::ApplyStrokeFile(cut, path);
  }
  catch (const translucency::Error&)
  {
    Tally("clean error");
    return 0;
  }
  cut->SetInputData(grid);
  cut->Update();
  Tally("success");
  return 0;
}
