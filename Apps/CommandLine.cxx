#include "CommandLine.h"
#include "PipelineRender.h"

#include "Error.h"
#include "OpticalProperties.h"
#include "Strings.h"

#include "vtkAssignScatteringCoefficients.h"
#include "vtkPaintScatteringCoefficients.h"
#include "vtkStrokeCut.h"
#include "vtkSurfaceIrradiance.h"
#include "vtkTetGenReader.h"
#include "vtkTetrahedralizeSurface.h"

#include <vtkAlgorithm.h>
#include <vtkCallbackCommand.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkExecutive.h>
#include <vtkOBJReader.h>
#include <vtkPLYReader.h>
#include <vtkPlane.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSTLReader.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLUnstructuredGridReader.h>
#include <vtkXMLWriter.h>

#include "vtk_nlohmannjson.h"
#include VTK_NLOHMANN_JSON(json.hpp)

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

namespace translucency_app
{
using json = nlohmann::json;



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
  ext = translucency::ToLower(ext);
  return ext;
}

MessageCollector::MessageCollector()
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

void MessageCollector::Watch(vtkObject* object)
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

std::string MessageCollector::Last() const
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

bool WriteAtomically(vtkXMLWriter* writer, vtkDataObject* data, const std::string& path,
  std::string& error)
{
  const std::string tmp = path + ".tmp";
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

void GridToCoreArrays(vtkUnstructuredGrid* grid, std::vector<double>& points, std::vector<int>& tets)
{
  points.resize(3 * grid->GetNumberOfPoints());
  for (vtkIdType i = 0; i < grid->GetNumberOfPoints(); ++i)
    grid->GetPoint(i, &points[3 * i]);
  tets.resize(4 * grid->GetNumberOfCells());
  const vtkIdType* ids;
  vtkIdType npts;
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c)
  {
    grid->GetCellPoints(c, npts, ids);
    for (int k = 0; k < 4; ++k)
      tets[4 * c + k] = static_cast<int>(ids[k]);
  }
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

void ApplyMaterial(vtkAssignScatteringCoefficients* assign, const std::string& material,
  const std::string& materialIds)
{
  if (Extension(material) != "json")
  {
    if (!materialIds.empty())
    {
      throw translucency::Error("--material-ids needs --material FILE.json holding a material "
                                "table {\"materials\": [...]} (got '" + material + "')");
    }
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
  if (j.contains("materials"))
  {
    // A material table (Documentation/Materials.md): the filter reads it.
    if (materialIds.empty())
    {
      throw translucency::Error("material table '" + material +
        "' needs --material-ids ARRAY (the cell array of material ids, e.g. RegionAttribute)");
    }
    assign->SetMaterialModeToMaterialIds();
    assign->SetMaterialTableFileName(material.c_str());
    assign->SetMaterialIdArrayName(materialIds.c_str());
    return;
  }
  if (!materialIds.empty())
  {
    throw translucency::Error("--material-ids needs a material table {\"materials\": [...]}, "
                              "but '" + material + "' holds a single material");
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

double Median(std::vector<double> v)
{
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}
const char* const SceneOptionsHelp = R"(  --mesh FILE              closed triangle surface (.ply .stl .obj .vtp), tet mesh
                           (.vtu), or TetGen mesh (.node/.ele). Lengths in mm.
  --target-tets N          tetrahedralize to about N tets (default 200000)
  --max-tet-volume V       ... or bound the tet volume by V mm^3 instead
  --quality Q              radius-edge ratio bound for TetGen (default 1.414)
  --material NAME|FILE     measured preset (default marble; see render --list-materials)
                           or a JSON file {"absorption": [r,g,b], "reduced_scattering":
                           [r,g,b], "refractive_index": eta} in 1/mm, or a material
                           table {"materials": [...]} (Documentation/Materials.md) used
                           with --material-ids. A .vtu input that already has the
                           coefficient arrays keeps them unless given.
  --material-ids ARRAY     cell array of integer material ids (e.g. RegionAttribute of
                           a TetGen mesh): each tet gets its entry of the table
  --light SPEC             may repeat; default directional:0,-1,-1:1 and uniform:0.1
                           directional:dx,dy,dz[:E]  direction of travel, E W/mm^2 (1)
                           point:x,y,z[:I]           position mm, intensity W/sr (1)
                           uniform[:E]               environment, E W/mm^2 (1)
  --no-shadows             no self-shadowing
  --uniform-samples N      occlusion rays per point for the uniform light (32)
  --paint FILE.json        paint the coefficients along a 3D stroke (after the material,
                           before any cut; vtkPaintScatteringCoefficients):
                           {"points": [[x,y,z], ...] (mm, required), "width": mm (1),
                            "mode": "set"|"multiply"|"add" ("set"),
                            "absorption": [r,g,b], "reduced_scattering": [r,g,b]
                            (target: 1/mm for set/add, factor for multiply; default
                            ketchup), "strength": 0..1 (1), "channels": [1,1,1],
                            "cutoff_weight": 0..1 (1e-6: no paint where the weight
                            is below it; 0 = exact Gaussian everywhere)}
  --cut-plane ox,oy,oz,nx,ny,nz
                           cut the tet mesh with the plane through o (mm) with normal n:
                           removes the side n points to (vtkStrokeCut)
  --cut-stroke FILE.json   cut along a stroke swept along the view direction:
                           {"points": [[x,y,z], ...] (>= 2, mm), "view_direction":
                           [dx,dy,dz] (default [0,0,-1]), "inside_out": false}; removes
                           the left of the stroke as seen along the view direction
                           (inside_out: the right). Order: tetrahedralize, material,
                           paint, cut, irradiance, solve.
)";

bool SceneOptions::Parse(const std::vector<std::string>& args, size_t& i)
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
    this->MeshPath = value();
  else if (a == "--target-tets")
  {
    const double n = number();
    if (!(n >= 1))
      throw UsageError("--target-tets must be >= 1");
    this->TargetTets = static_cast<long long>(n);
    this->TargetGiven = true;
  }
  else if (a == "--max-tet-volume")
  {
    this->MaxTetVolume = number();
    if (!(this->MaxTetVolume > 0))
      throw UsageError("--max-tet-volume must be > 0 (mm^3)");
  }
  else if (a == "--quality")
  {
    this->Quality = number();
    if (!(this->Quality >= 1.1))
      throw UsageError("--quality must be >= 1.1");
  }
  else if (a == "--material")
    this->Material = value();
  else if (a == "--material-ids")
    this->MaterialIds = value();
  else if (a == "--light")
    this->Lights.push_back(ParseLight(value()));
  else if (a == "--no-shadows")
    this->Shadows = false;
  else if (a == "--cut-plane")
  {
    this->CutPlane = ParseNumbers(value(), a);
    if (this->CutPlane.size() != 6)
      throw UsageError("--cut-plane needs six comma-separated numbers ox,oy,oz,nx,ny,nz");
    if (this->CutPlane[3] == 0 && this->CutPlane[4] == 0 && this->CutPlane[5] == 0)
      throw UsageError("--cut-plane: the normal is zero");
  }
  else if (a == "--cut-stroke")
    this->CutStroke = value();
  else if (a == "--paint")
    this->Paint = value();
  else if (a == "--uniform-samples")
  {
    const double n = number();
    if (!(n >= 0))
      throw UsageError("--uniform-samples must be >= 0");
    this->UniformSamples = static_cast<int>(n);
  }
  else
    return false;
  return true;
}

void SceneOptions::Finish(const std::string& command)
{
  if (!this->MaterialIds.empty() && this->Material.empty())
  {
    throw UsageError("--material-ids needs --material FILE.json (a material table)");
  }
  if (this->MeshPath.empty())
  {
    throw UsageError(command + " needs --mesh FILE");
  }
  if (!this->CutPlane.empty() && !this->CutStroke.empty())
  {
    throw UsageError("give --cut-plane or --cut-stroke, not both");
  }
  if (this->Lights.empty())
  {
    this->Lights.push_back(ParseLight("directional:0,-1,-1:1"));
    this->Lights.push_back(ParseLight("uniform:0.1"));
  }
}

namespace
{
/// Read `path` as a JSON object; `what` names the option in messages.
json ReadJsonObject(const std::string& path, const std::string& what)
{
  std::ifstream in(path);
  if (!in)
  {
    throw translucency::Error("cannot open " + what + " file '" + path + "'");
  }
  json j;
  try
  {
    in >> j;
  }
  catch (const std::exception& e)
  {
    throw translucency::Error(what + " file '" + path + "' is not valid JSON: " + e.what());
  }
  if (!j.is_object())
  {
    throw translucency::Error(what + " file '" + path + "' must hold a JSON object {...}");
  }
  return j;
}

/// A field of three numbers; false if absent.
bool ReadTriple(const json& j, const char* key, const std::string& path, double out[3])
{
  if (!j.contains(key))
  {
    return false;
  }
  const json& v = j[key];
  if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() ||
    !v[2].is_number())
  {
    throw translucency::Error(
      "'" + path + "': \"" + key + "\" must be an array of three numbers");
  }
  for (int c = 0; c < 3; ++c)
  {
    out[c] = v[c].get<double>();
    if (!std::isfinite(out[c]))
    {
      throw translucency::Error("'" + path + "': \"" + key + "\" must be finite");
    }
  }
  return true;
}

/// The required "points": [[x,y,z], ...] with at least `minimum` points.
std::vector<double> ReadStrokePoints(const json& j, const std::string& path, size_t minimum)
{
  if (!j.contains("points") || !j["points"].is_array())
  {
    throw translucency::Error("'" + path + "' needs \"points\": [[x, y, z], ...] (mm)");
  }
  const json& points = j["points"];
  if (points.size() < minimum)
  {
    throw translucency::Error("'" + path + "': \"points\" needs at least " +
      std::to_string(minimum) + " point" + (minimum > 1 ? "s" : "") + ", got " +
      std::to_string(points.size()));
  }
  std::vector<double> xyz;
  for (size_t p = 0; p < points.size(); ++p)
  {
    const json& q = points[p];
    if (!q.is_array() || q.size() != 3 || !q[0].is_number() || !q[1].is_number() ||
      !q[2].is_number() || !std::isfinite(q[0].get<double>()) ||
      !std::isfinite(q[1].get<double>()) || !std::isfinite(q[2].get<double>()))
    {
      throw translucency::Error("'" + path + "': \"points\"[" + std::to_string(p) +
        "] must be [x, y, z] (three finite numbers)");
    }
    for (int c = 0; c < 3; ++c)
      xyz.push_back(q[c].get<double>());
  }
  return xyz;
}

double ReadNumber(const json& j, const char* key, const std::string& path, double fallback)
{
  if (!j.contains(key))
    return fallback;
  if (!j[key].is_number() || !std::isfinite(j[key].get<double>()))
    throw translucency::Error("'" + path + "': \"" + key + "\" must be a number");
  return j[key].get<double>();
}

/// Configure `paint` from a --paint JSON file.
void ApplyPaintFile(vtkPaintScatteringCoefficients* paint, const std::string& path)
{
  const json j = ReadJsonObject(path, "paint");
  const std::vector<double> xyz = ReadStrokePoints(j, path, 1);
  for (size_t p = 0; p < xyz.size(); p += 3)
    paint->AddStrokePoint(xyz[p], xyz[p + 1], xyz[p + 2]);
  const double width = ReadNumber(j, "width", path, 1.0);
  if (!(width >= 0))
    throw translucency::Error("'" + path + "': \"width\" must be >= 0 (mm)");
  paint->SetWidth(width);
  const double strength = ReadNumber(j, "strength", path, 1.0);
  if (!(strength >= 0 && strength <= 1))
    throw translucency::Error("'" + path + "': \"strength\" must be in [0, 1]");
  paint->SetStrength(strength);
  const double cutoff = ReadNumber(j, "cutoff_weight", path, 1e-6);
  if (!(cutoff >= 0 && cutoff <= 1))
    throw translucency::Error("'" + path + "': \"cutoff_weight\" must be in [0, 1]");
  paint->SetCutoffWeight(cutoff);
  if (j.contains("mode"))
  {
    const std::string mode = j["mode"].is_string() ? j["mode"].get<std::string>() : "";
    if (mode == "set")
      paint->SetModeToSet();
    else if (mode == "multiply")
      paint->SetModeToMultiply();
    else if (mode == "add")
      paint->SetModeToAdd();
    else
      throw translucency::Error(
        "'" + path + "': \"mode\" must be \"set\", \"multiply\" or \"add\"");
  }
  double v[3];
  if (ReadTriple(j, "absorption", path, v))
    paint->SetTargetAbsorptionCoefficient(v);
  if (ReadTriple(j, "reduced_scattering", path, v))
    paint->SetTargetReducedScatteringCoefficient(v);
  if (ReadTriple(j, "channels", path, v))
    paint->SetChannelMask(v[0] != 0, v[1] != 0, v[2] != 0);
}

/// Configure `cut` from a --cut-stroke JSON file.
void ApplyStrokeFile(vtkStrokeCut* cut, const std::string& path)
{
  const json j = ReadJsonObject(path, "stroke");
  const std::vector<double> xyz = ReadStrokePoints(j, path, 2);
  double view[3] = { 0.0, 0.0, -1.0 };
  ReadTriple(j, "view_direction", path, view);
  if (view[0] == 0 && view[1] == 0 && view[2] == 0)
    throw translucency::Error("'" + path + "': \"view_direction\" is zero");
  if (j.contains("inside_out") && !j["inside_out"].is_boolean())
    throw translucency::Error("'" + path + "': \"inside_out\" must be true or false");
  vtkNew<vtkPoints> points;
  vtkNew<vtkCellArray> lines;
  const vtkIdType n = static_cast<vtkIdType>(xyz.size() / 3);
  lines->InsertNextCell(n);
  for (vtkIdType p = 0; p < n; ++p)
  {
    points->InsertNextPoint(&xyz[3 * p]);
    lines->InsertCellPoint(p);
  }
  vtkNew<vtkPolyData> stroke;
  stroke->SetPoints(points);
  stroke->SetLines(lines);
  cut->SetStrokeData(stroke);
  cut->SetViewDirection(view);
  cut->SetInsideOut(j.value("inside_out", false));
}
}

vtkSmartPointer<vtkUnstructuredGrid> BuildLitMesh(const SceneOptions& options,
  std::vector<Stage>& stages, double& topologyMs, EditStats* edits)
{
  std::string error;
  MessageCollector messages;

  // 1. Read.
  auto start = Clock::now();
  vtkSmartPointer<vtkPolyData> surface;
  vtkSmartPointer<vtkUnstructuredGrid> grid;
  if (!ReadMesh(options.MeshPath, surface, grid, error))
  {
    throw translucency::Error(error);
  }
  stages.push_back({ "read", MillisecondsSince(start) });

  // 2. Tetrahedralize.
  if (surface)
  {
    start = Clock::now();
    vtkNew<vtkTetrahedralizeSurface> tetra;
    messages.Watch(tetra);
    tetra->SetInputData(surface);
    tetra->SetQuality(options.Quality);
    if (options.MaxTetVolume > 0 && !options.TargetGiven)
      tetra->SetMaxTetVolume(options.MaxTetVolume);
    else
      tetra->SetTargetNumberOfTets(options.TargetTets);
    tetra->Update();
    if (!messages.Errors.empty())
      throw translucency::Error("'" + options.MeshPath + "': " + messages.Last());
    grid = tetra->GetOutput();
    stages.push_back({ "tetrahedralize", MillisecondsSince(start) });
  }

  // 3. Coefficients.
  start = Clock::now();
  vtkSmartPointer<vtkUnstructuredGrid> withMaterial = grid;
  const bool hasArrays = grid->GetCellData()->GetArray("AbsorptionCoefficient") &&
    grid->GetCellData()->GetArray("ReducedScatteringCoefficient") &&
    grid->GetCellData()->GetArray("RefractiveIndex");
  if (!options.Material.empty() || !hasArrays)
  {
    vtkNew<vtkAssignScatteringCoefficients> assign;
    messages.Watch(assign);
    ApplyMaterial(assign, options.Material.empty() ? std::string("marble") : options.Material,
      options.MaterialIds);
    assign->SetInputData(grid);
    assign->Update();
    if (!messages.Errors.empty())
      throw translucency::Error(messages.Last());
    withMaterial = assign->GetOutput();
  }
  stages.push_back({ "coefficients", MillisecondsSince(start) });
  EditStats localEdits;
  EditStats& stats = edits ? *edits : localEdits;

  // 4. Paint (--paint), on the whole mesh, before any cut.
  if (!options.Paint.empty())
  {
    start = Clock::now();
    vtkNew<vtkPaintScatteringCoefficients> paint;
    messages.Watch(paint);
    ApplyPaintFile(paint, options.Paint);
    paint->SetInputData(withMaterial);
    paint->Update();
    if (!messages.Errors.empty())
      throw translucency::Error("--paint '" + options.Paint + "': " + messages.Last());
    withMaterial = paint->GetOutput();
    vtkDataArray* weight = withMaterial->GetCellData()->GetArray("PaintWeight");
    stats.Painted = true;
    stats.PaintedTets = 0;
    for (vtkIdType c = 0; weight && c < weight->GetNumberOfTuples(); ++c)
      stats.PaintedTets += weight->GetComponent(c, 0) > 1e-6 ? 1 : 0;
    stats.PaintMs = MillisecondsSince(start);
    stages.push_back({ "paint", stats.PaintMs });
  }

  // 5. Cut (--cut-plane or --cut-stroke).
  if (!options.CutPlane.empty() || !options.CutStroke.empty())
  {
    start = Clock::now();
    vtkNew<vtkStrokeCut> cut;
    messages.Watch(cut);
    vtkNew<vtkPlane> plane;
    std::string what;
    if (!options.CutPlane.empty())
    {
      plane->SetOrigin(options.CutPlane[0], options.CutPlane[1], options.CutPlane[2]);
      plane->SetNormal(options.CutPlane[3], options.CutPlane[4], options.CutPlane[5]);
      cut->SetCutFunction(plane);
      what = "--cut-plane";
    }
    else
    {
      ApplyStrokeFile(cut, options.CutStroke);
      what = "--cut-stroke '" + options.CutStroke + "'";
    }
    cut->SetInputData(withMaterial);
    cut->Update();
    if (!messages.Errors.empty())
      throw translucency::Error(what + ": " + messages.Last());
    if (cut->GetOutput()->GetNumberOfCells() == 0)
      throw translucency::Error(what + " removes the whole mesh");
    withMaterial = cut->GetOutput();
    stats.Cut = true;
    stats.KeptTets = withMaterial->GetNumberOfCells();
    stats.MovedVertices = cut->GetNumberOfMovedVertices();
    stats.BlockedVertices = cut->GetNumberOfBlockedVertices();
    stats.CutMs = MillisecondsSince(start);
    stages.push_back({ "cut", stats.CutMs });
  }

  // 6. Irradiance.
  start = Clock::now();
  vtkNew<vtkSurfaceIrradiance> irradiance;
  messages.Watch(irradiance);
  irradiance->SetInputData(withMaterial);
  irradiance->SetShadows(options.Shadows);
  irradiance->SetUniformLightSamples(options.UniformSamples);
  double uniformE = 0.0;
  for (const Light& l : options.Lights)
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
  topologyMs = irradiance->GetTopologyTime();
  stages.push_back({ "irradiance", MillisecondsSince(start) - topologyMs });
  return irradiance->GetOutput();
}

bool ParseImageOption(const std::vector<std::string>& args, size_t& i, RadianceImageOptions& image)
{
  const std::string& a = args[i];
  auto value = [&]() -> const std::string& {
    if (i + 1 >= args.size())
      throw UsageError(a + " needs a value");
    return args[++i];
  };
  if (a == "--exposure")
    image.Exposure = ParseNumbers(value(), a).at(0);
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
  else
    return false;
  return true;
}

void PrintStages(const std::vector<Stage>& stages)
{
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
}

} // namespace translucency_app
