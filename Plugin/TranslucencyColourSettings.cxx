#include "TranslucencyColourSettings.h"

#include <vtkSMSettings.h>

#include <sstream>

namespace
{
struct ArrayStyle
{
  const char* Name;
  const char* Title; ///< the quantity and its unit
  bool Channels;     ///< three channels (R, G, B): colour by G
};

// The names and units of the data contract (Documentation/Pipeline.md).
const ArrayStyle Styles[] = {
  { "Fluence", "Fluence (W/mm^2)", true },
  { "Irradiance", "Irradiance q (W/mm^2)", true },
  { "Radiance", "Radiance (W/(mm^2 sr))", true },
  { "AbsorptionCoefficient", "Absorption mu_a (1/mm)", true },
  { "ReducedScatteringCoefficient", "Reduced scattering mu_s' (1/mm)", true },
  { "RefractiveIndex", "Refractive index", false },
  { "FluenceStandardError", "Fluence standard error (W/mm^2)", true },
  { "PaintWeight", "Paint weight", false },
};
} // namespace

std::string TranslucencyColourSettingsJson()
{
  std::ostringstream json;
  json << "{\n  \"array_lookup_tables\": {\n";
  bool first = true;
  for (const ArrayStyle& style : Styles)
  {
    json << (first ? "" : ",\n") << "    \"" << style.Name << "\": { \"Title\": \"" << style.Title
         << "\"";
    if (style.Channels)
    {
      // VectorMode 1 = Component (PVLookupTable), component 1 = G.
      json << ", \"PVLookupTable\": { \"VectorMode\": 1, \"VectorComponent\": 1 }";
    }
    json << " }";
    first = false;
  }
  json << "\n  }\n}\n";
  return json.str();
}

void TranslucencyRegisterColourSettings()
{
  vtkSMSettings::GetInstance()->AddCollectionFromString(TranslucencyColourSettingsJson(), 0.0);
}
