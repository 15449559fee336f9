// `translucency render`: a surface (or tet mesh) -> tet mesh -> material ->
// lights -> diffusion solve -> radiance -> files, pictures and a report.

#include "DiffuseOpticsOptions.h"
#include "Options.h"
#include "Pictures.h"
#include "PipelineRender.h"
#include "PowerReport.h"
#include "Provenance.h"
#include "Scene.h"

#include "DiffusionSolverFactory.h"
#include "Error.h"
#include "LinearSolver.h"
#include "OpticalProperties.h"
#include "Strings.h"

#include "vtkOutgoingRadiance.h"
#include "vtkSolveDiffusion.h"

#include <vtkNew.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLPolyDataWriter.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include "vtk_nlohmannjson.h"
#include VTK_NLOHMANN_JSON(json.hpp)

#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace translucency_app
{
namespace
{
using json = nlohmann::json;

struct RenderOptions
{
  SceneOptions Scene;
  RadianceImageOptions Image;
  std::string SolverName = translucency::GetDiffusionSolverNames().front(); ///< the default
  std::string LinearSolver;
  std::string OutputPrefix, PngPath, SlicePath, TpsfPath, JsonPath;
  double RelTol = 1e-6;
  int MaxIter = 2000;
  RadianceReadoutOption Readout;
  double GridSpacing = 0.0;
  long long Photons = 1000000;
  double Anisotropy = 0.0; ///< Henyey-Greenstein g of montecarlo
  bool TwoPointFlux = false; ///< quadgraph's opt-in, non-paper link weights
  bool ListMaterials = false;
  const CLI::App* App = nullptr; ///< for the provenance of the JSON
  DiffuseOpticsOptions Optics;
};

void ListMaterials()
{
  for (const auto& p : translucency::GetMaterialPresets())
  {
    std::cout << std::left << std::setw(12) << p.Name << " sigma_s' = (" << p.ReducedScattering[0]
              << ", " << p.ReducedScattering[1] << ", " << p.ReducedScattering[2]
              << ") 1/mm, mu_a = (" << p.Absorption[0] << ", " << p.Absorption[1] << ", "
              << p.Absorption[2] << ") 1/mm, eta = " << p.RefractiveIndex << "\n";
  }
}

/// Render: the checks of the options (before any work): the solver-specific
/// options against the solver, the TPSF plot against the diffuse-optics
/// options.
void CheckRenderOptions(const RenderOptions& o)
{
  const std::string& solverName = o.SolverName;
  if (o.Anisotropy != 0.0 && translucency::ToLower(solverName) != "montecarlo" &&
    translucency::ToLower(solverName) != "sp3")
  {
    std::ostringstream message;
    message << "--anisotropy " << o.Anisotropy << " applies to --solver montecarlo and sp3 only (the "
            << solverName << " solver uses mu_s', in which g is already folded)";
    throw UsageError(message.str());
  }
  if (o.TwoPointFlux && translucency::ToLower(solverName) != "quadgraph")
    throw UsageError("--two-point-flux applies to --solver quadgraph only (it replaces the "
                     "QuadGraph paper's eq. 5 link weights), not to " + solverName);
  if (!o.TpsfPath.empty() && (o.Optics.TimeGates.Count == 0 || o.Optics.Detectors.empty()))
    throw UsageError("--tpsf-png needs --time-gates and at least one --detector");
}

/// Render, before any work: no output may be an input or another output,
/// and a second run into the same prefix is refused (OutputFiles.h). `plan`
/// holds the locks: the caller keeps it for the whole run.
void PlanRenderOutputs(RenderOptions& o, OutputPlan& plan)
{
  o.Scene.AddInputs(plan);
  if (!o.OutputPrefix.empty())
  {
    plan.Output(o.OutputPrefix + ".vtu", "--output");
    plan.Output(o.OutputPrefix + ".vtp", "--output");
  }
  plan.Output(o.PngPath, "--png");
  plan.Output(o.SlicePath, "--slice-png");
  plan.Output(o.TpsfPath, "--tpsf-png");
  plan.Output(o.JsonPath, "--json");
  plan.Check();
}

/// Render, 5: the diffusion solve on the lit mesh (its errors, collected by
/// `messages`, thrown); its stage times added to `stages`.
vtkSmartPointer<vtkSolveDiffusion> SolveLitMesh(RenderOptions& o, vtkUnstructuredGrid* lit,
  double topologyMs, MessageCollector& messages, std::vector<Stage>& stages)
{
  const std::string& solverName = o.SolverName;
  auto solve = vtkSmartPointer<vtkSolveDiffusion>::New();
  messages.Watch(solve, "solving with " + solverName);
  Progress("solving with " + solverName + "...");
  if (!solve->SetSolverByName(solverName.c_str()))
    throw UsageError(messages.Last());
  solve->SetInputData(lit);
  solve->SetRelTol(o.RelTol);
  solve->SetMaxIter(o.MaxIter);
  solve->SetLinearSolver(o.LinearSolver.c_str());
  solve->SetGridSpacing(o.GridSpacing);
  solve->SetNumberOfPhotons(o.Photons);
  solve->SetAnisotropy(o.Anisotropy);
  solve->SetQuadGraphTwoPointFlux(o.TwoPointFlux);
  o.Optics.Apply(solve);
  solve->Update();
  if (!messages.Errors.empty())
    throw translucency::Error(messages.Last());
  // The topology is built once, by the first filter that needs it.
  stages.push_back({ "topology", topologyMs + solve->GetTopologyTime() });
  stages.push_back({ "assembly", solve->GetAssemblyTime() });
  stages.push_back({ "solve", solve->GetSolveTime() });
  return solve;
}

/// Render, 6: the outgoing radiance of the solved mesh (errors thrown).
vtkSmartPointer<vtkOutgoingRadiance> ComputeRadiance(const RenderOptions& o,
  vtkUnstructuredGrid* solved, MessageCollector& messages, std::vector<Stage>& stages)
{
  auto start = Clock::now();
  auto radiance = vtkSmartPointer<vtkOutgoingRadiance>::New();
  messages.Watch(radiance);
  radiance->SetInputData(solved);
  radiance->SetRadianceReadout(
    o.Readout.IsPaper() ? vtkOutgoingRadiance::PAPER : vtkOutgoingRadiance::ENERGY_CONSERVING);
  radiance->Update();
  if (!messages.Errors.empty())
    throw translucency::Error(messages.Last());
  stages.push_back({ "radiance", MillisecondsSince(start) });
  return radiance;
}

/// Render, 7: the .vtu/.vtp results and the radiance and slice pictures,
/// into the batch `outputs`.
void WriteRenderFiles(const RenderOptions& o, vtkUnstructuredGrid* solved,
  vtkPolyData* outSurface, OutputBatch& outputs, std::vector<Stage>& stages)
{
  const std::string &outputPrefix = o.OutputPrefix, &pngPath = o.PngPath,
                    &slicePath = o.SlicePath;
  std::string error;
  if (!outputPrefix.empty())
  {
    auto start = Clock::now();
    EnsureParentDirectory(outputPrefix + ".vtu");
    vtkNew<vtkXMLUnstructuredGridWriter> gridWriter;
    vtkNew<vtkXMLPolyDataWriter> surfaceWriter;
    if (!outputs.Write(gridWriter, solved, outputPrefix + ".vtu", error) ||
      !outputs.Write(surfaceWriter, outSurface, outputPrefix + ".vtp", error))
      throw translucency::Error(error);
    stages.push_back({ "write", MillisecondsSince(start) });
  }
  if (!pngPath.empty() || !slicePath.empty())
  {
    auto start = Clock::now();
    if (!pngPath.empty())
    {
      EnsureParentDirectory(pngPath);
      if (!WriteRadiancePNG(outSurface, o.Image, outputs.Add(pngPath), error))
        throw translucency::Error(error);
    }
    if (!slicePath.empty())
    {
      EnsureParentDirectory(slicePath);
      // Frequency domain: amplitude and phase side by side.
      if (o.Optics.Frequency > 0.0
            ? !WriteAmplitudePhaseSlicePNG(
                solved, o.Image, o.Optics.Frequency, outputs.Add(slicePath), error, outSurface)
            : !WriteFluenceSlicePNG(solved, o.Image, outputs.Add(slicePath), error, outSurface))
        throw translucency::Error(error);
    }
    stages.push_back({ "render", MillisecondsSince(start) });
  }
}

/// Render, 7: the temporal point-spread function of every detector, channel
/// --channel, on a log scale (gates with no positive reading left out).
void WriteTpsfPlot(const RenderOptions& o, vtkSolveDiffusion* solve, OutputBatch& outputs,
  std::vector<Stage>& stages)
{
  const int channel = o.Image.Channel;
  std::string error;
  auto start = Clock::now();
  static const char* channelName[3] = { "R", "G", "B" };
  std::vector<PlotSeries> curves;
  for (int d = 0; d < solve->GetNumberOfDetectors(); ++d)
  {
    PlotSeries curve;
    curve.Name = "detector " + std::to_string(d + 1) + " (" +
      o.Optics.Detectors[static_cast<size_t>(d)].Spec + ")";
    for (int g = 0; g < solve->GetNumberOfTimeGates(); ++g)
    {
      const double value = solve->GetDetectorFluenceTPSF(d, g, channel);
      if (value > 0.0)
      {
        curve.X.push_back(solve->GetTimeGateCentre(g));
        curve.Y.push_back(value);
      }
    }
    curves.push_back(curve);
  }
  EnsureParentDirectory(o.TpsfPath);
  if (!WritePlotPNG(curves, "time (ns, gate centres)",
        std::string("fluence ") + channelName[channel] +
          " per J of pulse (J/(mm^2 ns)), gate average, log scale",
        outputs.Add(o.TpsfPath), error))
    throw translucency::Error(error);
  stages.push_back({ "tpsf plot", MillisecondsSince(start) });
}

/// Render, 8: the summary on stdout (mesh, lights, solver, channels, the
/// diffuse-optics read-outs, power balance, notes, stage times); returns the
/// power balance (PowerBalanceJson) for the report.
json PrintRenderSummary(const RenderOptions& o, vtkSolveDiffusion* solve,
  vtkUnstructuredGrid* solved, vtkPolyData* outSurface, const std::vector<Stage>& stages)
{
  std::cout << "mesh: " << solved->GetNumberOfPoints() << " points, "
            << solved->GetNumberOfCells() << " tets, " << outSurface->GetNumberOfPoints()
            << " boundary points\n";
  std::cout << LightsLine(o.Scene) << "\n";
  std::cout << "solver: " << solve->GetSolverName() << " (" << solve->GetNumberOfUnknowns()
            << " unknowns per channel, linear solver " << solve->GetLinearSolverUsed() << ")\n";
  static const char* channel[3] = { "R", "G", "B" };
  for (int c = 0; c < 3; ++c)
  {
    std::cout << "  channel " << channel[c] << ": " << solve->GetNumberOfIterations(c)
              << " iterations, relative residual " << std::scientific << std::setprecision(2)
              << solve->GetFinalResidual(c) << std::defaultfloat
              << (solve->GetConverged(c) ? "" : " (NOT converged)") << "\n";
  }
  o.Optics.Print(solve);
  const json power = PowerBalanceJson(solve);
  PrintPowerBalance(power, std::cout);
  const std::string meshNote = solve->GetMeshResolutionNote();
  if (!meshNote.empty())
    std::cout << "note: " << meshNote << "\n";
  PrintStages(stages);
  return power;
}

/// Render, 8: the JSON report (provenance, mesh, solver, edits, read-outs,
/// power balance, channels, stage times).
json RenderReport(const RenderOptions& o, vtkSolveDiffusion* solve, vtkUnstructuredGrid* solved,
  vtkPolyData* outSurface, const EditStats& edits, const json& power,
  const std::vector<Stage>& stages)
{
  const SceneOptions& scene = o.Scene;
  json j;
  j["provenance"] = Provenance(o.App);
  j["provenance"]["scene"] = SceneProvenance(scene);
  j["provenance"]["seed"] = solve->GetSeed();
  j["mesh"] = scene.MeshPath;
  j["points"] = solved->GetNumberOfPoints();
  j["tets"] = solved->GetNumberOfCells();
  j["boundary_points"] = outSurface->GetNumberOfPoints();
  j["solver"] = solve->GetSolverName();
  j["linear_solver"] = solve->GetLinearSolverUsed();
  j["unknowns"] = solve->GetNumberOfUnknowns();
  j["nonzeros"] = solve->GetNumberOfNonZeros();
  if (edits.Cut)
  {
    j["cut"] = { { "tets_kept", edits.KeptTets }, { "vertices_moved", edits.MovedVertices },
      { "blocked", edits.BlockedVertices }, { "ms", edits.CutMs } };
  }
  if (edits.Painted)
  {
    j["paint"] = { { "tets_touched", edits.PaintedTets }, { "ms", edits.PaintMs } };
  }
  o.Optics.Report(solve, j);
  j["power_W"] = power;
  j["model_range"] = { { "warning", solve->GetModelRangeWarning() },
    { "mesh_resolution_note", solve->GetMeshResolutionNote() } };
  static const char* channel[3] = { "R", "G", "B" };
  for (int c = 0; c < 3; ++c)
  {
    j["channels"][channel[c]] = { { "iterations", solve->GetNumberOfIterations(c) },
      { "relative_residual", solve->GetFinalResidual(c) },
      { "converged", solve->GetConverged(c) } };
  }
  double total = 0.0;
  for (const Stage& s : stages)
  {
    j["times_ms"][s.Name] = s.Milliseconds;
    total += s.Milliseconds;
  }
  j["times_ms"]["total"] = total;
  return j;
}

int Render(RenderOptions& o)
{
  if (o.ListMaterials)
  {
    ListMaterials();
    return 0;
  }
  SceneOptions& scene = o.Scene;
  scene.InteriorSources = !o.Optics.Sources.empty();
  scene.Finish("render");
  CheckRenderOptions(o);
  OutputPlan plan; // its locks last until the end of the run
  PlanRenderOutputs(o, plan);
  // Before the solve: the pictures need an X server (Pictures.h).
  if (!o.PngPath.empty() || !o.SlicePath.empty() || !o.TpsfPath.empty())
    RequirePictureDisplay("no --png/--slice-png/--tpsf-png");

  std::vector<Stage> stages;
  std::string error;
  MessageCollector messages;
  double topologyMs = 0.0;
  EditStats edits;
  vtkSmartPointer<vtkUnstructuredGrid> lit = BuildLitMesh(scene, stages, topologyMs, &edits);
  vtkSmartPointer<vtkSolveDiffusion> solve = SolveLitMesh(o, lit, topologyMs, messages, stages);
  vtkUnstructuredGrid* solved = solve->GetOutput();
  vtkSmartPointer<vtkOutgoingRadiance> radiance = ComputeRadiance(o, solved, messages, stages);
  vtkPolyData* outSurface = radiance->GetOutput();
  // No exit 0 with NaN: every array of the results (fluence, radiance,
  // detector readings and TPSF) must be finite before anything is written.
  RequireFiniteResult(solved, "the " + o.SolverName + " solution");
  RequireFiniteResult(outSurface, "the surface radiance");

  // 7. Outputs: all new or all old (OutputBatch), committed after the report.
  OutputBatch outputs;
  WriteRenderFiles(o, solved, outSurface, outputs, stages);
  if (!o.TpsfPath.empty())
    WriteTpsfPlot(o, solve, outputs, stages);

  // 8. Report.
  const json power = PrintRenderSummary(o, solve, solved, outSurface, stages);
  if (!o.JsonPath.empty())
  {
    const json j = RenderReport(o, solve, solved, outSurface, edits, power, stages);
    EnsureParentDirectory(o.JsonPath);
    if (!outputs.WriteText(o.JsonPath, j.dump(2) + "\n", error))
      throw translucency::Error(error);
  }
  if (!outputs.Commit(error))
    throw translucency::Error(error);
  return 0;
}

} // namespace

Command AddRenderCommand(CLI::App& app)
{
  auto o = std::make_shared<RenderOptions>();
  CLI::App* c = app.add_subcommand("render",
    "Tetrahedralize a surface (or read a tet mesh), assign a material,\n"
    "light it, solve the diffusion equation, write the results."
    "\n\nusage: translucency render --mesh FILE [scene options] [options]");
  o->App = c;
  AddSceneOptions(c, o->Scene);
  c->add_option("--solver", o->SolverName,
     WrapNames(translucency::GetDiffusionSolverNames()))
    ->type_name("NAME")
    ->capture_default_str()
    ->check(DiffusionSolverCheck("--solver"));
  c->add_option("--linear-solver", o->LinearSolver,
     "linear solver (default: the solver's own); divergence/fem:\n" +
       WrapNames(translucency::GetLinearSolverNames()) +
       "\n(the first is the default); quadgraph/grid:\n" +
       WrapNames(translucency::GetNonSymmetricLinearSolverNames()) + " (the first is the default)")
    ->type_name("NAME");
  AddGridAndPhotonOptions(c, o->GridSpacing, o->Photons);
  AddNumber(c, "--anisotropy", o->Anisotropy,
    "Henyey-Greenstein g of montecarlo (sp3: the phase function's g), in (-1, 1):\n"
    "mu_s = mu_s' / (1 - g)\n"
    "(the material's mu_s' is kept)", "G", [](double g) { return g > -1 && g < 1; },
    "--anisotropy must be in (-1, 1)");
  c->add_flag("--two-point-flux", o->TwoPointFlux,
    "quadgraph only, NOT the paper's scheme: two-point finite-volume link\n"
    "weights kappa S / (V d) instead of eq. 5's 1 / d^2 (conserves light on\n"
    "graded meshes; Documentation/Solvers.md)");
  AddNumber(c, "--rel-tol", o->RelTol, "relative residual of iterative solvers", "T",
    [](double t) { return t > 0 && t < 1; }, "--rel-tol must be in (0, 1)");
  AddNumber(c, "--max-iter", o->MaxIter, "iteration limit", "N", [](double n) { return n >= 1; },
    "--max-iter must be >= 1");
  AddRadianceReadoutOption(c, o->Readout);
  c->add_option("--output", o->OutputPrefix,
     "write PREFIX.vtu (tet mesh, Fluence, coefficients) and\n"
     "PREFIX.vtp (surface, Radiance, Irradiance, Fluence)")
    ->type_name("PREFIX");
  c->add_option("--png", o->PngPath,
     "render the tone-mapped radiance (needs X,\ne.g. run under xvfb-run -a)")
    ->type_name("FILE");
  c->add_option("--tpsf-png", o->TpsfPath,
     "plot each detector's temporal point-spread function\n"
     "(--time-gates, channel --channel, log scale; needs X)")
    ->type_name("FILE");
  c->add_option("--slice-png", o->SlicePath,
     "render a slice of the fluence rate (inferno, colour bar in\n"
     "W/mm^2; --slice-plane, --channel, --scale); with --frequency\n"
     "two panels: amplitude (W/mm^2) and phase (rad)")
    ->type_name("FILE");
  AddImageOptions(c, o->Image);
  AddDiffuseOpticsOptions(c, o->Optics);
  c->add_option("--json", o->JsonPath, "machine-readable statistics")->type_name("FILE");
  c->add_flag("--list-materials", o->ListMaterials, "print the measured presets and exit");
  return { c, [o]() { return Render(*o); } };
}

} // namespace translucency_app
