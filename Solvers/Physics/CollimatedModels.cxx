#include "CollimatedModels.h"

#include "Error.h"
#include "Strings.h"

#include <algorithm>

namespace translucency
{

const std::vector<CollimatedModelEntry>& GetCollimatedModelTable()
{
  static const std::vector<CollimatedModelEntry> table = {
    { CollimatedModel::Surface, "surface", "Surface (boundary irradiance)",
      "boundary irradiance q (TransCut eq. 2)" },
    { CollimatedModel::Extended, "extended", "Extended (volume source)",
      "unscattered beam exp(-mu_t' s) + volume source mu_s' E_c (divergence, fem, sp3)" },
    { CollimatedModel::ExtendedMoments, "extended-moments", "Extended, Fresnel-moment boundary",
      "extended, with the Robin condition's A from the Fresnel moments" },
  };
  return table;
}

const CollimatedModelEntry& GetCollimatedModel(const std::string& name)
{
  const std::string key = ToLower(name);
  for (const CollimatedModelEntry& entry : GetCollimatedModelTable())
  {
    if (entry.Name == key)
    {
      return entry;
    }
  }
  std::vector<std::string> names;
  for (const CollimatedModelEntry& entry : GetCollimatedModelTable())
  {
    names.push_back(entry.Name);
  }
  throw Error("unknown collimated model '" + name + "' (known collimated models: " +
    JoinNames(names) + ")");
}

const CollimatedModelEntry& GetCollimatedModel(CollimatedModel model)
{
  for (const CollimatedModelEntry& entry : GetCollimatedModelTable())
  {
    if (entry.Model == model)
    {
      return entry;
    }
  }
  throw Error("collimated model " + std::to_string(static_cast<int>(model)) + " is not listed");
}

const std::vector<CollimatedDefault>& GetCollimatedDefaultTable()
{
  // Measured against Monte Carlo on a 20 x 20 x 10 mm box and a 60 x 60 x
  // 10 mm slab (mu_a 0.01, mu_s' 1/mm, eta 1.3; DiffuseOptics.md, "Which
  // collimated model by default"; scripts/collimated_model_table.py): the
  // model nearest Monte Carlo on most read-outs, the deep fluence and the
  // transmittance first. The order decides a scene with several kinds.
  static const std::vector<CollimatedDefault> table = {
    { LightKind::Directional, "directional", CollimatedModel::ExtendedMoments,
      "deep fluence +1.0 % (surface -7.8 %), transmittance -0.2 % (-15.1 %) on the box" },
    { LightKind::Coloured, "coloured", CollimatedModel::ExtendedMoments,
      "as directional, channel by channel (both sides are linear in the light)" },
    { LightKind::Spot, "spot", CollimatedModel::ExtendedMoments,
      "deep fluence -4.9 % (surface -7.8 %), transmittance -8.5 % (-12.8 %) on the box" },
    { LightKind::Point, "point", CollimatedModel::ExtendedMoments,
      "as spot: the same boundary irradiance of a point, without the cone" },
    { LightKind::Uniform, "uniform", CollimatedModel::ExtendedMoments,
      "deep fluence -1.1 % (surface -2.3 %), transmittance +0.1 % (+0.3 %) on the box" },
    { LightKind::Pencil, "pencil", CollimatedModel::Surface,
      "deep fluence -2.2 % (extended-moments -4.8 %), transmittance -1.1 % (-2.6 %)" },
    { LightKind::None, "interior sources", CollimatedModel::Surface,
      "as pencil: a pencil beam is a point source one transport length deep" },
  };
  return table;
}

CollimatedModel DefaultCollimatedModel(LightKind kind)
{
  for (const CollimatedDefault& row : GetCollimatedDefaultTable())
  {
    if (row.Kind == kind)
    {
      return row.Model;
    }
  }
  return CollimatedModel::Surface; // not reached: every kind is listed
}

LightKind KindOfLight(const LightSource& light)
{
  switch (light.Type)
  {
    case LightSource::Kind::Directional:
      return light.Power[1] != light.Power[0] || light.Power[2] != light.Power[0]
        ? LightKind::Coloured
        : LightKind::Directional;
    case LightSource::Kind::Spot:
      return LightKind::Spot;
    case LightSource::Kind::Uniform:
      return LightKind::Uniform;
    default:
      return LightKind::Point;
  }
}

CollimatedModel DefaultCollimatedModel(
  const std::vector<LightSource>& lights, bool uniformLight, bool pencilBeams)
{
  for (const CollimatedDefault& row : GetCollimatedDefaultTable())
  {
    bool present = false;
    switch (row.Kind)
    {
      case LightKind::Uniform:
        present = uniformLight;
        break;
      case LightKind::Pencil:
        present = pencilBeams;
        break;
      case LightKind::None:
        present = true; // the last row: none of the above
        break;
      default:
        present = std::any_of(lights.begin(), lights.end(),
          [&row](const LightSource& light) { return KindOfLight(light) == row.Kind; });
    }
    if (present)
    {
      return row.Model;
    }
  }
  return CollimatedModel::Surface; // not reached: None is listed
}

std::string DescribeCollimatedDefaults()
{
  std::string text;
  for (const CollimatedDefault& row : GetCollimatedDefaultTable())
  {
    text += (text.empty() ? "" : ", ") + row.KindName + ": " + GetCollimatedModel(row.Model).Name;
  }
  return text;
}

std::string FormatCollimatedModelHelp(const std::string& indent)
{
  std::size_t width = std::string("default").size();
  for (const CollimatedModelEntry& entry : GetCollimatedModelTable())
  {
    width = std::max(width, entry.Name.size());
  }
  auto line = [&](const std::string& name, const std::string& help) {
    return indent + name + std::string(width + 2 - name.size(), ' ') + help + "\n";
  };
  std::string text = line("default", "by light kind (the first the scene has decides):");
  for (const CollimatedDefault& row : GetCollimatedDefaultTable())
  {
    text += line("", "  " + row.KindName + ": " + GetCollimatedModel(row.Model).Name);
  }
  for (const CollimatedModelEntry& entry : GetCollimatedModelTable())
  {
    text += line(entry.Name, entry.Help);
  }
  return text;
}

} // namespace translucency
