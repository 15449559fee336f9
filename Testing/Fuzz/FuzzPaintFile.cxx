// libFuzzer target: the --paint JSON stroke of the command line
// (Apps/JsonInputs), then vtkPaintScatteringCoefficients on a small grid.
#include "FuzzSupport.h"

#include "Error.h"
#include "JsonInputs.h"
#include "vtkAssignScatteringCoefficients.h"
#include "vtkPaintScatteringCoefficients.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
  using namespace translucency_fuzz;
  const std::string path = WriteInput("paint.json", data, size);
  static vtkSmartPointer<vtkDataObject> painted = []
  {
    vtkNew<vtkAssignScatteringCoefficients> assign;
    assign->SetInputData(SmallTetGrid());
    assign->Update();
    return vtkSmartPointer<vtkDataObject>(assign->GetOutputDataObject(0));
  }();
  vtkNew<vtkPaintScatteringCoefficients> paint;
  try
  {
    translucency_app::ApplyPaintFile(paint, path);
  }
  catch (const translucency::Error&)
  {
    Tally("clean error");
    return 0;
  }
  paint->SetInputData(painted);
  paint->Update();
  Tally("success");
  return 0;
}
