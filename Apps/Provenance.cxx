#include "Provenance.h"

#include "Options.h"
#include "Scene.h"

#include <CLI/CLI.hpp>

namespace translucency_app
{
namespace
{
std::vector<std::string>& CommandLine()
{
  static std::vector<std::string> args;
  return args;
}
}

std::string ProjectVersion()
{
  return TRANSLUCENCY_VERSION;
}

std::string SourceRevision()
{
  return TRANSLUCENCY_REVISION;
}

std::string VersionLine()
{
  return "translucency " + ProjectVersion() + " (revision " + SourceRevision() + ")";
}

void SetCommandLine(int argc, char* argv[])
{
  CommandLine().assign(argv, argv + argc);
}

nlohmann::json Provenance(const CLI::App* command)
{
  nlohmann::json p;
  p["program"] = "translucency";
  p["version"] = ProjectVersion();
  p["revision"] = SourceRevision();
  p["command_line"] = CommandLine();
  nlohmann::json options = nlohmann::json::object();
  for (const CLI::Option* option : command->get_options())
  {
    if (option->get_lnames().empty() || option->get_lnames()[0] == "help")
      continue;
    const std::string name = "--" + option->get_lnames()[0];
    if (option->count() > 0)
    {
      const std::vector<std::string>& given = option->results();
      options[name] = given.size() == 1 ? nlohmann::json(given[0]) : nlohmann::json(given);
    }
    else if (!option->get_default_str().empty())
      options[name] = option->get_default_str();
    else if (option->get_expected_max() == 0)
      options[name] = false; // a flag not given
  }
  p["options"] = options;
  return p;
}

std::string LightsLine(const SceneOptions& scene)
{
  std::string line = "lights:";
  for (const Light& l : scene.Lights)
  {
    line += " " + l.Type;
    if (l.Type != "uniform")
      line += ":" + DefaultText(l.Values[0]) + "," + DefaultText(l.Values[1]) + "," +
        DefaultText(l.Values[2]);
    if (l.Type == "spot")
      line += ":" + DefaultText(l.Axis[0]) + "," + DefaultText(l.Axis[1]) + "," +
        DefaultText(l.Axis[2]) + ":" + DefaultText(l.Cutoff) + "," + DefaultText(l.Exponent);
    line += ":" + DefaultText(l.PowerRGB[0]);
    if (l.Coloured)
      line += "," + DefaultText(l.PowerRGB[1]) + "," + DefaultText(l.PowerRGB[2]);
  }
  if (scene.DefaultLights)
    line += " (the default: set --light to choose)";
  return line;
}

nlohmann::json SceneProvenance(const SceneOptions& scene)
{
  nlohmann::json s;
  s["mesh"] = scene.MeshPath;
  s["material"] = scene.Material.empty() ? "marble (default; a .vtu keeps its own coefficients)"
                                         : scene.Material;
  nlohmann::json lights = nlohmann::json::array();
  for (const Light& l : scene.Lights)
  {
    nlohmann::json light = { { "type", l.Type } };
    if (l.Type == "directional")
      light["direction"] = { l.Values[0], l.Values[1], l.Values[2] };
    else if (l.Type == "point" || l.Type == "spot")
      light["position_mm"] = { l.Values[0], l.Values[1], l.Values[2] };
    if (l.Type == "spot")
    {
      light["axis"] = { l.Axis[0], l.Axis[1], l.Axis[2] };
      light["cutoff_deg"] = l.Cutoff;
      light["exponent"] = l.Exponent;
    }
    const bool intensity = l.Type == "point" || l.Type == "spot";
    light[intensity ? "intensity_W_per_sr" : "irradiance_W_per_mm2"] = l.Coloured
      ? nlohmann::json({ l.PowerRGB[0], l.PowerRGB[1], l.PowerRGB[2] })
      : nlohmann::json(l.Power);
    lights.push_back(light);
  }
  s["lights"] = lights;
  s["default_lights"] = scene.DefaultLights;
  s["shadows"] = scene.Shadows;
  return s;
}

} // namespace translucency_app
