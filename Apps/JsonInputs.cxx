#include "JsonInputs.h"
#include "Utilities.h"

#include "Error.h"
#include "InputFiles.h"
#include "Strings.h"

#include "vtkAssignScatteringCoefficients.h"
#include "vtkPaintScatteringCoefficients.h"
#include "vtkStrokeCut.h"

#include <vtkCellArray.h>
#include <vtkNew.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>

#include "vtk_nlohmannjson.h"
#include VTK_NLOHMANN_JSON(json.hpp)

#include <cmath>
#include <fstream>
#include <sstream>
#include <vector>

namespace translucency_app
{
using json = nlohmann::json;

namespace
{
/// The largest coefficient (1/mm) a material file may give: a mean free
/// path of 1 nm. 1e308 passed the core's checks and gave a
/// NaN fluence.
constexpr double MaxCoefficient = 1e6;

/// Parse the JSON file `path` (a regular file within the size bound,
/// translucency::ReadInputFile); `kind` ("material file") names it in
/// messages. Nesting deeper than translucency::MaxJsonNesting is refused
/// before parsing.
json ParseJsonFile(const std::string& path, const std::string& kind)
{
  const std::string text = translucency::ReadInputFile(path, kind);
  const std::string what = kind + " '" + path + "'";
  if (translucency::JsonNestingDepth(text) > translucency::MaxJsonNesting)
  {
    throw translucency::Error(what + ": arrays/objects nested deeper than " +
      std::to_string(translucency::MaxJsonNesting) + " levels");
  }
  try
  {
    return json::parse(text);
  }
  catch (const std::exception& e)
  {
    throw translucency::Error(what + " is not valid JSON: " + translucency::Abbreviate(e.what(), 160));
  }
}
} // namespace

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
  const json j = ParseJsonFile(material, "material file");
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
      // Only the upper bound here: vtkAssignScatteringCoefficients reports a
      // negative value, naming its array.
      if (out[c] > MaxCoefficient)
      {
        std::ostringstream os;
        os << "material file '" << material << "': \"" << key << "\"[" << c
           << "] must be at most " << MaxCoefficient << " 1/mm, not " << out[c];
        throw translucency::Error(os.str());
      }
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
  const double eta = j.value("refractive_index", 1.3);
  // [0.1, 10]: 1e-320 passed the core's "> 0" and gave a NaN fluence.
  if (!(eta >= 0.1 && eta <= 10.0))
  {
    std::ostringstream os;
    os << "material file '" << material << "': \"refractive_index\" must be in [0.1, 10], not "
       << eta;
    throw translucency::Error(os.str());
  }
  assign->SetRefractiveIndex(eta);
}

namespace
{
/// Read `path` as a JSON object; `what` names the option in messages.
json ReadJsonObject(const std::string& path, const std::string& what)
{
  json j = ParseJsonFile(path, what + " file");
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
    // Coefficients (1/mm), factors, directions: 1e308 as a paint target gave a
    // NaN fluence.
    if (std::abs(out[c]) > MaxCoefficient)
    {
      std::ostringstream os;
      os << "'" << path << "': \"" << key << "\"[" << c << "] must be within +-"
         << MaxCoefficient << ", not " << out[c];
      throw translucency::Error(os.str());
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

} // namespace

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

} // namespace translucency_app
