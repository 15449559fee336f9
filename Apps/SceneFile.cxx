#include "SceneFile.h"

#include "ResourceLimits.h"

#include "JsonInputs.h"
#include "MeshIO.h"
#include "Utilities.h"

#include "Error.h"
#include "InputFiles.h"
#include "Strings.h"
#include "RadiosityScene.h"

#include "vtkAssignScatteringCoefficients.h"
#include "vtkTetrahedralizeSurface.h"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCompositeDataSet.h>
#include <vtkDoubleArray.h>
#include <vtkInformation.h>
#include <vtkNew.h>
#include <vtkPartitionedDataSetCollection.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkTriangleFilter.h>
#include <vtkUnstructuredGrid.h>

#include "vtk_nlohmannjson.h"
#include VTK_NLOHMANN_JSON(json.hpp)

#include <cmath>
#include <fstream>
#include <sstream>
#include <map>

namespace translucency_app
{

namespace
{
using json = nlohmann::json;

struct Context
{
  std::string File;
  std::string Directory;
  std::string Where; ///< "object 2 'marble'"
  [[noreturn]] void Fail(const std::string& what) const
  {
    throw translucency::Error("scene '" + File + "'" + (Where.empty() ? "" : ", " + Where) +
      ": " + what);
  }
};

/// The largest magnitude of a number in a scene file: lengths (mm), powers
/// and albedos alike. 1e308 once overflowed the ray caster's bounds (a crash).
constexpr double MaxSceneNumber = 1e6;
/// The most patches one box may have (its faces at `cell_size`).
constexpr double MaxBoxPatches = 1e6;

std::vector<double> Numbers(const json& j, const char* key, size_t count, const Context& ctx)
{
  if (!j.contains(key))
  {
    ctx.Fail(std::string("missing \"") + key + "\"");
  }
  const json& v = j[key];
  if (count == 1 && v.is_number())
  {
    return { v.get<double>() };
  }
  if (!v.is_array() || v.size() != count)
  {
    ctx.Fail(std::string("\"") + key + "\" must be " +
      (count == 1 ? "a number" : "an array of " + std::to_string(count) + " numbers"));
  }
  std::vector<double> out;
  for (const auto& x : v)
  {
    if (!x.is_number() || !std::isfinite(x.get<double>()))
    {
      ctx.Fail(std::string("\"") + key + "\" must hold finite numbers");
    }
    if (std::abs(x.get<double>()) > MaxSceneNumber)
    {
      ctx.Fail(std::string("\"") + key + "\" holds " + translucency::Abbreviate(x.dump()) +
        ", beyond +-1e6 (lengths in mm, powers in W)");
    }
    out.push_back(x.get<double>());
  }
  return out;
}

double Number(const json& j, const char* key, double fallback, const Context& ctx)
{
  return j.contains(key) ? Numbers(j, key, 1, ctx)[0] : fallback;
}

/// An integer field: a whole number from `min` to T's maximum (a cast of
/// 1e300 to int is undefined behaviour), else an error naming the key and value.
template <class T>
T Count(const json& j, const char* key, double fallback, T min, const Context& ctx)
{
  const double value = Number(j, key, fallback, ctx);
  try
  {
    return translucency::CheckedInteger<T>(value, std::string("\"") + key + "\"", min);
  }
  catch (const translucency::Error& e)
  {
    ctx.Fail(e.what());
  }
}

/// RGB from a number (grey) or an array of 3.
std::vector<double> Colour(const json& j, const char* key, const Context& ctx)
{
  if (j.contains(key) && j[key].is_number())
  {
    const double v = j[key].get<double>();
    return { v, v, v };
  }
  return Numbers(j, key, 3, ctx);
}

std::string Resolve(const std::string& directory, const std::string& file)
{
  if (file.empty() || file[0] == '/' || directory.empty())
  {
    return file;
  }
  return directory + "/" + file;
}

vtkSmartPointer<vtkPolyData> ToPolyData(const std::vector<double>& points,
  const std::vector<int>& triangles)
{
  vtkNew<vtkPoints> pts;
  pts->SetDataTypeToDouble();
  pts->SetNumberOfPoints(static_cast<vtkIdType>(points.size() / 3));
  for (size_t p = 0; p < points.size() / 3; ++p)
  {
    pts->SetPoint(static_cast<vtkIdType>(p), &points[3 * p]);
  }
  vtkNew<vtkCellArray> polys;
  for (size_t t = 0; t < triangles.size(); t += 3)
  {
    const vtkIdType ids[3] = { triangles[t], triangles[t + 1], triangles[t + 2] };
    polys->InsertNextCell(3, ids);
  }
  auto poly = vtkSmartPointer<vtkPolyData>::New();
  poly->SetPoints(pts);
  poly->SetPolys(polys);
  return poly;
}

const std::map<std::string, int> FaceNames = { { "-x", 0 }, { "+x", 1 }, { "-y", 2 },
  { "+y", 3 }, { "-z", 4 }, { "+z", 5 } };

int FaceId(const std::string& name, const Context& ctx)
{
  auto it = FaceNames.find(name);
  if (it == FaceNames.end())
  {
    ctx.Fail("unknown face '" + name + "' (-x, +x, -y, +y, -z or +z)");
  }
  return it->second;
}

/// Coefficients on a tet mesh from "material" (preset name, JSON file or
/// inline {absorption, scattering, eta}) and "coefficient_scale".
vtkSmartPointer<vtkUnstructuredGrid> AssignMaterial(
  vtkUnstructuredGrid* grid, const json& object, const Context& ctx)
{
  const bool hasArrays = grid->GetCellData()->GetArray("AbsorptionCoefficient") &&
    grid->GetCellData()->GetArray("ReducedScatteringCoefficient") &&
    grid->GetCellData()->GetArray("RefractiveIndex");
  if (!object.contains("material"))
  {
    if (hasArrays)
    {
      return grid;
    }
    ctx.Fail("translucent object without coefficients: give \"material\" (a preset name such "
             "as \"marble\", a material JSON file or {\"absorption\": [r, g, b], "
             "\"scattering\": [r, g, b], \"eta\": 1.3}) or a .vtu with the coefficient arrays");
  }
  MessageCollector messages;
  vtkNew<vtkAssignScatteringCoefficients> assign;
  messages.Watch(assign);
  const json& m = object["material"];
  if (m.is_string())
  {
    const std::string name = m.get<std::string>();
    ApplyMaterial(assign, Extension(name) == "json" ? Resolve(ctx.Directory, name) : name);
  }
  else if (m.is_object())
  {
    const std::vector<double> a = Numbers(m, "absorption", 3, ctx);
    const std::vector<double> s = Numbers(m, "scattering", 3, ctx);
    assign->SetAbsorptionCoefficient(a[0], a[1], a[2]);
    assign->SetReducedScatteringCoefficient(s[0], s[1], s[2]);
    assign->SetRefractiveIndex(Number(m, "eta", 1.3, ctx));
  }
  else
  {
    ctx.Fail("\"material\" must be a preset name, a JSON file name or an object");
  }
  const double scale = Number(object, "coefficient_scale", 1.0, ctx);
  if (!(scale > 0.0))
  {
    ctx.Fail("\"coefficient_scale\" must be > 0");
  }
  assign->SetScaleFactor(scale);
  assign->SetInputData(grid);
  assign->Update();
  if (!messages.Errors.empty())
  {
    ctx.Fail(messages.Last());
  }
  return assign->GetOutput();
}

vtkSmartPointer<vtkUnstructuredGrid> Tetrahedralize(
  vtkPolyData* surface, const json& object, const Context& ctx)
{
  MessageCollector messages;
  vtkNew<vtkTetrahedralizeSurface> tetra;
  messages.Watch(tetra);
  tetra->SetInputData(surface);
  if (object.contains("max_tet_volume"))
  {
    tetra->SetMaxTetVolume(Number(object, "max_tet_volume", 0.0, ctx));
  }
  else
  {
    tetra->SetTargetNumberOfTets(
      Count<vtkIdType>(object, "target_tets", 20000.0, 1, ctx));
  }
  tetra->Update();
  if (!messages.Errors.empty())
  {
    ctx.Fail(messages.Last());
  }
  vtkSmartPointer<vtkUnstructuredGrid> grid = tetra->GetOutput();
  return grid;
}

} // namespace

namespace
{
/// LoadScene: the scene file read and parsed (nesting checked first), with
/// at least one object.
json ReadSceneJson(const std::string& path, Context& ctx)
{
  ctx.File = path;
  const size_t slash = path.find_last_of('/');
  ctx.Directory = slash == std::string::npos ? std::string() : path.substr(0, slash);
  // A regular file within the size bound (not a FIFO or /dev/zero).
  const std::string text = translucency::ReadInputFile(path, "scene file");
  if (translucency::JsonNestingDepth(text) > translucency::MaxJsonNesting)
  {
    ctx.Fail("arrays/objects nested deeper than " + std::to_string(translucency::MaxJsonNesting) +
      " levels");
  }
  json j;
  try
  {
    j = json::parse(text);
  }
  catch (const std::exception& e)
  {
    ctx.Fail(std::string("not valid JSON: ") + translucency::Abbreviate(e.what(), 160));
  }
  if (!j.is_object() || !j.contains("objects") || !j["objects"].is_array() ||
    j["objects"].empty())
  {
    ctx.Fail("needs \"objects\": [ ... ] with at least one object");
  }
  return j;
}

/// LoadScene: object `index` of the file (a box or a tetrahedralised mesh)
/// as partition `index` of the scene.
void LoadSceneObject(const json& object, unsigned int index, double defaultCell,
  double cellSizeOverride, Context& ctx, LoadedScene& scene)
{
  const std::string name =
    object.contains("name") && object["name"].is_string() ? object["name"].get<std::string>()
                                                          : "object " + std::to_string(index);
  ctx.Where = "object " + std::to_string(index) + " '" + translucency::Abbreviate(name) + "'";
  if (!object.is_object())
  {
    ctx.Fail("every object must be a JSON object");
  }
  const bool translucent = object.value("translucent", false);
  const std::string type = object.value("type", object.contains("file") ? "mesh" : "box");
  const double cell =
    cellSizeOverride > 0.0 ? cellSizeOverride : Number(object, "cell_size", defaultCell, ctx);
  vtkSmartPointer<vtkDataObject> data;
  if (type == "box")
  {
    const std::vector<double> lo = Numbers(object, "min", 3, ctx);
    const std::vector<double> hi = Numbers(object, "max", 3, ctx);
    const bool inward = object.value("inward", false);
    const int open = object.contains("open_face")
      ? FaceId(object["open_face"].get<std::string>(), ctx)
      : -1;
    if (cell > 0.0)
    {
      double d[3], patches = 0.0;
      for (int k = 0; k < 3; ++k)
        d[k] = std::ceil(std::abs(hi[k] - lo[k]) / cell);
      patches = 2.0 * (d[0] * d[1] + d[1] * d[2] + d[0] * d[2]);
      if (patches > MaxBoxPatches)
      {
        std::ostringstream os;
        os << "the box would have about " << patches << " patches at cell_size " << cell
           << " mm (at most " << MaxBoxPatches << "): raise cell_size";
        ctx.Fail(os.str());
      }
    }
    std::vector<double> points;
    std::vector<int> triangles, faces;
    try
    {
      translucency::RadiosityScene::BoxSurface(
        lo.data(), hi.data(), cell, inward, open, points, triangles, &faces);
    }
    catch (const translucency::Error& e)
    {
      ctx.Fail(e.what());
    }
    vtkSmartPointer<vtkPolyData> surface = ToPolyData(points, triangles);
    if (translucent)
    {
      if (inward || open >= 0)
      {
        ctx.Fail("a translucent box must be closed and face outwards");
      }
      data = AssignMaterial(Tetrahedralize(surface, object, ctx), object, ctx);
    }
    else
    {
      std::vector<double> colour = Colour(object, "albedo", ctx);
      std::map<int, std::vector<double>> faceColour;
      if (object.contains("face_albedo"))
      {
        if (!object["face_albedo"].is_object())
        {
          ctx.Fail("\"face_albedo\" must map face names to colours");
        }
        for (auto it = object["face_albedo"].begin(); it != object["face_albedo"].end(); ++it)
        {
          faceColour[FaceId(it.key(), ctx)] = Colour(object["face_albedo"], it.key().c_str(), ctx);
        }
      }
      vtkNew<vtkDoubleArray> albedo;
      albedo->SetName("Albedo");
      albedo->SetNumberOfComponents(3);
      for (int f : faces)
      {
        auto it = faceColour.find(f);
        const std::vector<double>& c = it != faceColour.end() ? it->second : colour;
        albedo->InsertNextTuple(c.data());
      }
      surface->GetCellData()->AddArray(albedo);
      data = surface;
    }
  }
  else if (type == "mesh")
  {
    if (!object.contains("file") || !object["file"].is_string())
    {
      ctx.Fail("a mesh object needs \"file\"");
    }
    const std::string file = Resolve(ctx.Directory, object["file"].get<std::string>());
    vtkSmartPointer<vtkPolyData> surface;
    vtkSmartPointer<vtkUnstructuredGrid> grid;
    std::string error;
    if (!ReadMesh(file, surface, grid, error))
    {
      ctx.Fail(error);
    }
    if (translucent)
    {
      if (!grid)
      {
        grid = Tetrahedralize(surface, object, ctx);
      }
      data = AssignMaterial(grid, object, ctx);
    }
    else
    {
      if (!surface)
      {
        ctx.Fail("an opaque object needs a surface file (.ply .stl .obj .vtp), not a tet mesh");
      }
      vtkNew<vtkTriangleFilter> triangulate;
      triangulate->SetInputData(surface);
      triangulate->PassVertsOff();
      triangulate->PassLinesOff();
      triangulate->Update();
      vtkSmartPointer<vtkPolyData> tris = triangulate->GetOutput();
      if (!tris->GetCellData()->GetArray("Albedo"))
      {
        const std::vector<double> colour = Colour(object, "albedo", ctx);
        vtkNew<vtkDoubleArray> albedo;
        albedo->SetName("Albedo");
        albedo->SetNumberOfComponents(3);
        for (vtkIdType c = 0; c < tris->GetNumberOfCells(); ++c)
        {
          albedo->InsertNextTuple(colour.data());
        }
        tris->GetCellData()->AddArray(albedo);
      }
      data = tris;
    }
  }
  else
  {
    ctx.Fail("unknown type '" + type + "' (box or mesh)");
  }
  scene.Objects->SetPartition(index, 0, data);
  scene.Objects->GetMetaData(index)->Set(vtkCompositeDataSet::NAME(), name.c_str());
  scene.Names.push_back(name);
  scene.Translucent.push_back(translucent);
}

/// LoadScene: a light of the file (point, spot or directional).
translucency::LightSource LoadSceneLight(const json& l, Context& ctx)
{
  translucency::LightSource light;
  const std::string type = l.value("type", "point");
  const std::vector<double> power = Colour(l, "power", ctx);
  light.Power = { power[0], power[1], power[2] };
  if (type == "point" || type == "spot")
  {
    const std::vector<double> p = Numbers(l, "position", 3, ctx);
    light.Position = { p[0], p[1], p[2] };
    light.Type = translucency::LightSource::Kind::Point;
  }
  if (type == "directional" || type == "spot")
  {
    const std::vector<double> d = Numbers(l, "direction", 3, ctx);
    light.Direction = { d[0], d[1], d[2] };
    light.Type = translucency::LightSource::Kind::Directional;
  }
  if (type == "spot")
  {
    light.Type = translucency::LightSource::Kind::Spot;
    light.SpotCutoff = Number(l, "cutoff", 30.0, ctx);
    light.SpotExponent = Number(l, "exponent", 0.0, ctx);
  }
  else if (type != "point" && type != "directional")
  {
    ctx.Fail("unknown light type '" + type + "' (point, spot or directional)");
  }
  return light;
}

LoadedScene LoadSceneUnchecked(const std::string& path, double cellSizeOverride, Context& ctx)
{
  json j = ReadSceneJson(path, ctx);

  LoadedScene scene;
  scene.Objects = vtkSmartPointer<vtkPartitionedDataSetCollection>::New();
  const double defaultCell = Number(j, "cell_size", 2.0, ctx);
  unsigned int index = 0;
  for (const json& object : j["objects"])
  {
    LoadSceneObject(object, index, defaultCell, cellSizeOverride, ctx, scene);
    ++index;
  }

  ctx.Where.clear();
  if (!j.contains("lights") || !j["lights"].is_array() || j["lights"].empty())
  {
    ctx.Fail("needs \"lights\": [ ... ] with at least one light");
  }
  index = 0;
  for (const json& l : j["lights"])
  {
    ctx.Where = "light " + std::to_string(index++);
    scene.Lights.push_back(LoadSceneLight(l, ctx));
  }
  ctx.Where.clear();
  if (j.contains("camera"))
  {
    const json& c = j["camera"];
    ctx.Where = "camera";
    scene.Camera.Position = Numbers(c, "position", 3, ctx);
    scene.Camera.FocalPoint = Numbers(c, "focal_point", 3, ctx);
    if (c.contains("view_up"))
      scene.Camera.ViewUp = Numbers(c, "view_up", 3, ctx);
    scene.Camera.ViewAngle = Number(c, "view_angle", 40.0, ctx);
    ctx.Where.clear();
  }
  if (j.contains("radiosity"))
  {
    const json& r = j["radiosity"];
    ctx.Where = "radiosity";
    SceneSettings& s = scene.Settings;
    s.RaysPerPatch = Count<int>(r, "rays_per_patch", s.RaysPerPatch, 1, ctx);
    s.RelTol = Number(r, "rel_tol", s.RelTol, ctx);
    s.MaxIter = Count<int>(r, "max_iter", s.MaxIter, 1, ctx);
    s.SOperator = r.value("s_operator", s.SOperator);
    s.Iteration = r.value("iteration", s.Iteration);
    s.LinearSolver = r.value("linear_solver", s.LinearSolver);
    s.FormFactorThreshold = Number(r, "form_factor_threshold", s.FormFactorThreshold, ctx);
    s.VoxelSize = Number(r, "voxel_size", s.VoxelSize, ctx);
    s.MaxDistance = Number(r, "max_distance", s.MaxDistance, ctx);
  }
  return scene;
}

} // namespace

LoadedScene LoadScene(const std::string& path, double cellSizeOverride)
{
  Context ctx;
  try
  {
    return LoadSceneUnchecked(path, cellSizeOverride, ctx);
  }
  catch (const json::exception& e)
  {
    // A value of the wrong JSON type (e.g. "translucent": []) where a
    // getter expected another: name the object it was in.
    ctx.Fail("a value has the wrong JSON type (" + translucency::Abbreviate(e.what(), 160) + ")");
  }
}


} // namespace translucency_app
