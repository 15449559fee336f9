// translucency radiosity: a scene of translucent and opaque diffuse objects,
// B = (I - S F)^-1 S E (TranslucentRadiosity, eq. 14), the paper's
// Fig. 6 four-panel picture, per-object .vtp files and a JSON report (with
// optional relight / translucency-change timings, --bench N).

#include "Options.h"
#include "Pictures.h"
#include "PipelineRender.h"
#include "Provenance.h"
#include "SceneFile.h"

#include "Error.h"
#include "LinearSolver.h"
#include "Strings.h"
#include "ToneMap.h"

#include "vtkTranslucentRadiosity.h"

#include <vtkActor.h>
#include <vtkCamera.h>
#include <vtkCellData.h>
#include <vtkCellDataToPointData.h>
#include <vtkCompositeDataIterator.h>
#include <vtkCompositeDataSet.h>
#include <vtkDataArray.h>
#include <vtkInformation.h>
#include <vtkNew.h>
#include <vtkPartitionedDataSet.h>
#include <vtkPartitionedDataSetCollection.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLPolyDataWriter.h>

#include "vtk_nlohmannjson.h"
#include VTK_NLOHMANN_JSON(json.hpp)

#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace translucency_app
{

namespace
{
using json = nlohmann::json;


/// Per-point RGB of `array` (cell data interpolated to the points), times
/// `exposure`, sRGB-encoded.
void Colourise(vtkPolyData* poly, const char* array, double exposure)
{
  vtkDataArray* values = poly->GetPointData()->GetArray(array);
  vtkNew<vtkUnsignedCharArray> rgb;
  rgb->SetName("RGB");
  rgb->SetNumberOfComponents(3);
  rgb->SetNumberOfTuples(poly->GetNumberOfPoints());
  for (vtkIdType i = 0; i < poly->GetNumberOfPoints(); ++i)
  {
    for (int c = 0; c < 3; ++c)
    {
      rgb->SetComponent(
        i, c, std::round(255.0 * translucency::EncodeSRGB(exposure * values->GetComponent(i, c))));
    }
  }
  poly->GetPointData()->AddArray(rgb);
}

std::vector<vtkSmartPointer<vtkPolyData>> Leaves(vtkDataObject* data)
{
  std::vector<vtkSmartPointer<vtkPolyData>> out;
  auto* composite = vtkCompositeDataSet::SafeDownCast(data);
  vtkSmartPointer<vtkCompositeDataIterator> it;
  it.TakeReference(composite->NewIterator());
  for (it->InitTraversal(); !it->IsDoneWithTraversal(); it->GoToNextItem())
  {
    if (auto* poly = vtkPolyData::SafeDownCast(it->GetCurrentDataObject()))
    {
      out.push_back(poly);
    }
  }
  return out;
}

bool WriteFourPanels(vtkDataObject* result, const SceneCamera& camera, const std::string& file,
  std::string& error)
{
  const char* arrays[4] = { "DirectRadiosity", "SubsurfaceRadiosity", "InterReflectionRadiosity",
    "Radiosity" };
  const char* titles[4] = { "direct", "subsurface only (first bounce)", "inter-reflection only",
    "combined" };
  // Smooth: cell values to the points, per object.
  std::vector<vtkSmartPointer<vtkPolyData>> smooth;
  for (const auto& leaf : Leaves(result))
  {
    vtkNew<vtkCellDataToPointData> toPoints;
    toPoints->SetInputData(leaf);
    toPoints->PassCellDataOff();
    toPoints->Update();
    smooth.push_back(vtkPolyData::SafeDownCast(toPoints->GetOutput()));
  }
  // One exposure for the four panels: the 99th percentile of the brightest
  // channel of the combined radiosity maps to 0.9.
  std::vector<double> peaks;
  for (const auto& poly : smooth)
  {
    vtkDataArray* b = poly->GetPointData()->GetArray("Radiosity");
    for (vtkIdType i = 0; i < b->GetNumberOfTuples(); ++i)
    {
      peaks.push_back(std::max({ b->GetComponent(i, 0), b->GetComponent(i, 1), b->GetComponent(i, 2) }));
    }
  }
  std::sort(peaks.begin(), peaks.end());
  const double p99 = peaks.empty() ? 1.0 : peaks[static_cast<size_t>(0.99 * (peaks.size() - 1))];
  const double exposure = p99 > 0.0 ? 0.9 / p99 : 1.0;

  const int size = 400;
  vtkSmartPointer<vtkRenderWindow> window = NewPictureWindow(4 * size, size);
  double bounds[6] = { 1e300, -1e300, 1e300, -1e300, 1e300, -1e300 };
  for (const auto& poly : smooth)
  {
    double b[6];
    poly->GetBounds(b);
    for (int d = 0; d < 3; ++d)
    {
      bounds[2 * d] = std::min(bounds[2 * d], b[2 * d]);
      bounds[2 * d + 1] = std::max(bounds[2 * d + 1], b[2 * d + 1]);
    }
  }
  for (int panel = 0; panel < 4; ++panel)
  {
    vtkNew<vtkRenderer> renderer;
    renderer->SetViewport(0.25 * panel, 0.0, 0.25 * (panel + 1), 1.0);
    renderer->SetBackground(0.0, 0.0, 0.0);
    for (const auto& poly : smooth)
    {
      vtkNew<vtkPolyData> copy;
      copy->ShallowCopy(poly);
      Colourise(copy, arrays[panel], exposure);
      vtkNew<vtkPolyDataMapper> mapper;
      mapper->SetInputData(copy);
      mapper->SetScalarModeToUsePointFieldData();
      mapper->SelectColorArray("RGB");
      mapper->SetColorModeToDirectScalars();
      mapper->ScalarVisibilityOn();
      vtkNew<vtkActor> actor;
      actor->SetMapper(mapper);
      actor->GetProperty()->LightingOff(); // the radiosity is the appearance
      renderer->AddActor(actor);
    }
    vtkCamera* cam = renderer->GetActiveCamera();
    const double centre[3] = { 0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3]),
      0.5 * (bounds[4] + bounds[5]) };
    if (camera.Position.size() == 3)
    {
      cam->SetPosition(camera.Position.data());
      cam->SetFocalPoint(camera.FocalPoint.data());
      cam->SetViewUp(camera.ViewUp.data());
      cam->SetViewAngle(camera.ViewAngle);
      renderer->ResetCameraClippingRange();
    }
    else
    {
      cam->SetFocalPoint(centre);
      cam->SetPosition(centre[0], centre[1] - 1.0, centre[2]);
      cam->SetViewUp(0.0, 0.0, 1.0);
      renderer->ResetCamera(bounds);
    }
    vtkNew<vtkTextActor> title;
    title->SetInput(titles[panel]);
    title->GetTextProperty()->SetFontSize(16);
    title->GetTextProperty()->SetColor(1.0, 1.0, 1.0);
    title->GetPositionCoordinate()->SetCoordinateSystemToNormalizedViewport();
    title->SetPosition(0.03, 0.03);
    renderer->AddActor2D(title);
    window->AddRenderer(renderer);
  }
  return Snapshot(window, file, error);
}

double MedianOf(std::vector<double> v)
{
  return v.empty() ? 0.0 : Median(std::move(v));
}

struct RadiosityOptions
{
  std::string ScenePath, Prefix, Png, JsonPath, SOperator, Iteration, LinearSolver;
  double RelTol = -1.0;   ///< -1: the scene's
  double CellSize = 0.0;  ///< 0: the scene's
  int Rays = -1;          ///< -1: the scene's
  int Bench = 0;
  bool Heuristics = false;
  const CLI::App* App = nullptr; ///< for the provenance of the JSON
};

/// Radiosity: the filter's lights, replaced by `lights`.
void SetRadiosityLights(
  vtkTranslucentRadiosity* radiosity, const std::vector<translucency::LightSource>& lights)
{
  radiosity->RemoveAllLights();
  for (const auto& l : lights)
  {
    if (l.Type == translucency::LightSource::Kind::Point)
      radiosity->AddPointLight(
        l.Position[0], l.Position[1], l.Position[2], l.Power[0], l.Power[1], l.Power[2]);
    else if (l.Type == translucency::LightSource::Kind::Directional)
      radiosity->AddDirectionalLight(
        l.Direction[0], l.Direction[1], l.Direction[2], l.Power[0], l.Power[1], l.Power[2]);
    else
      radiosity->AddSpotLight(l.Position[0], l.Position[1], l.Position[2], l.Direction[0],
        l.Direction[1], l.Direction[2], l.SpotCutoff, l.SpotExponent, l.Power[0], l.Power[1],
        l.Power[2]);
  }
}

/// Radiosity --bench: `bench` relights (the first light moved a little each
/// time: form factors and S kept, warm-started diffusion solves) and
/// translucency changes (every translucent object's coefficients scaled),
/// their median times in the report.
void RunRadiosityBench(vtkTranslucentRadiosity* radiosity, LoadedScene& scene, int bench,
  MessageCollector& messages, json& report, std::vector<Stage>& stages)
{
  auto addLights = [&](const std::vector<translucency::LightSource>& lights) {
    SetRadiosityLights(radiosity, lights);
  };
  auto start = Clock::now();
  // Relight: move the first light a little each time (form factors and S
  // are kept; warm-started diffusion solves).
  std::vector<double> relightTotal, relightCore, changeTotal, changeCore;
  std::vector<int> relightIterations, changeIterations;
  for (int r = 0; r < bench; ++r)
  {
    std::vector<translucency::LightSource> lights = scene.Lights;
    lights[0].Position[0] += (r % 2 ? -1.0 : 1.0) * 0.02 * (r + 1);
    addLights(lights);
    start = Clock::now();
    radiosity->Update();
    relightTotal.push_back(MillisecondsSince(start));
    relightCore.push_back(radiosity->GetDirectTime() + radiosity->GetSolveTime());
    relightIterations.push_back(radiosity->GetNumberOfIterations());
  }
  addLights(scene.Lights);
  // Translucency change: scale the coefficients of every translucent object.
  bool anyTranslucent = false;
  for (int r = 0; r < bench; ++r)
  {
    const double factor = r % 2 ? 2.0 : 0.5;
    for (unsigned int k = 0; k < scene.Objects->GetNumberOfPartitionedDataSets(); ++k)
    {
      if (!scene.Translucent[k])
        continue;
      anyTranslucent = true;
      auto* grid = vtkUnstructuredGrid::SafeDownCast(scene.Objects->GetPartition(k, 0));
      for (const char* name : { "AbsorptionCoefficient", "ReducedScatteringCoefficient" })
      {
        vtkDataArray* a = grid->GetCellData()->GetArray(name);
        for (vtkIdType t = 0; t < a->GetNumberOfTuples(); ++t)
          for (int c = 0; c < 3; ++c)
            a->SetComponent(t, c, a->GetComponent(t, c) * factor);
        a->Modified();
      }
      grid->Modified();
    }
    if (!anyTranslucent)
      break;
    radiosity->Modified();
    start = Clock::now();
    radiosity->Update();
    changeTotal.push_back(MillisecondsSince(start));
    changeCore.push_back(
      radiosity->GetSetupTime() + radiosity->GetDirectTime() + radiosity->GetSolveTime());
    changeIterations.push_back(radiosity->GetNumberOfIterations());
  }
  if (!messages.Errors.empty())
    throw translucency::Error(messages.Last());
  report["bench"] = { { "repeats", bench },
    { "relight_filter_ms_median", MedianOf(relightTotal) },
    { "relight_core_ms_median", MedianOf(relightCore) },
    { "relight_iterations", relightIterations },
    { "translucency_change_filter_ms_median", MedianOf(changeTotal) },
    { "translucency_change_core_ms_median", MedianOf(changeCore) },
    { "translucency_change_iterations", changeIterations } };
  stages.push_back({ "bench", MillisecondsSince(start) });
  std::cout << "relight: median " << MedianOf(relightTotal) << " ms (filter), "
            << MedianOf(relightCore) << " ms (direct light + iteration)\n"
            << "translucency change: median " << MedianOf(changeTotal) << " ms (filter), "
            << MedianOf(changeCore) << " ms (S set-up + direct + iteration)\n";
}

int Radiosity(const RadiosityOptions& o)
{
  const std::string &scenePath = o.ScenePath, &prefix = o.Prefix, &png = o.Png,
                    &jsonPath = o.JsonPath, &sOperator = o.SOperator,
                    &iteration = o.Iteration, &linearSolver = o.LinearSolver;
  const double relTol = o.RelTol, cellSize = o.CellSize;
  const int rays = o.Rays, bench = o.Bench;
  const bool heuristics = o.Heuristics;
  std::vector<Stage> stages;
  const auto wallStart = Clock::now();
  // Before any work: no output may be an input or another output, and a
  // second run into the same prefix is refused (OutputFiles.h).
  OutputPlan plan;
  plan.Input(scenePath, "--scene");
  plan.Output(prefix + "_0.vtp", "--output");
  plan.Output(png, "--png", false);
  plan.Output(jsonPath, "--json", false);
  plan.Check();
  if (!png.empty())
    RequirePictureDisplay("no --png"); // before the solve (Pictures.h)
  auto start = Clock::now();
  LoadedScene scene = LoadScene(scenePath, cellSize);
  stages.push_back({ "scene (read, tetrahedralize)", MillisecondsSince(start) });
  SceneSettings& s = scene.Settings;
  if (!sOperator.empty())
    s.SOperator = sOperator;
  if (!iteration.empty())
    s.Iteration = iteration;
  if (relTol > 0.0)
    s.RelTol = relTol;
  if (rays > 0)
    s.RaysPerPatch = rays;
  if (!linearSolver.empty())
    s.LinearSolver = linearSolver;
  if (s.SOperator != "diffusion" && s.SOperator != "profile")
    throw translucency::Error("scene '" + scenePath + "': s_operator must be diffusion or profile");

  MessageCollector messages;
  vtkNew<vtkTranslucentRadiosity> radiosity;
  messages.Watch(radiosity, "radiosity");
  radiosity->SetInputData(scene.Objects);
  radiosity->SetSubsurfaceMethod(s.SOperator == "profile"
      ? vtkTranslucentRadiosity::SUBSURFACE_PROFILE
      : vtkTranslucentRadiosity::SUBSURFACE_DIFFUSION);
  radiosity->SetIteration(s.Iteration == "jacobi" ? vtkTranslucentRadiosity::ITERATION_JACOBI
                                                  : vtkTranslucentRadiosity::ITERATION_GAUSS_SEIDEL);
  radiosity->SetRelTol(s.RelTol);
  radiosity->SetMaxIter(s.MaxIter);
  radiosity->SetRaysPerPatch(s.RaysPerPatch);
  radiosity->SetFormFactorThreshold(s.FormFactorThreshold);
  radiosity->SetVoxelSize(s.VoxelSize);
  radiosity->SetMaxDistance(s.MaxDistance);
  radiosity->SetComputeHeuristics(heuristics);
  radiosity->SetLinearSolver(s.LinearSolver.c_str());
  auto addLights = [&](const std::vector<translucency::LightSource>& lights) {
    SetRadiosityLights(radiosity, lights);
  };
  addLights(scene.Lights);
  start = Clock::now();
  radiosity->Update();
  if (!messages.Errors.empty())
    throw translucency::Error("scene '" + scenePath + "': " + messages.Last());
  const double firstMs = MillisecondsSince(start);
  // The filter's parts, then the rest of it: the rows add up (no row
  // contains another), and "other" below makes the total the wall time.
  stages.push_back({ "form factors", radiosity->GetFormFactorTime() });
  stages.push_back({ "S set-up", radiosity->GetSetupTime() });
  stages.push_back({ "direct light + S E", radiosity->GetDirectTime() });
  stages.push_back({ "iteration", radiosity->GetSolveTime() });
  stages.push_back({ "radiosity (rest)",
    std::max(0.0, firstMs - radiosity->GetFormFactorTime() - radiosity->GetSetupTime() -
        radiosity->GetDirectTime() - radiosity->GetSolveTime()) });

  json report = { { "scene", scenePath }, { "s_operator", s.SOperator },
    { "iteration", s.Iteration }, { "linear_solver", s.LinearSolver }, { "patches", radiosity->GetNumberOfPatches() },
    { "rays_per_patch", s.RaysPerPatch }, { "iterations", radiosity->GetNumberOfIterations() },
    { "converged", radiosity->GetConverged() }, { "rel_tol", s.RelTol },
    { "form_factor_ms", radiosity->GetFormFactorTime() },
    { "form_factor_bytes", radiosity->GetFormFactorMemory() },
    { "subsurface_setup_ms", radiosity->GetSetupTime() },
    { "subsurface_bytes", radiosity->GetSubsurfaceMemory() },
    { "direct_ms", radiosity->GetDirectTime() }, { "solve_ms", radiosity->GetSolveTime() },
    { "filter_total_ms", firstMs } };
  report["provenance"] = Provenance(o.App);

  // Outputs: one .vtp per object, the PNG and the JSON report, all new or
  // all old (OutputBatch), committed after the report.
  vtkSmartPointer<vtkDataObject> result = radiosity->GetOutputDataObject(0);
  OutputBatch outputs;
  {
    std::string error;
    start = Clock::now();
    // No exit 0 with NaN: every array of every object must be finite.
    RequireFiniteResult(result, "the radiosity");
    const auto leaves = Leaves(result);
    EnsureParentDirectory(prefix + "_0.vtp");
    for (size_t k = 0; k < leaves.size(); ++k)
    {
      vtkNew<vtkXMLPolyDataWriter> writer;
      const std::string file = prefix + "_" + std::to_string(k) + ".vtp";
      if (!outputs.Write(writer, leaves[k], file, error))
        throw translucency::Error(error);
    }
    stages.push_back({ "write", MillisecondsSince(start) });
    if (!png.empty())
    {
      start = Clock::now();
      EnsureParentDirectory(png);
      vtkSmartPointer<vtkDataObject> copy;
      copy.TakeReference(result->NewInstance());
      copy->ShallowCopy(result);
      if (!WriteFourPanels(copy, scene.Camera, outputs.Add(png), error))
        throw translucency::Error(error);
      stages.push_back({ "png", MillisecondsSince(start) });
    }
  }

  if (bench > 0)
  {
    RunRadiosityBench(radiosity, scene, bench, messages, report, stages);
  }

  std::cout << radiosity->GetNumberOfPatches() << " patches, " << radiosity->GetNumberOfIterations()
            << " iterations (" << (radiosity->GetConverged() ? "converged" : "NOT converged")
            << "), F " << radiosity->GetFormFactorMemory() / 1048576.0 << " MiB, S "
            << radiosity->GetSubsurfaceMemory() / 1048576.0 << " MiB\n";
  // Everything not in a row (reports, bookkeeping): the total is the wall time.
  double rows = 0.0;
  for (const Stage& stage : stages)
    rows += stage.Milliseconds;
  stages.push_back({ "other", std::max(0.0, MillisecondsSince(wallStart) - rows) });
  PrintStages(stages);
  json timing = json::object();
  for (const Stage& stage : stages)
    timing[stage.Name] = stage.Milliseconds;
  report["times_ms"] = timing;
  if (!jsonPath.empty())
  {
    std::string error;
    if (!outputs.WriteText(jsonPath, report.dump(2) + "\n", error))
      throw translucency::Error(error);
  }
  std::string commitError;
  if (!outputs.Commit(commitError))
    throw translucency::Error(commitError);
  return 0;
}

} // namespace

Command AddRadiosityCommand(CLI::App& app)
{
  auto o = std::make_shared<RadiosityOptions>();
  CLI::App* c = app.add_subcommand("radiosity",
    "Translucent radiosity of a scene of several objects (JSON scene file).\n\n"
    "Inter-reflection between translucent and opaque diffuse objects,\n"
    "B = (I - S F)^-1 S E. Writes PREFIX_<k>.vtp per object (cell arrays\n"
    "DirectIrradiance, DirectRadiosity, SubsurfaceRadiosity,\n"
    "InterReflectionRadiosity, Radiosity). Scene format: Documentation/Radiosity.md."
    "\n\nusage: translucency radiosity --scene FILE.json --output PREFIX [options]");
  o->App = c;
  c->add_option("--scene", o->ScenePath, "the scene (objects, materials, lights, camera)")
    ->type_name("FILE.json")
    ->required();
  c->add_option("--output", o->Prefix, "writes PREFIX_<k>.vtp, one per object")
    ->type_name("PREFIX")
    ->required();
  c->add_option("--png", o->Png,
     "the four panels of the paper's Fig. 6: direct,\n"
     "subsurface only (first bounce), inter-reflection\n"
     "only, combined (needs X: run under xvfb-run -a)")
    ->type_name("FILE");
  c->add_option("--s-operator", o->SOperator,
     "S by our diffusion solve (default) or the\n"
     "paper's dipole profile over optical paths")
    ->type_name("diffusion|profile")
    ->check(OneOf("--s-operator", { "diffusion", "profile" }));
  c->add_option("--json", o->JsonPath, "report: patches, iterations, residuals, times, memory")
    ->type_name("FILE");
  c->add_option("--iteration", o->Iteration, "default: the scene's, else gauss-seidel")
    ->type_name("jacobi|gauss-seidel")
    ->check(OneOf("--iteration", { "jacobi", "gauss-seidel" }));
  const auto positive = [](double x) { return x > 0; };
  const std::string mustBePositive = "--rays, --bench, --cell-size and --rel-tol must be positive";
  AddNumber(c, "--rel-tol", o->RelTol, "relative change to stop at (default: the scene's,\nelse 0.005)", "X",
    positive, mustBePositive)
    ->default_str("");
  c->add_option("--linear-solver", o->LinearSolver,
     "linear solver of the diffusion S (default: the scene's,\nelse cg-jacobi): " +
       WrapNames(translucency::GetLinearSolverNames(), 40))
    ->type_name("NAME");
  AddNumber(c, "--rays", o->Rays, "rays per patch of the form factors (default: the\nscene's, else 256)", "N",
    positive, mustBePositive)
    ->default_str("");
  AddNumber(c, "--cell-size", o->CellSize, "patch size of every built-in box (overrides the scene)",
    "MM", positive, mustBePositive)
    ->default_str("");
  c->add_flag("--heuristics", o->Heuristics,
    "also the paper's Sec. 6.3 heuristics (arrays\nHeuristicRadiosity1/2)");
  AddNumber(c, "--bench", o->Bench,
    "then N relights (light moved) and N translucency\n"
    "changes (coefficients x 0.5 / x 2), medians in the JSON",
    "N", [](double n) { return n >= 0 && n <= 1000; }, "--bench must be from 0 to 1000");
  return { c, [o]() { return Radiosity(*o); } };
}

} // namespace translucency_app
