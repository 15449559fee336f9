// translucency: command-line front end of the Translucency pipeline.
//
//   translucency render --mesh FILE [options]   surface/tet mesh -> fluence -> radiance -> PNG
//   translucency bench [options]                assembly/solve medians at several mesh sizes
//   translucency --help
//
// Every error is printed as "translucency: error: ..." and the exit code is 1
// (2 for a usage error).

#include "PipelineRender.h"

#include "ConjugateGradient.h"
#include "DiscreteDivergence.h"
#include "Error.h"
#include "OpticalProperties.h"
#include "TetMesh.h"

#include "vtkAssignScatteringCoefficients.h"
#include "vtkOutgoingRadiance.h"
#include "vtkSolveDiffusion.h"
#include "vtkSurfaceIrradiance.h"
#include "vtkTetGenReader.h"
#include "vtkTetrahedralizeSurface.h"

#include <vtkAlgorithm.h>
#include <vtkCallbackCommand.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkExecutive.h>
#include <vtkNew.h>
#include <vtkOBJReader.h>
#include <vtkOutputWindow.h>
#include <vtkPLYReader.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSTLReader.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLPolyDataWriter.h>
#include <vtkXMLUnstructuredGridReader.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include "vtk_nlohmannjson.h"
#include VTK_NLOHMANN_JSON(json.hpp)

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

namespace
{
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

const char* const Usage = R"(usage: translucency <command> [options]

Commands:
  render   Tetrahedralize a surface (or read a tet mesh), assign a material,
           light it, solve the diffusion equation, write the results.
  bench    Median assembly and solve times at several mesh sizes.

translucency render --mesh FILE [options]
  --mesh FILE              closed triangle surface (.ply .stl .obj .vtp), tet mesh
                           (.vtu), or TetGen mesh (.node/.ele). Lengths in mm.
  --target-tets N          tetrahedralize to about N tets (default 200000)
  --max-tet-volume V       ... or bound the tet volume by V mm^3 instead
  --quality Q              radius-edge ratio bound for TetGen (default 1.414)
  --material NAME|FILE     measured preset (default marble; see --list-materials) or a
                           JSON file {"absorption": [r,g,b], "reduced_scattering":
                           [r,g,b], "refractive_index": eta} in 1/mm. A .vtu input that
                           already has the coefficient arrays keeps them unless given.
  --light SPEC             may repeat; default directional:0,-1,-1:1 and uniform:0.1
                           directional:dx,dy,dz[:E]  direction of travel, E W/mm^2 (1)
                           point:x,y,z[:I]           position mm, intensity W/sr (1)
                           uniform[:E]               environment, E W/mm^2 (1)
  --no-shadows             no self-shadowing
  --uniform-samples N      occlusion rays per point for the uniform light (32)
  --rel-tol T              CG relative residual (default 1e-6)
  --max-iter N             CG iteration limit (default 2000)
  --output PREFIX          write PREFIX.vtu (tet mesh, Fluence, coefficients) and
                           PREFIX.vtp (surface, Radiance, Irradiance, Fluence)
  --png FILE               render the tone-mapped radiance (800x600; needs X,
                           e.g. run under xvfb-run -a)
  --slice-png FILE         render a fluence slice through the centre with a colour bar
  --view dx,dy,dz          camera direction of view (default 0,0,-1)
  --up x,y,z               camera up vector (default 0,1,0)
  --exposure X             radiance multiplier before display (default: automatic)
  --size WxH               image size (default 800x600)
  --json FILE              machine-readable statistics
  --list-materials         print the measured presets and exit

translucency bench [options]
  --mesh FILE              surface to tetrahedralize (default: Data/bunny.ply)
  --tets N1,N2,...         target sizes (default 100000,1000000)
  --runs N                 repetitions per measurement (default 7)
  --json FILE              machine-readable results
)";

struct UsageError : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

struct Stage
{
  std::string Name;
  double Milliseconds;
};

double Since(Clock::time_point start)
{
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

std::vector<double> ParseNumbers(const std::string& text, const std::string& what)
{
  std::vector<double> values;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ','))
  {
    try
    {
      size_t used = 0;
      values.push_back(std::stod(item, &used));
      if (used != item.size() || !std::isfinite(values.back()))
      {
        throw std::invalid_argument(item);
      }
    }
    catch (const std::exception&)
    {
      throw UsageError("'" + item + "' in " + what + " is not a number");
    }
  }
  return values;
}

std::string Extension(const std::string& path)
{
  const size_t dot = path.find_last_of('.');
  std::string ext = dot == std::string::npos ? "" : path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
  return ext;
}

/// Collects vtkErrorMacro / vtkWarningMacro text of the filters.
struct MessageCollector
{
  std::string Errors;
  vtkNew<vtkCallbackCommand> ErrorCallback;
  vtkNew<vtkCallbackCommand> WarningCallback;
  vtkNew<vtkCallbackCommand> IgnoreCallback;
  MessageCollector()
  {
    this->ErrorCallback->SetClientData(this);
    this->ErrorCallback->SetCallback([](vtkObject*, unsigned long, void* self, void* data) {
      auto* collector = static_cast<MessageCollector*>(self);
      collector->Errors += static_cast<const char*>(data);
    });
    this->WarningCallback->SetCallback([](vtkObject*, unsigned long, void*, void* data) {
      std::cerr << "translucency: warning: " << static_cast<const char*>(data) << "\n";
    });
  }
  void Watch(vtkObject* object)
  {
    object->AddObserver(vtkCommand::ErrorEvent, this->ErrorCallback);
    object->AddObserver(vtkCommand::WarningEvent, this->WarningCallback);
    // The executive's "Algorithm ... returned failure for request" follows
    // every filter error, which is already reported: silence it (it would
    // otherwise go to stderr through vtkLogger, whatever the output window).
    if (auto* algorithm = vtkAlgorithm::SafeDownCast(object))
    {
      algorithm->GetExecutive()->AddObserver(vtkCommand::ErrorEvent, this->IgnoreCallback);
    }
  }
  /// The message of the last error, without VTK's "ERROR: In file, line" header.
  std::string Last() const
  {
    std::string text = this->Errors;
    const size_t pos = text.rfind("): ");
    if (pos != std::string::npos)
    {
      text = text.substr(pos + 3);
    }
    while (!text.empty() && (text.back() == '\n' || text.back() == ' '))
    {
      text.pop_back();
    }
    return text;
  }
};

struct Light
{
  std::string Type;
  double Values[3] = { 0, 0, 0 };
  double Power = 1.0;
};

Light ParseLight(const std::string& spec)
{
  Light light;
  std::vector<std::string> parts;
  std::stringstream ss(spec);
  std::string part;
  while (std::getline(ss, part, ':'))
  {
    parts.push_back(part);
  }
  if (parts.empty())
  {
    throw UsageError("empty --light");
  }
  light.Type = parts[0];
  if (light.Type == "uniform")
  {
    if (parts.size() > 2)
    {
      throw UsageError("--light uniform[:E] takes at most one value: '" + spec + "'");
    }
    if (parts.size() == 2)
    {
      light.Power = ParseNumbers(parts[1], "--light " + spec).at(0);
    }
  }
  else if (light.Type == "directional" || light.Type == "point")
  {
    if (parts.size() < 2 || parts.size() > 3)
    {
      throw UsageError("--light " + light.Type + " needs x,y,z[:power]: '" + spec + "'");
    }
    std::vector<double> v = ParseNumbers(parts[1], "--light " + spec);
    if (v.size() != 3)
    {
      throw UsageError("--light " + spec + ": expected three comma-separated numbers");
    }
    std::copy(v.begin(), v.end(), light.Values);
    if (parts.size() == 3)
    {
      light.Power = ParseNumbers(parts[2], "--light " + spec).at(0);
    }
    if (light.Type == "directional" && v[0] == 0 && v[1] == 0 && v[2] == 0)
    {
      throw UsageError("--light " + spec + ": the direction is zero");
    }
  }
  else
  {
    throw UsageError("unknown light type '" + light.Type + "' (directional, point or uniform)");
  }
  if (!(light.Power >= 0))
  {
    throw UsageError("--light " + spec + ": the power must be >= 0");
  }
  return light;
}

/// Read a surface or tet mesh. Returns a polydata (to tetrahedralize) or a grid.
bool ReadMesh(const std::string& path, vtkSmartPointer<vtkPolyData>& surface,
  vtkSmartPointer<vtkUnstructuredGrid>& grid, std::string& error)
{
  std::ifstream probe(path);
  if (!probe)
  {
    error = "cannot open mesh file '" + path + "'";
    return false;
  }
  const std::string ext = Extension(path);
  MessageCollector messages;
  vtkSmartPointer<vtkAlgorithm> reader;
  if (ext == "ply")
  {
    auto r = vtkSmartPointer<vtkPLYReader>::New();
    r->SetFileName(path.c_str());
    reader = r;
  }
  else if (ext == "stl")
  {
    auto r = vtkSmartPointer<vtkSTLReader>::New();
    r->SetFileName(path.c_str());
    reader = r;
  }
  else if (ext == "obj")
  {
    auto r = vtkSmartPointer<vtkOBJReader>::New();
    r->SetFileName(path.c_str());
    reader = r;
  }
  else if (ext == "vtp")
  {
    auto r = vtkSmartPointer<vtkXMLPolyDataReader>::New();
    r->SetFileName(path.c_str());
    reader = r;
  }
  else if (ext == "vtu")
  {
    auto r = vtkSmartPointer<vtkXMLUnstructuredGridReader>::New();
    r->SetFileName(path.c_str());
    reader = r;
  }
  else if (ext == "node" || ext == "ele")
  {
    auto r = vtkSmartPointer<vtkTetGenReader>::New();
    r->SetFileName(path.c_str());
    reader = r;
  }
  else
  {
    error = "unknown mesh format '." + ext + "' of '" + path +
      "' (use .ply, .stl, .obj, .vtp, .vtu, .node or .ele)";
    return false;
  }
  messages.Watch(reader);
  reader->Update();
  vtkDataObject* data = reader->GetOutputDataObject(0);
  if (!messages.Errors.empty())
  {
    error = "cannot read '" + path + "': " + messages.Last();
    return false;
  }
  if (auto* poly = vtkPolyData::SafeDownCast(data))
  {
    surface = poly;
  }
  else if (auto* ug = vtkUnstructuredGrid::SafeDownCast(data))
  {
    grid = ug;
  }
  if ((surface && surface->GetNumberOfCells() == 0) || (grid && grid->GetNumberOfCells() == 0) ||
    (!surface && !grid))
  {
    error = "'" + path + "' holds no cells";
    return false;
  }
  return true;
}

template <class Writer, class Data>
bool WriteAtomically(Data* data, const std::string& path, std::string& error)
{
  const std::string tmp = path + ".tmp";
  vtkNew<Writer> writer;
  writer->SetInputData(data);
  writer->SetFileName(tmp.c_str());
  writer->SetDataModeToAppended();
  writer->SetCompressorTypeToZLib();
  if (writer->Write() == 0)
  {
    std::remove(tmp.c_str());
    error = "cannot write '" + path + "'";
    return false;
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0)
  {
    std::remove(tmp.c_str());
    error = "cannot rename the temporary file to '" + path + "'";
    return false;
  }
  return true;
}

bool WriteText(const std::string& path, const std::string& text, std::string& error)
{
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp);
    out << text;
    if (!out)
    {
      error = "cannot write '" + path + "'";
      return false;
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0)
  {
    std::remove(tmp.c_str());
    error = "cannot rename the temporary file to '" + path + "'";
    return false;
  }
  return true;
}

/// Make sure the directory holding `path` exists (like mkdir -p).
void EnsureParentDirectory(const std::string& path)
{
  const size_t slash = path.find_last_of('/');
  if (slash == std::string::npos || slash == 0)
  {
    return;
  }
  std::string dir = path.substr(0, slash);
  std::string command = "mkdir -p '" + dir + "'";
  if (std::system(command.c_str()) != 0)
  {
    std::cerr << "translucency: warning: cannot create directory '" << dir << "'\n";
  }
}

void ApplyMaterial(vtkAssignScatteringCoefficients* assign, const std::string& material)
{
  if (Extension(material) != "json")
  {
    assign->SetMaterialName(material.c_str());
    return;
  }
  std::ifstream in(material);
  if (!in)
  {
    throw translucency::Error("cannot open material file '" + material + "'");
  }
  json j;
  try
  {
    in >> j;
  }
  catch (const std::exception& e)
  {
    throw translucency::Error("material file '" + material + "' is not valid JSON: " + e.what());
  }
  auto triple = [&](const char* key, double out[3]) {
    if (!j.contains(key) || !j[key].is_array() || j[key].size() != 3)
    {
      throw translucency::Error("material file '" + material + "' needs \"" + key +
        "\": [r, g, b] (1/mm)");
    }
    for (int c = 0; c < 3; ++c)
    {
      if (!j[key][c].is_number())
      {
        throw translucency::Error(
          "material file '" + material + "': \"" + key + "\" must hold three numbers");
      }
      out[c] = j[key][c].get<double>();
    }
  };
  if (!j.is_object())
  {
    throw translucency::Error("material file '" + material +
      "' must hold a JSON object {\"absorption\": [r, g, b], ...}");
  }
  if (j.contains("preset"))
  {
    if (!j["preset"].is_string())
    {
      throw translucency::Error(
        "material file '" + material + "': \"preset\" must be a preset name (a string)");
    }
    assign->SetMaterialName(j["preset"].get<std::string>().c_str());
    return;
  }
  double muA[3], sigmaS[3];
  triple("absorption", muA);
  triple("reduced_scattering", sigmaS);
  assign->SetMaterialName("");
  assign->SetAbsorptionCoefficient(muA);
  assign->SetReducedScatteringCoefficient(sigmaS);
  if (j.contains("refractive_index") && !j["refractive_index"].is_number())
  {
    throw translucency::Error(
      "material file '" + material + "': \"refractive_index\" must be a number");
  }
  assign->SetRefractiveIndex(j.value("refractive_index", 1.3));
}

int Render(const std::vector<std::string>& args)
{
  std::string meshPath, material, outputPrefix, pngPath, slicePath, jsonPath;
  vtkIdType targetTets = 200000;
  double maxTetVolume = 0.0, quality = 1.414, relTol = 1e-6, exposure = 0.0;
  int maxIter = 2000, uniformSamples = 32;
  bool shadows = true, targetGiven = false;
  std::vector<Light> lights;
  translucency_app::RadianceImageOptions image;

  for (size_t i = 0; i < args.size(); ++i)
  {
    const std::string& a = args[i];
    auto value = [&]() -> const std::string& {
      if (i + 1 >= args.size())
      {
        throw UsageError(a + " needs a value");
      }
      return args[++i];
    };
    auto number = [&]() { return ParseNumbers(value(), a).at(0); };
    if (a == "--mesh")
      meshPath = value();
    else if (a == "--target-tets")
    {
      const double n = number();
      if (!(n >= 1))
        throw UsageError("--target-tets must be >= 1");
      targetTets = static_cast<vtkIdType>(n);
      targetGiven = true;
    }
    else if (a == "--max-tet-volume")
    {
      maxTetVolume = number();
      if (!(maxTetVolume > 0))
        throw UsageError("--max-tet-volume must be > 0 (mm^3)");
    }
    else if (a == "--quality")
    {
      quality = number();
      if (!(quality >= 1.1))
        throw UsageError("--quality must be >= 1.1");
    }
    else if (a == "--material")
      material = value();
    else if (a == "--light")
      lights.push_back(ParseLight(value()));
    else if (a == "--no-shadows")
      shadows = false;
    else if (a == "--uniform-samples")
      uniformSamples = static_cast<int>(number());
    else if (a == "--rel-tol")
      relTol = number();
    else if (a == "--max-iter")
      maxIter = static_cast<int>(number());
    else if (a == "--output")
      outputPrefix = value();
    else if (a == "--png")
      pngPath = value();
    else if (a == "--slice-png")
      slicePath = value();
    else if (a == "--json")
      jsonPath = value();
    else if (a == "--exposure")
      exposure = number();
    else if (a == "--view" || a == "--up")
    {
      std::vector<double> v = ParseNumbers(value(), a);
      if (v.size() != 3 || (v[0] == 0 && v[1] == 0 && v[2] == 0))
        throw UsageError(a + " needs three numbers, not all zero");
      std::copy(v.begin(), v.end(), a == "--view" ? image.ViewDirection : image.ViewUp);
    }
    else if (a == "--size")
    {
      const std::string s = value();
      if (std::sscanf(s.c_str(), "%dx%d", &image.Width, &image.Height) != 2 || image.Width < 16 ||
        image.Height < 16 || image.Width > 8192 || image.Height > 8192)
        throw UsageError("--size must be WxH, e.g. 800x600");
    }
    else if (a == "--list-materials")
    {
      for (const auto& p : translucency::GetMaterialPresets())
      {
        std::cout << std::left << std::setw(12) << p.Name << " sigma_s' = (" << p.ReducedScattering[0]
                  << ", " << p.ReducedScattering[1] << ", " << p.ReducedScattering[2]
                  << ") 1/mm, mu_a = (" << p.Absorption[0] << ", " << p.Absorption[1] << ", "
                  << p.Absorption[2] << ") 1/mm, eta = " << p.RefractiveIndex << "\n";
      }
      return 0;
    }
    else
      throw UsageError("unknown option '" + a + "' (see translucency --help)");
  }
  if (meshPath.empty())
  {
    throw UsageError("render needs --mesh FILE");
  }
  if (lights.empty())
  {
    lights.push_back(ParseLight("directional:0,-1,-1:1"));
    lights.push_back(ParseLight("uniform:0.1"));
  }
  if (relTol <= 0 || relTol >= 1)
    throw UsageError("--rel-tol must be in (0, 1)");
  if (maxIter < 1)
    throw UsageError("--max-iter must be >= 1");
  if (uniformSamples < 0)
    throw UsageError("--uniform-samples must be >= 0");

  std::vector<Stage> stages;
  std::string error;
  MessageCollector messages;

  // 1. Read.
  auto start = Clock::now();
  vtkSmartPointer<vtkPolyData> surface;
  vtkSmartPointer<vtkUnstructuredGrid> grid;
  if (!ReadMesh(meshPath, surface, grid, error))
  {
    throw translucency::Error(error);
  }
  stages.push_back({ "read", Since(start) });

  // 2. Tetrahedralize.
  if (surface)
  {
    start = Clock::now();
    vtkNew<vtkTetrahedralizeSurface> tetra;
    messages.Watch(tetra);
    tetra->SetInputData(surface);
    tetra->SetQuality(quality);
    if (maxTetVolume > 0 && !targetGiven)
      tetra->SetMaxTetVolume(maxTetVolume);
    else
      tetra->SetTargetNumberOfTets(targetTets);
    tetra->Update();
    if (!messages.Errors.empty())
      throw translucency::Error("'" + meshPath + "': " + messages.Last());
    grid = tetra->GetOutput();
    stages.push_back({ "tetrahedralize", Since(start) });
  }

  // 3. Coefficients.
  start = Clock::now();
  vtkSmartPointer<vtkUnstructuredGrid> withMaterial = grid;
  const bool hasArrays = grid->GetCellData()->GetArray("AbsorptionCoefficient") &&
    grid->GetCellData()->GetArray("ReducedScatteringCoefficient") &&
    grid->GetCellData()->GetArray("RefractiveIndex");
  if (!material.empty() || !hasArrays)
  {
    vtkNew<vtkAssignScatteringCoefficients> assign;
    messages.Watch(assign);
    ApplyMaterial(assign, material.empty() ? std::string("marble") : material);
    assign->SetInputData(grid);
    assign->Update();
    if (!messages.Errors.empty())
      throw translucency::Error(messages.Last());
    withMaterial = assign->GetOutput();
  }
  stages.push_back({ "coefficients", Since(start) });

  // 4. Irradiance.
  start = Clock::now();
  vtkNew<vtkSurfaceIrradiance> irradiance;
  messages.Watch(irradiance);
  irradiance->SetInputData(withMaterial);
  irradiance->SetShadows(shadows);
  irradiance->SetUniformLightSamples(uniformSamples);
  double uniformE = 0.0;
  for (const Light& l : lights)
  {
    if (l.Type == "directional")
      irradiance->AddDirectionalLight(l.Values[0], l.Values[1], l.Values[2], l.Power);
    else if (l.Type == "point")
      irradiance->AddPointLight(l.Values[0], l.Values[1], l.Values[2], l.Power);
    else
      uniformE += l.Power;
  }
  irradiance->SetUniformLightIrradiance(uniformE);
  irradiance->Update();
  if (!messages.Errors.empty())
    throw translucency::Error(messages.Last());
  const double irradianceTopology = irradiance->GetTopologyTime();
  stages.push_back({ "irradiance", Since(start) - irradianceTopology });

  // 5. Solve.
  vtkNew<vtkSolveDiffusion> solve;
  messages.Watch(solve);
  solve->SetInputConnection(irradiance->GetOutputPort());
  solve->SetRelTol(relTol);
  solve->SetMaxIter(maxIter);
  solve->Update();
  if (!messages.Errors.empty())
    throw translucency::Error(messages.Last());
  // The topology is built once, by the first filter that needs it.
  stages.push_back({ "topology", irradianceTopology + solve->GetTopologyTime() });
  stages.push_back({ "assembly", solve->GetAssemblyTime() });
  stages.push_back({ "solve", solve->GetSolveTime() });
  vtkUnstructuredGrid* solved = solve->GetOutput();

  // 6. Radiance.
  start = Clock::now();
  vtkNew<vtkOutgoingRadiance> radiance;
  messages.Watch(radiance);
  radiance->SetInputData(solved);
  radiance->Update();
  if (!messages.Errors.empty())
    throw translucency::Error(messages.Last());
  vtkPolyData* outSurface = radiance->GetOutput();
  stages.push_back({ "radiance", Since(start) });

  // 7. Outputs.
  if (!outputPrefix.empty())
  {
    start = Clock::now();
    EnsureParentDirectory(outputPrefix + ".vtu");
    if (!WriteAtomically<vtkXMLUnstructuredGridWriter>(solved, outputPrefix + ".vtu", error) ||
      !WriteAtomically<vtkXMLPolyDataWriter>(outSurface, outputPrefix + ".vtp", error))
      throw translucency::Error(error);
    stages.push_back({ "write", Since(start) });
  }
  if (!pngPath.empty() || !slicePath.empty())
  {
    start = Clock::now();
    image.Exposure = exposure;
    if (!pngPath.empty())
    {
      EnsureParentDirectory(pngPath);
      if (!translucency_app::WriteRadiancePNG(outSurface, image, pngPath, error))
        throw translucency::Error(error);
    }
    if (!slicePath.empty())
    {
      EnsureParentDirectory(slicePath);
      if (!translucency_app::WriteFluenceSlicePNG(solved, image, slicePath, error))
        throw translucency::Error(error);
    }
    stages.push_back({ "render", Since(start) });
  }

  // 8. Report.
  const vtkIdType numPoints = solved->GetNumberOfPoints();
  const vtkIdType numTets = solved->GetNumberOfCells();
  const vtkIdType numBoundary = outSurface->GetNumberOfPoints();
  std::cout << "mesh: " << numPoints << " points, " << numTets << " tets, " << numBoundary
            << " boundary points\n";
  std::cout << "solver: divergence + conjugate gradient (Jacobi)\n";
  static const char* channel[3] = { "R", "G", "B" };
  for (int c = 0; c < 3; ++c)
  {
    std::cout << "  channel " << channel[c] << ": " << solve->GetNumberOfIterations(c)
              << " iterations, relative residual " << std::scientific << std::setprecision(2)
              << solve->GetFinalResidual(c) << std::defaultfloat
              << (solve->GetConverged(c) ? "" : " (NOT converged)") << "\n";
  }
  std::cout << "\n  stage            time (ms)\n  ---------------- ---------\n";
  double total = 0.0;
  for (const Stage& s : stages)
  {
    std::cout << "  " << std::left << std::setw(16) << s.Name << " " << std::right << std::setw(9)
              << std::fixed << std::setprecision(1) << s.Milliseconds << "\n";
    total += s.Milliseconds;
  }
  std::cout << "  " << std::left << std::setw(16) << "total" << " " << std::right << std::setw(9)
            << total << std::defaultfloat << "\n";

  if (!jsonPath.empty())
  {
    json j;
    j["mesh"] = meshPath;
    j["points"] = numPoints;
    j["tets"] = numTets;
    j["boundary_points"] = numBoundary;
    j["solver"] = solve->GetSolverName();
    j["linear_solver"] = "cg-jacobi";
    for (int c = 0; c < 3; ++c)
    {
      j["channels"][channel[c]] = { { "iterations", solve->GetNumberOfIterations(c) },
        { "relative_residual", solve->GetFinalResidual(c) },
        { "converged", solve->GetConverged(c) } };
    }
    for (const Stage& s : stages)
    {
      j["times_ms"][s.Name] = s.Milliseconds;
    }
    j["times_ms"]["total"] = total;
    EnsureParentDirectory(jsonPath);
    if (!WriteText(jsonPath, j.dump(2) + "\n", error))
      throw translucency::Error(error);
  }
  return 0;
}

double Median(std::vector<double> v)
{
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

int Bench(const std::vector<std::string>& args)
{
  std::string meshPath = "Data/bunny.ply", jsonPath;
  std::vector<double> sizes = { 100000, 1000000 };
  int runs = 7;
  for (size_t i = 0; i < args.size(); ++i)
  {
    const std::string& a = args[i];
    auto value = [&]() -> const std::string& {
      if (i + 1 >= args.size())
        throw UsageError(a + " needs a value");
      return args[++i];
    };
    if (a == "--mesh")
      meshPath = value();
    else if (a == "--tets")
      sizes = ParseNumbers(value(), a);
    else if (a == "--runs")
      runs = static_cast<int>(ParseNumbers(value(), a).at(0));
    else if (a == "--json")
      jsonPath = value();
    else
      throw UsageError("unknown option '" + a + "' (see translucency --help)");
  }
  if (runs < 1)
    throw UsageError("--runs must be >= 1");
  std::string error;
  vtkSmartPointer<vtkPolyData> surface;
  vtkSmartPointer<vtkUnstructuredGrid> grid;
  if (!ReadMesh(meshPath, surface, grid, error))
    throw translucency::Error(error);
  if (!surface)
    throw translucency::Error("bench needs a surface mesh (.ply, .stl, .obj, .vtp)");

  json results = json::array();
  std::cout << "threads: " << omp_get_max_threads() << ", runs per figure: " << runs
            << " (medians)\n\n";
  std::cout << "  target     tets   points     nnz  tetgen(ms) topology(ms) assembly(ms) "
               "spmv(ms) asm/spmv  solve(ms) iters(R) solve/spmv\n";
  for (double target : sizes)
  {
    MessageCollector messages;
    auto start = Clock::now();
    vtkNew<vtkTetrahedralizeSurface> tetra;
    messages.Watch(tetra);
    tetra->SetInputData(surface);
    tetra->SetTargetNumberOfTets(static_cast<vtkIdType>(target));
    tetra->Update();
    if (!messages.Errors.empty())
      throw translucency::Error(messages.Last());
    const double tetgenMs = Since(start);
    vtkNew<vtkAssignScatteringCoefficients> assign;
    assign->SetInputConnection(tetra->GetOutputPort());
    vtkNew<vtkSurfaceIrradiance> light;
    light->SetInputConnection(assign->GetOutputPort());
    light->AddDirectionalLight(0, -1, -1, 1.0);
    light->SetUniformLightIrradiance(0.1);
    light->SetUniformLightSamples(0);
    light->Update();
    vtkUnstructuredGrid* g = light->GetOutput();

    // Core types, as vtkSolveDiffusion builds them.
    std::vector<double> points(3 * g->GetNumberOfPoints());
    for (vtkIdType i = 0; i < g->GetNumberOfPoints(); ++i)
      g->GetPoint(i, &points[3 * i]);
    std::vector<int> tets(4 * g->GetNumberOfCells());
    const vtkIdType* ids;
    vtkIdType npts;
    for (vtkIdType c = 0; c < g->GetNumberOfCells(); ++c)
    {
      g->GetCellPoints(c, npts, ids);
      for (int k = 0; k < 4; ++k)
        tets[4 * c + k] = static_cast<int>(ids[k]);
    }
    translucency::OpticalProperties material;
    const translucency::MaterialPreset& marble = translucency::FindMaterialPreset("marble");
    material = translucency::OpticalProperties::Uniform(static_cast<int>(g->GetNumberOfCells()),
      marble.Absorption, marble.ReducedScattering, marble.RefractiveIndex);
    std::vector<double> q(3 * g->GetNumberOfPoints());
    vtkDataArray* qa = g->GetPointData()->GetArray("Irradiance");
    for (vtkIdType i = 0; i < g->GetNumberOfPoints(); ++i)
      for (int c = 0; c < 3; ++c)
        q[3 * i + c] = qa->GetComponent(i, c);

    std::vector<double> topo, assembly, spmv, solveTimes;
    translucency::TetMesh mesh;
    for (int r = 0; r < runs; ++r)
    {
      start = Clock::now();
      mesh.SetGeometry(points, tets);
      topo.push_back(Since(start));
    }
    translucency::DiscreteDivergence disc;
    translucency::DiffusionSystem system;
    for (int r = 0; r < runs; ++r)
    {
      start = Clock::now();
      disc.Assemble(mesh, material, q, system);
      assembly.push_back(Since(start));
    }
    Eigen::VectorXd x = Eigen::VectorXd::Ones(system.NumberOfUnknowns), y(system.NumberOfUnknowns);
    for (int r = 0; r < runs; ++r)
    {
      start = Clock::now();
      y.noalias() = system.Matrix(0) * x;
      spmv.push_back(Since(start));
    }
    translucency::ConjugateGradient cg;
    cg.SetRelTol(1e-6);
    int iterations = 0;
    for (int r = 0; r < runs; ++r)
    {
      std::array<Eigen::VectorXd, 3> solution;
      start = Clock::now();
      cg.Solve(system, solution, false);
      solveTimes.push_back(Since(start));
      iterations = cg.GetNumIterations(0);
    }
    const double a = Median(assembly), s = Median(spmv), so = Median(solveTimes);
    std::cout << std::fixed << std::setprecision(2) << "  " << std::setw(7)
              << static_cast<long>(target) << " " << std::setw(8) << mesh.GetNumberOfTets() << " "
              << std::setw(8) << mesh.GetNumberOfPoints() << " " << std::setw(8)
              << mesh.GetNumberOfNonZeros() << " " << std::setw(10) << tetgenMs << " "
              << std::setw(12) << Median(topo) << " " << std::setw(12) << a << " " << std::setw(8)
              << s << " " << std::setw(8) << a / s << " " << std::setw(10) << so << " "
              << std::setw(8) << iterations << " " << std::setw(10) << so / s << "\n"
              << std::defaultfloat;
    results.push_back({ { "target_tets", target }, { "tets", mesh.GetNumberOfTets() },
      { "points", mesh.GetNumberOfPoints() }, { "nonzeros", mesh.GetNumberOfNonZeros() },
      { "tetgen_ms", tetgenMs }, { "topology_ms_median", Median(topo) },
      { "assembly_3ch_ms_median", a }, { "spmv_1ch_ms_median", s },
      { "solve_3ch_ms_median", so }, { "cg_iterations_R", iterations },
      { "assembly_over_spmv", a / s }, { "solve_over_spmv", so / s } });
  }
  if (!jsonPath.empty() && !WriteText(jsonPath, results.dump(2) + "\n", error))
    throw translucency::Error(error);
  return 0;
}
}

int main(int argc, char* argv[])
{
  std::vector<std::string> args(argv + 1, argv + argc);
  // Filter messages are reported through observers, not VTK's output window.
  vtkOutputWindow::GetInstance()->SetDisplayModeToNever();
  try
  {
    if (args.empty() || args[0] == "--help" || args[0] == "-h" || args[0] == "help")
    {
      std::cout << Usage;
      return args.empty() ? 2 : 0;
    }
    const std::string command = args[0];
    args.erase(args.begin());
    if (std::find(args.begin(), args.end(), "--help") != args.end())
    {
      std::cout << Usage;
      return 0;
    }
    if (command == "render")
      return Render(args);
    if (command == "bench")
      return Bench(args);
    throw UsageError("unknown command '" + command + "' (render or bench)");
  }
  catch (const UsageError& e)
  {
    std::cerr << "translucency: usage error: " << e.what() << "\n";
    return 2;
  }
  catch (const std::exception& e)
  {
    std::cerr << "translucency: error: " << e.what() << "\n";
    return 1;
  }
}
