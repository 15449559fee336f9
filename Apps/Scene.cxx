#include "Scene.h"
#include "JsonInputs.h"
#include "MeshIO.h"

#include "DefaultLights.h"
#include "Error.h"
#include "Strings.h"

#include "vtkAssignScatteringCoefficients.h"
#include "vtkPaintScatteringCoefficients.h"
#include "vtkStrokeCut.h"
#include "vtkSurfaceIrradiance.h"
#include "vtkTetrahedralizeSurface.h"

#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkNew.h>
#include <vtkPlane.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkStaticCellLocator.h>
#include <vtkUnstructuredGrid.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <sstream>

namespace translucency_app
{

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
  // The power: one number (every channel) or R,G,B.
  auto power = [&](const std::string& text) {
    const std::vector<double> p = ParseNumbers(text, "--light " + spec);
    if (p.size() != 1 && p.size() != 3)
    {
      throw UsageError("--light " + spec + ": the power is one number or R,G,B");
    }
    for (int c = 0; c < 3; ++c)
    {
      light.PowerRGB[c] = p.size() == 3 ? p[c] : p[0];
      if (!(light.PowerRGB[c] >= 0))
      {
        throw UsageError("--light " + spec + ": the power must be >= 0");
      }
    }
    light.Power = light.PowerRGB[0];
    light.Coloured = p.size() == 3;
  };
  auto triple = [&](const std::string& text, double out[3]) {
    const std::vector<double> v = ParseNumbers(text, "--light " + spec);
    if (v.size() != 3)
    {
      throw UsageError("--light " + spec + ": expected three comma-separated numbers");
    }
    std::copy(v.begin(), v.end(), out);
  };
  light.Type = parts[0];
  if (light.Type == "none")
  {
    if (parts.size() > 1)
    {
      throw UsageError("--light none takes no values: '" + spec + "'");
    }
    light.Power = 0.0;
    std::fill(light.PowerRGB, light.PowerRGB + 3, 0.0);
  }
  else if (light.Type == "uniform")
  {
    if (parts.size() > 2)
    {
      throw UsageError("--light uniform[:E] takes at most one value: '" + spec + "'");
    }
    if (parts.size() == 2)
    {
      light.Power = ParseNumbers(parts[1], "--light " + spec).at(0);
      std::fill(light.PowerRGB, light.PowerRGB + 3, light.Power);
    }
  }
  else if (light.Type == "directional" || light.Type == "point")
  {
    if (parts.size() < 2 || parts.size() > 3)
    {
      throw UsageError("--light " + light.Type + " needs x,y,z[:power]: '" + spec + "'");
    }
    triple(parts[1], light.Values);
    if (parts.size() == 3)
    {
      power(parts[2]);
    }
    if (light.Type == "directional" && light.Values[0] == 0 && light.Values[1] == 0 &&
      light.Values[2] == 0)
    {
      throw UsageError("--light " + spec + ": the direction is zero");
    }
  }
  else if (light.Type == "spot")
  {
    if (parts.size() < 4 || parts.size() > 5)
    {
      throw UsageError(
        "--light spot needs x,y,z:dx,dy,dz:cutoff[,exponent][:power]: '" + spec + "'");
    }
    triple(parts[1], light.Values);
    triple(parts[2], light.Axis);
    const std::vector<double> cone = ParseNumbers(parts[3], "--light " + spec);
    if (cone.size() > 2)
    {
      throw UsageError("--light " + spec + ": the cone is cutoff[,exponent]");
    }
    light.Cutoff = cone[0];
    light.Exponent = cone.size() == 2 ? cone[1] : 0.0;
    if (parts.size() == 5)
    {
      power(parts[4]);
    }
    if (light.Axis[0] == 0 && light.Axis[1] == 0 && light.Axis[2] == 0)
    {
      throw UsageError("--light " + spec + ": the axis is zero");
    }
    if (!(light.Cutoff > 0 && light.Cutoff <= 180))
    {
      throw UsageError("--light " + spec + ": the cut-off must be in (0, 180] degrees");
    }
    if (!(light.Exponent >= 0))
    {
      throw UsageError("--light " + spec + ": the exponent must be >= 0");
    }
  }
  else
  {
    throw UsageError("unknown light type '" + light.Type +
      "' (directional, point, spot, uniform or none)");
  }
  if (!(light.Power >= 0))
  {
    throw UsageError("--light " + spec + ": the power must be >= 0");
  }
  return light;
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
  const bool none = std::any_of(
    this->Lights.begin(), this->Lights.end(), [](const Light& l) { return l.Type == "none"; });
  if (none)
  {
    if (this->Lights.size() > 1)
    {
      throw UsageError("--light none cannot be combined with other --light options");
    }
    this->Lights.clear(); // no light at all
  }
  else if (this->Lights.empty() && !this->InteriorSources)
  {
    // The one default, the same as the ParaView plugin's Surface Irradiance
    // panel (Plugin/SurfaceIrradiance.xml); every report prints it.
    this->DefaultLights = true;
    std::istringstream specs(translucency::DescribeDefaultLights());
    std::string spec;
    while (specs >> spec)
    {
      this->Lights.push_back(ParseLight(spec));
    }
  }
}
/// BuildLitMesh, 2. Tetrahedralize the surface (the mesher's own name in
/// the messages); a tet count far from the target is noted.
vtkSmartPointer<vtkUnstructuredGrid> Tetrahedralize(
  const SceneOptions& options, vtkPolyData* surface, std::vector<Stage>& stages)
{
  MessageCollector messages;
  const auto start = Clock::now();
  vtkNew<vtkTetrahedralizeSurface> tetra;
  // The mesher's own name in the messages (--mesher: tetgen or hxt).
  const std::string mesher =
    translucency::ToLower(options.Mesher) == "hxt" ? "gmsh HXT" : "TetGen";
  messages.Watch(tetra, "tetrahedralizing (" + mesher + ")");
  Progress("tetrahedralizing " + options.MeshPath + " (" + mesher + ")...");
  tetra->SetInputData(surface);
  tetra->SetQuality(options.Quality);
  tetra->SetMesher(options.Mesher.c_str());
  tetra->SetUniformSizing(options.UniformSizing);
  tetra->SetGradingFactor(options.GradingFactor);
  if (options.MaxTetVolume > 0 && !options.TargetGiven)
    tetra->SetMaxTetVolume(options.MaxTetVolume);
  else
    tetra->SetTargetNumberOfTets(options.TargetTets);
  tetra->Update();
  if (!messages.Errors.empty())
    throw translucency::Error("'" + options.MeshPath + "': " + messages.Last());
  vtkSmartPointer<vtkUnstructuredGrid> grid = tetra->GetOutput();
  stages.push_back({ "tetrahedralize", MillisecondsSince(start) });
  // A count more than 25 % off the target: the filter's warning (on stderr
  // through `messages`) says why and what to do.
  return grid;
}

/// BuildLitMesh, 5. Cut (--cut-plane or --cut-stroke); the statistics in
/// `stats`.
vtkSmartPointer<vtkUnstructuredGrid> CutMesh(const SceneOptions& options,
  vtkUnstructuredGrid* withMaterialIn, std::vector<Stage>& stages, EditStats& stats)
{
  MessageCollector messages;
  vtkSmartPointer<vtkUnstructuredGrid> withMaterial = withMaterialIn;
  const auto start = Clock::now();
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
  return withMaterial;
}


void SceneOptions::AddInputs(OutputPlan& plan) const
{
  plan.Input(this->MeshPath, "--mesh");
  if (Extension(this->Material) == "json")
    plan.Input(this->Material, "--material");
  plan.Input(this->Paint, "--paint");
  plan.Input(this->CutStroke, "--cut-stroke");
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
    grid = Tetrahedralize(options, surface, stages);
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
    withMaterial = CutMesh(options, withMaterial, stages, stats);
  }

  // 6. Irradiance. A point or spot light inside the object faces no
  // surface from outside: the fluence would be all zero without a word.
  {
    vtkSmartPointer<vtkStaticCellLocator> locator;
    for (const Light& l : options.Lights)
    {
      if (l.Type != "point" && l.Type != "spot")
        continue;
      if (!locator)
      {
        locator = vtkSmartPointer<vtkStaticCellLocator>::New();
        locator->SetDataSet(withMaterial);
        locator->BuildLocator();
      }
      double x[3] = { l.Values[0], l.Values[1], l.Values[2] };
      const vtkIdType tet = locator->FindCell(x);
      if (tet >= 0)
        throw translucency::Error("--light " + l.Type + " at " + translucency::FormatPoint(x) +
          " mm is inside the object (in tet " + std::to_string(tet) +
          "): a --light shines on the surface from outside, so it would light nothing; "
          "move it outside, or use --source point:x,y,z for a source inside the object");
    }
  }
  start = Clock::now();
  vtkNew<vtkSurfaceIrradiance> irradiance;
  messages.Watch(irradiance);
  irradiance->SetInputData(withMaterial);
  irradiance->SetShadows(options.Shadows);
  irradiance->SetDefaultLights(false); // Finish() resolved the defaults: the lights are explicit
  irradiance->SetUniformLightSamples(options.UniformSamples);
  irradiance->SetCollimatedModelByName(options.Collimated.c_str()); // checked by --collimated
  double uniformE = 0.0;
  for (const Light& l : options.Lights)
  {
    const double* p = l.PowerRGB;
    if (l.Type == "directional")
      irradiance->AddDirectionalLightRGB(l.Values[0], l.Values[1], l.Values[2], p[0], p[1], p[2]);
    else if (l.Type == "point")
      irradiance->AddPointLightRGB(l.Values[0], l.Values[1], l.Values[2], p[0], p[1], p[2]);
    else if (l.Type == "spot")
      irradiance->AddSpotLight(l.Values[0], l.Values[1], l.Values[2], l.Axis[0], l.Axis[1],
        l.Axis[2], l.Cutoff, l.Exponent, p[0], p[1], p[2]);
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

} // namespace translucency_app
