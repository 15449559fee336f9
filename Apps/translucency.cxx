// translucency: command-line front end of the Translucency pipeline.
//
//   translucency render --mesh FILE [options]    surface/tet mesh -> fluence -> radiance -> PNG
//   translucency compare --mesh FILE [options]   every solver on one problem, side by side
//   translucency bench [options]                 assembly/solve medians at several mesh sizes
//   translucency radiosity --scene FILE.json --output PREFIX   translucent radiosity (Radiosity.cxx)
//   translucency --help
//
// Every error is printed as "translucency: error: ..." and the exit code is 1
// (2 for a usage error).

#include "BenchLinearSolvers.h"
#include "CommandLine.h"
#include "PipelineRender.h"

#include "ConjugateGradient.h"
#include "DiscreteDivergence.h"
#include "Error.h"
#include "OpticalProperties.h"
#include "TetMesh.h"

#include "vtkAssignScatteringCoefficients.h"
#include "vtkOutgoingRadiance.h"
#include "vtkPaintScatteringCoefficients.h"
#include "vtkStrokeCut.h"
#include "vtkSolveDiffusion.h"
#include "vtkSurfaceIrradiance.h"
#include "vtkTetrahedralizeSurface.h"

#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkPlane.h>
#include <vtkNew.h>
#include <vtkOutputWindow.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLPolyDataWriter.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include "vtk_nlohmannjson.h"
#include VTK_NLOHMANN_JSON(json.hpp)

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <string>
#include <vector>

namespace
{
using namespace translucency_app;
using json = nlohmann::json;

const char* const UsageHead = R"(usage: translucency <command> [options]

Commands:
  render   Tetrahedralize a surface (or read a tet mesh), assign a material,
           light it, solve the diffusion equation, write the results.
  compare  Run several solvers on the same problem and lay the results side by side.
  bench    Median assembly and solve times at several mesh sizes.
  radiosity  Translucent radiosity of a scene of several objects (JSON scene file).
  acquire  Recover kappa and mu_a from measured radiance (inverse diffusion).

Scene options (render and compare):
)";

const char* const RenderHelp = R"(
translucency render --mesh FILE [scene options] [options]
  --solver NAME            divergence (default), fem, quadgraph, grid, montecarlo
  --linear-solver NAME     linear solver (default: the solver's own); divergence/fem:
                           cg-jacobi (default), transcut-multires, multigrid-cg,
                           multigrid-agg, ...;
                           quadgraph/grid: bicgstab (default), relaxation
  --grid-spacing H         voxel spacing of the grid solver, mm (default: automatic)
  --photons N              photon budget of montecarlo (default 1000000)
  --rel-tol T              relative residual of iterative solvers (default 1e-6)
  --max-iter N             iteration limit (default 2000)
  --n-squared-law          divide the radiance by eta^2 (energy-conserving read-out;
                           TransCut eq. 3 as printed omits it)
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
)";

const char* const BenchHelp = R"(
translucency bench [options]
  --mesh FILE              surface to tetrahedralize (default: Data/bunny.ply)
  --tets N1,N2,...         target sizes (default 100000,1000000)
  --runs N                 repetitions per measurement (default 7)
  --json FILE              machine-readable results
  --edit                   also time a plane cut (+ topology + assembly) and a paint
                           stroke on ~1 % of the tets (+ incremental row update)
)";

void PrintUsage()
{
  std::cout << UsageHead << SceneOptionsHelp << RenderHelp << CompareHelp << BenchHelp
            << BenchLinearSolversHelp << translucency_app::RadiosityHelp << AcquireHelp;
}

int Render(const std::vector<std::string>& args)
{
  SceneOptions scene;
  std::string solverName = "divergence", outputPrefix, pngPath, slicePath, jsonPath;
  std::string linearSolver;
  double relTol = 1e-6;
  int maxIter = 2000;
  bool nSquaredLaw = false;
  double gridSpacing = 0.0;
  long long photons = 1000000;
  RadianceImageOptions image;

  for (size_t i = 0; i < args.size(); ++i)
  {
    const std::string& a = args[i];
    auto value = [&]() -> const std::string& {
      if (i + 1 >= args.size())
        throw UsageError(a + " needs a value");
      return args[++i];
    };
    if (scene.Parse(args, i) || ParseImageOption(args, i, image))
      continue;
    if (a == "--solver")
      solverName = value();
    else if (a == "--linear-solver")
      linearSolver = value();
    else if (a == "--rel-tol")
      relTol = ParseNumbers(value(), a).at(0);
    else if (a == "--max-iter")
      maxIter = static_cast<int>(ParseNumbers(value(), a).at(0));
    else if (a == "--output")
      outputPrefix = value();
    else if (a == "--png")
      pngPath = value();
    else if (a == "--slice-png")
      slicePath = value();
    else if (a == "--json")
      jsonPath = value();
    else if (a == "--n-squared-law")
      nSquaredLaw = true;
    else if (a == "--grid-spacing")
    {
      gridSpacing = ParseNumbers(value(), a).at(0);
      if (!(gridSpacing > 0))
        throw UsageError("--grid-spacing must be > 0 mm");
    }
    else if (a == "--photons")
    {
      const double n = ParseNumbers(value(), a).at(0);
      if (!(n >= 1))
        throw UsageError("--photons must be >= 1");
      photons = static_cast<long long>(n);
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
  scene.Finish("render");
  if (relTol <= 0 || relTol >= 1)
    throw UsageError("--rel-tol must be in (0, 1)");
  if (maxIter < 1)
    throw UsageError("--max-iter must be >= 1");

  std::vector<Stage> stages;
  std::string error;
  MessageCollector messages;
  double topologyMs = 0.0;
  EditStats edits;
  vtkSmartPointer<vtkUnstructuredGrid> lit = BuildLitMesh(scene, stages, topologyMs, &edits);

  // 5. Solve.
  vtkNew<vtkSolveDiffusion> solve;
  messages.Watch(solve);
  if (!solve->SetSolverByName(solverName.c_str()))
    throw UsageError(messages.Last());
  solve->SetInputData(lit);
  solve->SetRelTol(relTol);
  solve->SetMaxIter(maxIter);
  solve->SetLinearSolver(linearSolver.c_str());
  solve->SetGridSpacing(gridSpacing);
  solve->SetNumberOfPhotons(photons);
  solve->Update();
  if (!messages.Errors.empty())
    throw translucency::Error(messages.Last());
  // The topology is built once, by the first filter that needs it.
  stages.push_back({ "topology", topologyMs + solve->GetTopologyTime() });
  stages.push_back({ "assembly", solve->GetAssemblyTime() });
  stages.push_back({ "solve", solve->GetSolveTime() });
  vtkUnstructuredGrid* solved = solve->GetOutput();

  // 6. Radiance.
  auto start = Clock::now();
  vtkNew<vtkOutgoingRadiance> radiance;
  messages.Watch(radiance);
  radiance->SetInputData(solved);
  radiance->SetNSquaredLaw(nSquaredLaw);
  radiance->Update();
  if (!messages.Errors.empty())
    throw translucency::Error(messages.Last());
  vtkPolyData* outSurface = radiance->GetOutput();
  stages.push_back({ "radiance", MillisecondsSince(start) });

  // 7. Outputs.
  if (!outputPrefix.empty())
  {
    start = Clock::now();
    EnsureParentDirectory(outputPrefix + ".vtu");
    vtkNew<vtkXMLUnstructuredGridWriter> gridWriter;
    vtkNew<vtkXMLPolyDataWriter> surfaceWriter;
    if (!WriteAtomically(gridWriter, solved, outputPrefix + ".vtu", error) ||
      !WriteAtomically(surfaceWriter, outSurface, outputPrefix + ".vtp", error))
      throw translucency::Error(error);
    stages.push_back({ "write", MillisecondsSince(start) });
  }
  if (!pngPath.empty() || !slicePath.empty())
  {
    start = Clock::now();
    if (!pngPath.empty())
    {
      EnsureParentDirectory(pngPath);
      if (!WriteRadiancePNG(outSurface, image, pngPath, error))
        throw translucency::Error(error);
    }
    if (!slicePath.empty())
    {
      EnsureParentDirectory(slicePath);
      if (!WriteFluenceSlicePNG(solved, image, slicePath, error))
        throw translucency::Error(error);
    }
    stages.push_back({ "render", MillisecondsSince(start) });
  }

  // 8. Report.
  const vtkIdType numPoints = solved->GetNumberOfPoints();
  const vtkIdType numTets = solved->GetNumberOfCells();
  const vtkIdType numBoundary = outSurface->GetNumberOfPoints();
  std::cout << "mesh: " << numPoints << " points, " << numTets << " tets, " << numBoundary
            << " boundary points\n";
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
  PrintStages(stages);

  if (!jsonPath.empty())
  {
    json j;
    j["mesh"] = scene.MeshPath;
    j["points"] = numPoints;
    j["tets"] = numTets;
    j["boundary_points"] = numBoundary;
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
    EnsureParentDirectory(jsonPath);
    if (!WriteText(jsonPath, j.dump(2) + "\n", error))
      throw translucency::Error(error);
  }
  return 0;
}

/// Cut and paint timings on one lit mesh (medians of `runs`): a plane cut
/// through the centre with the default relaxation, then the topology rebuild
/// and the 3-channel re-assembly of the cut mesh; a paint stroke touching
/// about 1 % of the tets, then the incremental re-assembly of their rows.
json BenchEdit(vtkUnstructuredGrid* g, int runs)
{
  std::vector<double> cutMs, topoMs, asmMs, paintMs, updateMs, paintExactMs, fullAsmMs;
  vtkIdType kept = 0, touched = 0;
  double bounds[6];
  g->GetBounds(bounds);
  const double centre[3] = { 0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3]),
    0.5 * (bounds[4] + bounds[5]) };
  const translucency::MaterialPreset& marble = translucency::FindMaterialPreset("marble");
  for (int r = 0; r < runs; ++r)
  {
    vtkNew<vtkPlane> plane;
    plane->SetOrigin(centre);
    plane->SetNormal(1.0, 0.0, 0.0);
    vtkNew<vtkStrokeCut> cut;
    cut->SetInputData(g);
    cut->SetCutFunction(plane);
    auto start = Clock::now();
    cut->Update();
    cutMs.push_back(MillisecondsSince(start));
    vtkUnstructuredGrid* out = cut->GetOutput();
    kept = out->GetNumberOfCells();
    std::vector<double> points;
    std::vector<int> tets;
    GridToCoreArrays(out, points, tets);
    start = Clock::now();
    translucency::TetMesh mesh;
    mesh.SetGeometry(std::move(points), std::move(tets));
    topoMs.push_back(MillisecondsSince(start));
    auto material = translucency::OpticalProperties::Uniform(
      mesh.GetNumberOfTets(), marble.Absorption, marble.ReducedScattering, marble.RefractiveIndex);
    std::vector<double> q(3 * static_cast<size_t>(mesh.GetNumberOfPoints()), 0.0);
    translucency::DiscreteDivergence disc;
    translucency::DiffusionSystem system;
    start = Clock::now();
    disc.Assemble(mesh, material, q, system);
    asmMs.push_back(MillisecondsSince(start));
  }
  // Paint: a stroke point on the top of the object, width giving ~1 % of tets.
  std::vector<double> points;
  std::vector<int> tets;
  GridToCoreArrays(g, points, tets);
  translucency::TetMesh mesh;
  mesh.SetGeometry(points, tets);
  auto material = translucency::OpticalProperties::Uniform(
    mesh.GetNumberOfTets(), marble.Absorption, marble.ReducedScattering, marble.RefractiveIndex);
  std::vector<double> q(3 * static_cast<size_t>(mesh.GetNumberOfPoints()), 0.0);
  translucency::DiscreteDivergence disc;
  translucency::DiffusionSystem system;
  disc.Assemble(mesh, material, q, system);
  const double diag = std::sqrt((bounds[1] - bounds[0]) * (bounds[1] - bounds[0]) +
    (bounds[3] - bounds[2]) * (bounds[3] - bounds[2]) + (bounds[5] - bounds[4]) * (bounds[5] - bounds[4]));
  for (int r = 0; r < runs; ++r)
  {
    vtkNew<vtkPaintScatteringCoefficients> paint;
    paint->SetInputData(g);
    paint->AddStrokePoint(centre[0], bounds[3], centre[2]);
    paint->SetWidth(0.024 * diag);
    auto start = Clock::now();
    paint->Update();
    paintMs.push_back(MillisecondsSince(start));
    // The tets whose coefficients changed, as listed by the paint filter.
    vtkDataArray* painted = paint->GetOutput()->GetFieldData()->GetArray("PaintedCellIds");
    std::vector<int> changed;
    for (vtkIdType k = 0; painted && k < painted->GetNumberOfTuples(); ++k)
      changed.push_back(static_cast<int>(painted->GetComponent(k, 0)));
    touched = static_cast<vtkIdType>(changed.size());
    vtkDataArray* muA = paint->GetOutput()->GetCellData()->GetArray("AbsorptionCoefficient");
    vtkDataArray* sigma = paint->GetOutput()->GetCellData()->GetArray("ReducedScatteringCoefficient");
    for (int t : changed)
      for (int c = 0; c < 3; ++c)
      {
        material.AbsorptionCoefficient[3 * t + c] = muA->GetComponent(t, c);
        material.ReducedScatteringCoefficient[3 * t + c] = sigma->GetComponent(t, c);
      }
    start = Clock::now();
    disc.UpdateTets(mesh, material, q, changed, system);
    updateMs.push_back(MillisecondsSince(start));
    // Same-run baselines: the same paint with no cut-off (every tet weighted,
    // as before the cut-off existed) and a full 3-channel assembly.
    vtkNew<vtkPaintScatteringCoefficients> exact;
    exact->SetInputData(g);
    exact->AddStrokePoint(centre[0], bounds[3], centre[2]);
    exact->SetWidth(0.024 * diag);
    exact->SetCutoffWeight(0.0);
    start = Clock::now();
    exact->Update();
    paintExactMs.push_back(MillisecondsSince(start));
    translucency::DiffusionSystem full;
    start = Clock::now();
    disc.Assemble(mesh, material, q, full);
    fullAsmMs.push_back(MillisecondsSince(start));
  }
  const double cut = Median(cutMs), topo = Median(topoMs), as = Median(asmMs);
  const double paint = Median(paintMs), update = Median(updateMs);
  std::cout << std::fixed << std::setprecision(1) << "    edit: plane cut " << cut
            << " ms (kept " << kept << " tets) + topology " << topo << " ms + assembly " << as
            << " ms = " << cut + topo + as << " ms; paint " << paint << " ms ("
            << touched << " tets, " << std::setprecision(2)
            << 100.0 * touched / g->GetNumberOfCells() << " %) + row update " << update
            << " ms = " << paint + update << " ms\n"
            << "    same-run baselines: paint without cut-off " << Median(paintExactMs)
            << " ms, full assembly " << Median(fullAsmMs) << " ms (paint total / full assembly "
            << std::setprecision(2) << (paint + update) / Median(fullAsmMs) << ")\n"
            << std::defaultfloat;
  return { { "cut_ms_median", cut }, { "cut_topology_ms_median", topo },
    { "cut_assembly_ms_median", as }, { "cut_total_ms", cut + topo + as },
    { "tets_kept", kept }, { "paint_ms_median", paint }, { "paint_update_ms_median", update },
    { "paint_total_ms", paint + update }, { "tets_painted", touched },
    { "paint_no_cutoff_ms_median", Median(paintExactMs) },
    { "full_assembly_ms_median", Median(fullAsmMs) } };
}

int Bench(const std::vector<std::string>& args)
{
  std::string meshPath = "Data/bunny.ply", jsonPath;
  std::vector<double> sizes = { 100000, 1000000 };
  int runs = 7;
  bool edit = false;
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
    else if (a == "--edit")
      edit = true;
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
    vtkSmartPointer<vtkUnstructuredGrid> tetrahedralized;
    std::vector<double> points;
    std::vector<int> tets;
    const double tetgenMs = TetrahedralizeForBench(surface, target, tetrahedralized, points, tets);
    auto start = Clock::now();
    vtkNew<vtkAssignScatteringCoefficients> assign;
    assign->SetInputData(tetrahedralized);
    vtkNew<vtkSurfaceIrradiance> light;
    light->SetInputConnection(assign->GetOutputPort());
    light->AddDirectionalLight(0, -1, -1, 1.0);
    light->SetUniformLightIrradiance(0.1);
    light->SetUniformLightSamples(0);
    light->Update();
    vtkUnstructuredGrid* g = light->GetOutput();

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
      topo.push_back(MillisecondsSince(start));
    }
    translucency::DiscreteDivergence disc;
    translucency::DiffusionSystem system;
    for (int r = 0; r < runs; ++r)
    {
      start = Clock::now();
      disc.Assemble(mesh, material, q, system);
      assembly.push_back(MillisecondsSince(start));
    }
    Eigen::VectorXd x = Eigen::VectorXd::Ones(system.NumberOfUnknowns), y(system.NumberOfUnknowns);
    for (int r = 0; r < runs; ++r)
    {
      start = Clock::now();
      y.noalias() = system.Matrix(0) * x;
      spmv.push_back(MillisecondsSince(start));
    }
    translucency::ConjugateGradient cg;
    cg.SetRelTol(1e-6);
    int iterations = 0;
    for (int r = 0; r < runs; ++r)
    {
      std::array<Eigen::VectorXd, 3> solution;
      start = Clock::now();
      cg.Solve(system, solution, false);
      solveTimes.push_back(MillisecondsSince(start));
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
    if (edit)
      results.back()["edit"] = BenchEdit(g, runs);
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
      PrintUsage();
      return args.empty() ? 2 : 0;
    }
    const std::string command = args[0];
    args.erase(args.begin());
    if (std::find(args.begin(), args.end(), "--help") != args.end())
    {
      PrintUsage();
      return 0;
    }
    if (command == "render")
      return Render(args);
    if (command == "compare")
      return translucency_app::Compare(args);
    if (command == "bench")
      return std::find(args.begin(), args.end(), "--linear-solvers") != args.end()
        ? BenchLinearSolvers(args)
        : Bench(args);
    if (command == "radiosity")
      return translucency_app::Radiosity(args);
    if (command == "acquire")
      return translucency_app::Acquire(args);
    throw UsageError(
      "unknown command '" + command + "' (render, compare, bench, radiosity or acquire)");
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
