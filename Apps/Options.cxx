#include "Options.h"
#include "Pictures.h"
#include "PipelineRender.h"
#include "Scene.h"

#include "CollimatedModels.h"
#include "DiffusionSolverFactory.h"
#include "Radiance.h"
#include "Strings.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <iomanip>
#include <sstream>

namespace translucency_app
{

std::string JoinOr(const std::vector<std::string>& names)
{
  std::string text;
  for (size_t k = 0; k < names.size(); ++k)
  {
    text += (k == 0 ? "" : (k + 1 == names.size() ? " or " : ", ")) + names[k];
  }
  return text;
}

std::string DefaultText(double value)
{
  if (value == std::floor(value) && std::abs(value) < 1e15)
  {
    return std::to_string(static_cast<long long>(value));
  }
  for (int digits = 1; digits <= 17; ++digits)
  {
    char text[64];
    std::snprintf(text, sizeof(text), "%.*g", digits, value);
    if (std::strtod(text, nullptr) == value)
    {
      std::string s = text;
      // 1e-06 -> 1e-6, 1e+06 -> 1e6.
      const size_t e = s.find('e');
      if (e != std::string::npos)
      {
        std::string mantissa = s.substr(0, e), exponent = s.substr(e + 1);
        const bool negative = exponent[0] == '-';
        exponent = exponent.substr(1);
        exponent.erase(0, std::min(exponent.find_first_not_of('0'), exponent.size() - 1));
        s = mantissa + "e" + (negative ? "-" : "") + exponent;
      }
      return s;
    }
  }
  return std::to_string(value);
}

std::string WrapNames(const std::vector<std::string>& names, size_t width)
{
  std::string text, line;
  for (size_t k = 0; k < names.size(); ++k)
  {
    const std::string item = names[k] + (k + 1 < names.size() ? "," : "");
    if (!line.empty() && line.size() + 1 + item.size() > width)
    {
      text += line + "\n";
      line.clear();
    }
    line += (line.empty() ? "" : " ") + item;
  }
  return text + line;
}

CLI::Validator NumberCheck(const std::string& option, std::function<bool(double)> valid,
  const std::string& failure)
{
  return CLI::Validator(
    [option, valid, failure](std::string& text) {
      const std::vector<double> v = ParseNumbers(text, option);
      if (v.size() != 1)
      {
        throw UsageError(option + " needs one number, not '" + text + "'");
      }
      if (valid && !valid(v[0]))
      {
        throw UsageError(failure);
      }
      return std::string();
    },
    "");
}

CLI::Validator OneOf(const std::string& option, const std::vector<std::string>& choices)
{
  return CLI::Validator(
    [option, choices](std::string& text) {
      if (std::find(choices.begin(), choices.end(), text) == choices.end())
      {
        throw UsageError(option + ": '" + text + "' is not " + JoinOr(choices));
      }
      return std::string();
    },
    "");
}

std::vector<std::string> CollimatedModelChoices()
{
  std::vector<std::string> names = { "default" };
  for (const translucency::CollimatedModelEntry& entry : translucency::GetCollimatedModelTable())
  {
    names.push_back(entry.Name);
  }
  return names;
}

CLI::Validator DiffusionSolverCheck(const std::string& option)
{
  return CLI::Validator(
    [option](std::string& text) {
      const std::vector<std::string> known = translucency::GetDiffusionSolverNames();
      std::stringstream ss(text);
      std::string item;
      while (std::getline(ss, item, ','))
      {
        if (!item.empty() &&
          std::find(known.begin(), known.end(), translucency::ToLower(item)) == known.end())
        {
          throw UsageError(option + ": unknown solver '" + item + "' (known solvers: " +
            translucency::JoinNames(known) + ")");
        }
      }
      return std::string();
    },
    "");
}

CLI::Option* AddNumberList(CLI::App* app, const std::string& name, std::vector<double>& target,
  const std::string& help, const std::string& typeName, size_t count, const std::string& failure)
{
  std::vector<double>* values = &target;
  std::string shown;
  for (double v : target)
  {
    shown += (shown.empty() ? "" : ",") + DefaultText(v);
  }
  CLI::Option* option = app->add_option_function<std::string>(
    name, [values, name](const std::string& text) { *values = ParseNumbers(text, name); }, help);
  option->type_name(typeName)->check(CLI::Validator(
    [name, count, failure](std::string& text) {
      if (ParseNumbers(text, name).size() != count && count > 0)
      {
        throw UsageError(failure);
      }
      return std::string();
    },
    ""));
  if (!shown.empty())
  {
    option->default_str(shown);
  }
  return option;
}

void AddMemoryLimitOption(CLI::App* command)
{
  command
    ->add_option_function<std::string>(
      "--memory-limit",
      [](const std::string& text) {
        const double gib = ParseNumbers(text, "--memory-limit").at(0);
        translucency::SetDefaultMemoryLimit(static_cast<std::size_t>(gib * 1073741824.0));
      },
      "refuse problems whose estimated memory exceeds this,\n"
      "GiB (grid, tets, patches, form factors, acquisition\n"
      "grids, photon and ray budgets)")
    ->type_name("GiB")
    ->default_str(DefaultText(static_cast<double>(translucency::GetDefaultMemoryLimit()) /
      1073741824.0))
    ->check(NumberCheck("--memory-limit", [](double g) { return g >= 1.0 / 1024 && g <= 1 << 24; },
      "--memory-limit must be from 0.0009765625 (1 MiB) to 16777216 GiB"));
  command
    ->add_flag_function(
      "--allow-long-runs", [](std::int64_t) { translucency::SetLongRunsAllowed(true); },
      "lift the work budgets that refuse hours-long requests\n"
      "(Monte Carlo photons, form-factor rays, acquisition\n"
      "solve work); memory stays bounded by --memory-limit");
}

void AddQuietOption(CLI::App* command)
{
  command->add_flag_function(
    "--quiet", [](std::int64_t) { SetQuiet(true); }, "no progress lines on stderr");
}

void AddSceneOptions(CLI::App* command, SceneOptions& scene)
{
  const std::string group = "Scene options";
  SceneOptions* s = &scene;
  command
    ->add_option("--mesh", scene.MeshPath,
      "closed triangle surface (.ply .stl .obj .vtp), tet mesh\n"
      "(.vtu), or TetGen mesh (.node/.ele). Lengths in mm.")
    ->type_name("FILE")
    ->group(group);
  AddNumber(command, "--target-tets", scene.TargetTets, "tetrahedralize to about N tets", "N",
    [](double n) { return n >= 1; }, "--target-tets must be >= 1")
    ->each([s](const std::string&) { s->TargetGiven = true; })
    ->group(group);
  AddNumber(command, "--max-tet-volume", scene.MaxTetVolume,
    "... or bound the tet volume by V mm^3 instead", "V", [](double v) { return v > 0; },
    "--max-tet-volume must be > 0 (mm^3)")
    ->default_str("")
    ->group(group);
  AddNumber(command, "--quality", scene.Quality, "radius-edge ratio bound for TetGen", "Q",
    [](double q) { return q >= 1.1; }, "--quality must be >= 1.1")
    ->group(group);
  command
    ->add_option("--mesher", scene.Mesher,
      "tetrahedraliser: tetgen (default; single-threaded,\n"
      "radius-edge bound --quality) or hxt (gmsh's parallel\n"
      "Delaunay mesher, when the build has gmsh)")
    ->type_name("NAME")
    ->check(CLI::Validator(
      [](std::string& text) {
        const std::string name = translucency::ToLower(text);
        if (name != "tetgen" && name != "hxt")
          throw UsageError("--mesher: unknown mesher '" + text + "': use tetgen or hxt");
        return std::string();
      },
      ""))
    ->group(group);
  command
    ->add_flag("--uniform-size", scene.UniformSizing,
      "one edge length everywhere (the surface refined, with hxt\n"
      "also coarsened, to the interior size) instead of cells\n"
      "graded towards the surface; QuadGraph needs it")
    ->group(group);
  command
    ->add_option("--grading", scene.GradingFactor,
      "tetgen: surface cells G times smaller than the interior\n"
      "ones (1 <= G <= 8; 1 = --uniform-size), growing linearly\n"
      "over one interior cell (default: TetGen's own grading)")
    ->check(CLI::Range(1.0, 8.0))
    ->excludes("--uniform-size")
    ->group(group);
  command
    ->add_option("--material", scene.Material,
      "measured preset (default marble; see render --list-materials)\n"
      "or a JSON file {\"absorption\": [r,g,b], \"reduced_scattering\":\n"
      "[r,g,b], \"refractive_index\": eta} in 1/mm, or a material\n"
      "table {\"materials\": [...]} (Documentation/Materials.md) used\n"
      "with --material-ids. A .vtu input that already has the\n"
      "coefficient arrays keeps them unless given.")
    ->type_name("NAME|FILE")
    ->group(group);
  command
    ->add_option("--material-ids", scene.MaterialIds,
      "cell array of integer material ids (e.g. RegionAttribute of\n"
      "a TetGen mesh): each tet gets its entry of the table")
    ->type_name("ARRAY")
    ->group(group);
  command
    ->add_option_function<std::vector<std::string>>(
      "--light",
      [s](const std::vector<std::string>& specs) {
        for (const std::string& spec : specs)
          s->Lights.push_back(ParseLight(spec));
      },
      "may repeat; default directional:0,-1,-1:1 and uniform:0.1\n"
      "directional:dx,dy,dz[:E]  direction of travel, E W/mm^2 (1)\n"
      "point:x,y,z[:I]           position mm, intensity W/sr (1)\n"
      "spot:x,y,z:dx,dy,dz:C[,X][:I]  axis, cone half-angle C deg,\n"
      "                          fall-off cos^X (0), I W/sr on the axis\n"
      "E or I: one number, or R,G,B for a coloured light\n"
      "uniform[:E]               environment, E W/mm^2 (1)\n"
      "none                      no light (alone)")
    ->type_name("SPEC")
    ->group(group);
  command->add_flag_callback("--no-shadows", [s]() { s->Shadows = false; }, "no self-shadowing")
    ->group(group);
  AddNumber(command, "--uniform-samples", scene.UniformSamples,
    "occlusion rays per point for the uniform light", "N",
    [](double n) { return n >= 0 && n <= 4096; }, "--uniform-samples must be from 0 to 4096")
    ->group(group);
  command
    ->add_option("--collimated", scene.Collimated,
      "how directional lights enter the diffusion model (pencil\n"
      "beams and spot lights: the Robin rule; DiffuseOptics.md):\n" +
        translucency::FormatCollimatedModelHelp("") +
        "default: measured against Monte Carlo per light kind, for\n"
        "divergence and fem (the other solvers: surface); explicit\n"
        "extended models: divergence, fem, sp3")
    ->type_name("MODEL")
    ->check(OneOf("--collimated", CollimatedModelChoices()))
    ->group(group);
  command
    ->add_option("--paint", scene.Paint,
      "paint the coefficients along a 3D stroke (after the material,\n"
      "before any cut; vtkPaintScatteringCoefficients):\n"
      "{\"points\": [[x,y,z], ...] (mm, required), \"width\": mm (1),\n"
      " \"mode\": \"set\"|\"multiply\"|\"add\" (\"set\"),\n"
      " \"absorption\": [r,g,b], \"reduced_scattering\": [r,g,b]\n"
      " (target: 1/mm for set/add, factor for multiply; default\n"
      " ketchup), \"strength\": 0..1 (1), \"channels\": [1,1,1],\n"
      " \"cutoff_weight\": 0..1 (1e-6: no paint where the weight\n"
      " is below it; 0 = exact Gaussian everywhere)}")
    ->type_name("FILE.json")
    ->group(group);
  AddNumberList(command, "--cut-plane", scene.CutPlane,
    "cut the tet mesh with the plane through o (mm) with normal n:\n"
    "removes the side n points to (vtkStrokeCut)",
    "ox,oy,oz,nx,ny,nz", 6, "--cut-plane needs six comma-separated numbers ox,oy,oz,nx,ny,nz")
    ->check(CLI::Validator(
      [](std::string& text) {
        const std::vector<double> v = ParseNumbers(text, "--cut-plane");
        if (v[3] == 0 && v[4] == 0 && v[5] == 0)
          throw UsageError("--cut-plane: the normal is zero");
        return std::string();
      },
      ""))
    ->group(group);
  command
    ->add_option("--cut-stroke", scene.CutStroke,
      "cut along a stroke swept along the view direction:\n"
      "{\"points\": [[x,y,z], ...] (>= 2, mm), \"view_direction\":\n"
      "[dx,dy,dz] (default [0,0,-1]), \"inside_out\": false}; removes\n"
      "the left of the stroke as seen along the view direction\n"
      "(inside_out: the right). Order: tetrahedralize, material,\n"
      "paint, cut, irradiance, solve.")
    ->type_name("FILE.json")
    ->group(group);
}

void AddImageOptions(CLI::App* command, RadianceImageOptions& image)
{
  const std::string group = "Picture options";
  RadianceImageOptions* im = &image;
  auto direction = [command, group](const std::string& name, double* target,
                     const std::string& help, const std::string& typeName) {
    command
      ->add_option_function<std::string>(
        name,
        [name, target](const std::string& text) {
          const std::vector<double> v = ParseNumbers(text, name);
          std::copy(v.begin(), v.end(), target);
        },
        help)
      ->type_name(typeName)
      ->default_str(
        DefaultText(target[0]) + "," + DefaultText(target[1]) + "," + DefaultText(target[2]))
      ->check(CLI::Validator(
        [name](std::string& text) {
          const std::vector<double> v = ParseNumbers(text, name);
          if (v.size() != 3 || (v[0] == 0 && v[1] == 0 && v[2] == 0))
            throw UsageError(name + " needs three numbers, not all zero");
          return std::string();
        },
        ""))
      ->group(group);
  };
  direction("--view", image.ViewDirection, "camera direction of view", "dx,dy,dz");
  direction("--up", image.ViewUp, "camera up vector", "x,y,z");
  AddNumber(command, "--exposure", image.Exposure, "radiance multiplier before display", "X")
    ->default_str("automatic")
    ->group(group);
  command
    ->add_option_function<std::string>(
      "--size",
      [im](const std::string& text) {
        std::sscanf(text.c_str(), "%dx%d", &im->Width, &im->Height);
      },
      "image size")
    ->type_name("WxH")
    ->default_str(std::to_string(image.Width) + "x" + std::to_string(image.Height))
    ->check(CLI::Validator(
      [](std::string& text) {
        int w = 0, h = 0;
        if (std::sscanf(text.c_str(), "%dx%d", &w, &h) != 2 || w < 16 || h < 16 || w > 8192 ||
          h > 8192)
          throw UsageError("--size must be WxH, e.g. 800x600");
        return std::string();
      },
      ""))
    ->group(group);
  command
    ->add_option_function<std::string>(
      "--channel", [im](const std::string& text) { im->Channel = ChannelIndex(text); },
      "colour channel of the colour-mapped pictures (slice, error maps)")
    ->type_name("R|G|B")
    ->default_str("R")
    ->check(CLI::Validator(
      [](std::string& text) {
        if (ChannelIndex(text) < 0)
          throw UsageError("--channel: '" + text + "' is not R, G or B");
        return std::string();
      },
      ""))
    ->group(group);
  command
    ->add_option_function<std::string>(
      "--scale", [im](const std::string& text) { im->LogScale = text == "log"; },
      "colour scale of the fluence slice")
    ->type_name("log|linear")
    ->default_str("log")
    ->check(OneOf("--scale", { "log", "linear" }))
    ->group(group);
  AddNumberList(command, "--slice-plane", image.SlicePlane,
    "slice of --slice-png: the plane through o (mm) with normal n\n"
    "(default: through the centre, normal to --view)",
    "ox,oy,oz,nx,ny,nz", 6, "--slice-plane needs six numbers: ox,oy,oz,nx,ny,nz")
    ->check(CLI::Validator(
      [](std::string& text) {
        const std::vector<double> v = ParseNumbers(text, "--slice-plane");
        if (v.size() == 6 && v[3] == 0 && v[4] == 0 && v[5] == 0)
          throw UsageError("--slice-plane: the normal (last three numbers) is zero");
        return std::string();
      },
      ""))
    ->group(group);
}

void AddGridAndPhotonOptions(CLI::App* command, double& gridSpacing, long long& photons)
{
  AddNumber(command, "--grid-spacing", gridSpacing, "voxel spacing of the grid solver, mm", "H",
    [](double h) { return h > 0; }, "--grid-spacing must be > 0 mm")
    ->default_str("automatic");
  AddNumber(command, "--photons", photons, "photon budget of montecarlo", "N",
    [](double n) { return n >= 1; }, "--photons must be >= 1");
}

void AddRadianceReadoutOption(CLI::App* command, RadianceReadoutOption& readout)
{
  CLI::Option* name = command->add_option("--radiance-readout", readout.Name,
      "energy-conserving: TransCut eq. 3 / eta^2 (the n^2 law;\n"
      "a non-absorbing object emits what it receives, as Monte\n"
      "Carlo does); paper: eq. 3 as printed (eta^2 x the light,\n"
      "1.69x at eta 1.3), to reproduce TransCut's figures")
    ->type_name("NAME")
    ->capture_default_str()
    ->check(OneOf("--radiance-readout", translucency::GetRadianceReadoutNames()));
  command->add_flag("--n-squared-law", readout.NSquaredLaw,
      "same as --radiance-readout energy-conserving (the default)")
    ->excludes(name);
}

} // namespace translucency_app
