// libFuzzer target: vtkMaterialTableReader on a JSON material table.
#include "FuzzSupport.h"

#include "vtkMaterialTableReader.h"

#include <vtkTable.h>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
  using namespace translucency_fuzz;
  const std::string path = WriteInput("materials.json", data, size);
  vtkNew<vtkMaterialTableReader> reader;
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkTable* table = reader->GetOutput();
  Check(table->GetNumberOfRows() >= 0, "a table");
  Tally(table->GetNumberOfRows() > 0 ? "success" : "clean error");
  return 0;
}
