// libFuzzer target: compare's --measured CSV file (Apps/CompareMeasured).
// The first byte of the input sets how many --detector columns the run
// expects ('0', '1', '2': 1, 2 or 3; any byte modulo 3), the rest is the file.
#include "FuzzSupport.h"

#include "CompareMeasured.h"
#include "Error.h"

#include <cmath>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
  using namespace translucency_fuzz;
  if (size == 0)
  {
    Tally("skipped");
    return -1;
  }
  const std::size_t detectors = 1 + data[0] % 3;
  const std::string path = WriteInput("measured.csv", data + 1, size - 1);
  translucency_app::MeasuredFile file;
  try
  {
    file = translucency_app::ReadMeasuredTpsf(path, detectors);
  }
  catch (const translucency::Error& e)
  {
    Check(std::string(e.what()).find("measured.csv") != std::string::npos,
      "the error names the file");
    Tally("clean error");
    return 0;
  }
  // What the header promises: increasing finite times, one finite value per
  // detector and row.
  Check(file.TimeUnit == "ns" || file.TimeUnit == "ps", "a time unit");
  Check(file.Times.size() >= 2, "at least two rows");
  Check(file.Columns.size() == detectors && file.Values.size() == detectors,
    "one column per detector");
  for (std::size_t r = 0; r < file.Times.size(); ++r)
  {
    Check(std::isfinite(file.Times[r]), "finite times");
    Check(r == 0 || file.Times[r] > file.Times[r - 1], "increasing times");
  }
  for (const auto& column : file.Values)
  {
    Check(column.size() == file.Times.size(), "a value per row");
    for (double v : column)
    {
      Check(std::isfinite(v), "finite values");
    }
  }
  Tally("success");
  return 0;
}
