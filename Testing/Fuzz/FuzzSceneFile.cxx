// libFuzzer target: the radiosity scene file (Apps/SceneFile). Bad input
// must be a translucency::Error naming the scene. Boxes are meshed with
// 4 mm cells at least (a scene may ask for any number of cells: that is
// slow, not wrong).
#include "FuzzSupport.h"

#include "Error.h"
#include "SceneFile.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
  using namespace translucency_fuzz;
  const std::string path = WriteInput("scene.json", data, size);
  try
  {
    translucency_app::LoadScene(path, 4.0);
    Tally("success");
  }
  catch (const translucency::Error&)
  {
    Tally("clean error");
  }
  return 0;
}
