// `translucency bench`: median topology, assembly, SpMV and solve times at
// several mesh sizes (optionally cut and paint timings, --edit), or, with
// --linear-solvers, every linear solver side by side (BenchLinearSolvers.cxx),
// or, with --diffuse-optics, the frequency-domain and time-gate solves against
// the CW solve (BenchDiffuseOptics.cxx).

#include "BenchDiffuseOptics.h"
#include "BenchLinearSolvers.h"
#include "BenchMeshers.h"
#include "BenchPipeline.h"
#include "MeshIO.h"
#include "Options.h"

#include "ConjugateGradient.h"
#include "DiffusionSolverFactory.h"
#include "DiscreteDivergence.h"
#include "Error.h"
#include "LinearSolver.h"
#include "OpticalProperties.h"
#include "Sp3Solver.h"
#include "Strings.h"
#include "TetMesh.h"
#include "TimeResolved.h"

#include "vtkAssignScatteringCoefficients.h"
#include "vtkPaintScatteringCoefficients.h"
#include "vtkStrokeCut.h"
#include "vtkSurfaceIrradiance.h"

#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkNew.h>
#include <vtkPlane.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>

#include "vtk_nlohmannjson.h"
#include VTK_NLOHMANN_JSON(json.hpp)

#include <omp.h>

#include <array>
#include <cmath>
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

/// The options of the plain bench.
struct BenchOptions
{
  std::string MeshPath;
  std::vector<double> Tets;
  int Runs = 7;
  std::string JsonPath;
  bool Edit = false;
  bool Sp3 = false;
};

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

/// SP3 against the divergence solve on one lit mesh (issue 35's cost
/// target: SP3 <= 3x divergence, cold and warm), each with its default
/// linear solver (by size: multigrid-agg from 20k vertices) at rel-tol 1e-6:
/// cold = a new solver object (assembly, set-up, solve from zero), warm = the
/// same object after the light moved (`q2`: a second directional light;
/// warm start from the previous solution). Medians of `runs`, the
/// solvers alternating within each run. "sp3-gmres" is sp3 with restarted
/// GMRES on its block system in place of its default BiCGSTAB
/// (Sp3Solver::SetKrylovMethod), the measurement behind that choice.
json BenchSp3(const translucency::TetMesh& mesh, const translucency::OpticalProperties& material,
  const std::vector<double>& q, const std::vector<double>& q2, int runs)
{
  json out;
  constexpr int count = 3;
  const char* names[count] = { "divergence", "sp3", "sp3-gmres" };
  // The solvers alternate within each run (divergence, sp3, sp3-gmres,
  // divergence, ...), so that a change of the machine's load hits all alike.
  std::array<std::vector<double>, count> cold, warm;
  std::array<int, count> coldIterations{}, warmIterations{};
  for (int r = 0; r < runs; ++r)
  {
    for (int s = 0; s < count; ++s)
    {
      const char* name = names[s];
      std::unique_ptr<translucency::DiffusionSolver> solver =
        translucency::CreateDiffusionSolver(s == 0 ? "divergence" : "sp3");
      if (s == 2)
        dynamic_cast<translucency::Sp3Solver&>(*solver).SetKrylovMethod("gmres");
      solver->SetRelTol(1e-6);
      translucency::DiffusionProblem problem;
      problem.Mesh = &mesh;
      problem.Material = &material;
      problem.Irradiance = &q;
      std::vector<double> fluence;
      translucency::SolverReport report;
      auto start = Clock::now();
      if (!solver->Solve(problem, fluence, report) || !report.Converged[0])
        throw translucency::Error(std::string("bench: the ") + name + " cold solve did not converge");
      cold[s].push_back(MillisecondsSince(start));
      coldIterations[s] = report.Iterations[0];
      problem.Irradiance = &q2;
      start = Clock::now();
      if (!solver->Solve(problem, fluence, report) || !report.Converged[0])
        throw translucency::Error(std::string("bench: the ") + name + " warm solve did not converge");
      warm[s].push_back(MillisecondsSince(start));
      warmIterations[s] = report.Iterations[0];
    }
  }
  std::array<std::array<double, 2>, count> times{};
  for (int s = 0; s < count; ++s)
  {
    times[s] = { Median(cold[s]), Median(warm[s]) };
    std::cout << std::fixed << std::setprecision(1) << "    " << names[s] << ": cold " << times[s][0]
              << " ms (" << coldIterations[s] << " iterations in R), warm " << times[s][1]
              << " ms (" << warmIterations[s] << ")\n" << std::defaultfloat;
    out[names[s]] = { { "cold_ms_median", times[s][0] }, { "warm_ms_median", times[s][1] },
      { "cold_iterations_R", coldIterations[s] }, { "warm_iterations_R", warmIterations[s] } };
  }
  const double ratio[2] = { times[1][0] / times[0][0], times[1][1] / times[0][1] };
  std::cout << std::fixed << std::setprecision(2) << "    sp3 / divergence: cold " << ratio[0]
            << "x, warm " << ratio[1] << "x\n" << std::defaultfloat;
  out["sp3_over_divergence_cold"] = ratio[0];
  out["sp3_over_divergence_warm"] = ratio[1];
  const double reference[2] = { times[2][0] / times[0][0], times[2][1] / times[0][1] };
  std::cout << std::fixed << std::setprecision(2) << "    sp3-gmres / divergence: cold "
            << reference[0] << "x, warm " << reference[1] << "x\n" << std::defaultfloat;
  out["sp3_gmres_over_divergence_cold"] = reference[0];
  out["sp3_gmres_over_divergence_warm"] = reference[1];
  return out;
}

int Bench(const BenchOptions& o)
{
    const std::string& meshPath = o.MeshPath;
  const std::vector<double>& sizes = o.Tets;
  const int runs = o.Runs;
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
    if (o.Edit)
      results.back()["edit"] = BenchEdit(g, runs);
    if (o.Sp3)
    {
      // The second light for the warm solves: the first one turned by 45
      // degrees about the vertical.
      vtkNew<vtkSurfaceIrradiance> turned;
      turned->SetInputConnection(assign->GetOutputPort());
      turned->AddDirectionalLight(0.7071, -0.7071, -1, 1.0);
      turned->SetUniformLightIrradiance(0.1);
      turned->SetUniformLightSamples(0);
      turned->Update();
      vtkDataArray* qb = turned->GetOutput()->GetPointData()->GetArray("Irradiance");
      std::vector<double> q2(q.size());
      for (vtkIdType i = 0; i < g->GetNumberOfPoints(); ++i)
        for (int c = 0; c < 3; ++c)
          q2[3 * i + c] = qb->GetComponent(i, c);
      results.back()["sp3"] = BenchSp3(mesh, material, q, q2, runs);
    }
  }
  if (!o.JsonPath.empty() && !WriteText(o.JsonPath, results.dump(2) + "\n", error))
    throw translucency::Error(error);
  return 0;
}

/// What the options of `bench` fill in: one subcommand, several benches
/// (the plain one, --linear-solvers, --diffuse-optics, --pipeline,
/// --meshers) sharing --mesh, --tets, --runs and --json (each bench with its
/// own defaults).
struct BenchCommandState
{
  LinearSolverBenchOptions Linear; ///< also holds the shared --mesh and --json
  BenchOptions Plain;
  DiffuseOpticsBenchOptions Optics;
  std::vector<double> Tets; ///< --tets (empty: each bench's default)
  int Runs = 0;             ///< --runs (0: each bench's default)
  std::vector<std::string> Solvers; ///< --linear-solvers' values (comma lists)
  bool Meshers = false, DiffuseOptics = false, Pipeline = false;
  bool GradedOnly = false; ///< --graded-only (with --meshers)
  std::string Collimated = "default"; ///< --collimated (with --pipeline)
  CLI::Option* LinearSolvers = nullptr; ///< set when --linear-solvers is given
};

/// bench: the options every bench shares (--mesh, --tets, --runs, --json)
/// and the plain bench's --edit and --sp3.
void AddSharedBenchOptions(
  CLI::App* c, BenchCommandState& s, CLI::Option*& edit, CLI::Option*& sp3)
{
  c->add_option("--mesh", s.Linear.MeshPath, "surface to tetrahedralize")
    ->type_name("FILE")
    ->capture_default_str();
  AddNumberList(c, "--tets", s.Tets, "target sizes (default 100000,1000000; with\n--linear-solvers 100000,500000,1000000)", "N1,N2,...")
    ->check(CLI::Validator(
      [](std::string& text) {
        const std::vector<double> sizes = ParseNumbers(text, "--tets");
        if (sizes.empty())
          throw UsageError("--tets: no size given (e.g. --tets 100000,1000000)");
        for (double n : sizes)
        {
          if (ToNumber<long long>(n, "--tets") < 1)
            throw UsageError("--tets: every size must be >= 1, not " + DefaultText(n));
        }
        return std::string();
      },
      ""));
  AddNumber(c, "--runs", s.Runs, "repetitions per measurement (default 7; with\n--linear-solvers 5)", "N",
    [](double n) { return n >= 1 && n <= 1000; }, "--runs must be from 1 to 1000")
    ->default_str("");
  c->add_option("--json", s.Linear.JsonPath, "machine-readable results")->type_name("FILE");
  edit = c->add_flag("--edit", s.Plain.Edit,
    "also time a plane cut (+ topology + assembly) and a paint\n"
    "stroke on ~1 % of the tets (+ incremental row update)");
  sp3 = c->add_flag("--sp3", s.Plain.Sp3,
    "also time the sp3 solver against divergence (default linear\n"
    "solvers, rel-tol 1e-6; sp3 also with GMRES in place of its\n"
    "BiCGSTAB): cold (new solver) and warm (the light turned 45\n"
    "degrees, warm start), medians of --runs");
}

/// bench: --linear-solvers and the options only it takes (--plot,
/// --hypre-ranks, --no-cut); returns --linear-solvers.
CLI::Option* AddLinearSolverBenchOptions(CLI::App* c, BenchCommandState& s)
{
  const std::string group = "Linear solvers (bench --linear-solvers)";
  CLI::Option* linearSolvers =
    c->add_option("--linear-solvers", s.Solvers,
       "every linear solver of this build (or the named ones of\n" +
         WrapNames(translucency::GetLinearSolverNames()) +
         ")\non the bunny, marble, one directional light: set-up, cold solve\n"
         "and warm solve (10-degree light rotation) to 1 % relative\n"
         "L2 error of the boundary fluence, SpMV-equivalents, the\n"
         "SpMV bandwidth bound, cut -> new fluence (multigrid-agg)")
      ->type_name("[N1,N2,...]")
      ->expected(0, 1) // one optional value; the comma list is split below
      ->group(group);
  CLI::Option* plot = c->add_option("--plot", s.Linear.PlotPath,
                        "error of the boundary fluence vs solve time per solver\n"
                        "(writes FILE.csv, plotted by scripts/plot_linear_solvers.py)")
                        ->type_name("FILE.png")
                        ->group(group);
  CLI::Option* ranks = AddNumber(c, "--hypre-ranks", s.Linear.HypreRanks,
    "also run hypre-amg on N MPI ranks through mpiexec and\n"
    "translucency-hypre-mpi (0 or 1: skip)",
    "N")->group(group);
  LinearSolverBenchOptions* linear = &s.Linear;
  CLI::Option* noCut =
    c->add_flag_callback("--no-cut", [linear]() { linear->DoCut = false; },
       "skip the cut -> new fluence figure")
      ->group(group);
  for (CLI::Option* only : { plot, ranks, noCut })
    only->needs(linearSolvers);
  return linearSolvers;
}

/// bench: --diffuse-optics and the options only it takes (issue 19's
/// performance targets); returns --diffuse-optics.
CLI::Option* AddDiffuseOpticsBenchOptions(CLI::App* c, BenchCommandState& s)
{
  DiffuseOpticsBenchOptions& optics = s.Optics;
  const std::string opticsGroup = "Diffuse optics (bench --diffuse-optics)";
  CLI::Option* diffuseOptics = c->add_flag("--diffuse-optics", s.DiffuseOptics,
    "frequency-domain solves (COCG with Jacobi and with the\n"
    "multigrid of the real part) against the CW cold solve at\n"
    "--tets (default 1000000), and --gates time gates at\n"
    "--gate-tets with the cg-jacobi and multigrid step solvers\n"
    "(the multigrid with and without recycled step solutions);\n"
    "--runs default 3")->group(opticsGroup);
  CLI::Option* frequency = AddNumber(c, "--frequency", optics.Frequency,
    "modulation frequency of the frequency-domain solves (Hz)", "HZ",
    [](double f) { return std::isfinite(f) && f > 0.0; }, "--frequency must be finite and > 0")
    ->group(opticsGroup);
  CLI::Option* gateTets = AddNumber(c, "--gate-tets", optics.GateTets,
    "target size of the time-gate table (0: skip it)", "N",
    [](double n) { return n >= 0 && n <= 1e8; }, "--gate-tets must be from 0 to 1e8")
    ->group(opticsGroup);
  CLI::Option* gateCount = AddNumber(c, "--gates", optics.Gates,
    "time gates over 0-5 ns", "N",
    [](double n) { return n >= 1 && n <= translucency::TimeGates::MaximumTimeGates; },
    "--gates must be from 1 to 10000")->group(opticsGroup);
  CLI::Option* stepsPerGate = AddNumber(c, "--steps-per-gate", optics.StepsPerGate,
    "time steps per gate of the time-gate table (0: automatic,\n"
    "as render's --steps-per-gate)", "K",
    [](double k) { return k >= 0 && k <= translucency::TimeGates::MaximumStepsPerGate; },
    "--steps-per-gate must be from 0 to 1000")->group(opticsGroup);
  for (CLI::Option* only : { frequency, gateTets, gateCount, stepsPerGate })
    only->needs(diffuseOptics);
  return diffuseOptics;
}

/// bench, run: the outputs checked, then the bench the flags choose, with
/// the shared --mesh, --json, --tets and --runs.
int RunBench(BenchCommandState& s)
{
  LinearSolverBenchOptions& linear = s.Linear;
  // Before any work: no output may be the input or another output.
  OutputPlan plan;
  plan.Input(linear.MeshPath, "--mesh");
  plan.Output(linear.JsonPath, "--json");
  if (!linear.PlotPath.empty())
  {
    plan.Output(linear.PlotPath, "--plot");
    plan.Output(PlotDataPath(linear.PlotPath), "--plot (its data, .csv)");
  }
  plan.Check();
  if (s.LinearSolvers->count() > 0)
  {
    for (const std::string& list : s.Solvers)
    {
      std::stringstream names(list);
      std::string name;
      while (std::getline(names, name, ','))
        if (!name.empty())
          linear.Names.push_back(name);
    }
    if (!s.Tets.empty())
      linear.Tets = s.Tets;
    if (s.Runs > 0)
      linear.Runs = s.Runs;
    return BenchLinearSolvers(linear);
  }
  if (s.DiffuseOptics)
  {
    s.Optics.MeshPath = linear.MeshPath;
    s.Optics.JsonPath = linear.JsonPath;
    if (!s.Tets.empty())
      s.Optics.Tets = s.Tets;
    if (s.Runs > 0)
      s.Optics.Runs = s.Runs;
    return BenchDiffuseOptics(s.Optics);
  }
  if (s.Pipeline)
  {
    PipelineBenchOptions p;
    p.MeshPath = linear.MeshPath;
    p.JsonPath = linear.JsonPath;
    if (!s.Tets.empty())
      p.Tets = s.Tets;
    if (s.Runs > 0)
      p.Runs = s.Runs;
    p.Collimated = s.Collimated;
    return BenchPipeline(p);
  }
  if (s.Meshers)
  {
    MesherBenchOptions m;
    m.MeshPath = linear.MeshPath;
    m.JsonPath = linear.JsonPath;
    if (!s.Tets.empty())
      m.Tets = s.Tets;
    if (s.Runs > 0)
      m.Runs = s.Runs;
    m.GradedOnly = s.GradedOnly;
    return BenchMeshers(m);
  }
  s.Plain.MeshPath = linear.MeshPath;
  s.Plain.JsonPath = linear.JsonPath;
  s.Plain.Tets = s.Tets.empty() ? std::vector<double>{ 100000, 1000000 } : s.Tets;
  if (s.Runs > 0)
    s.Plain.Runs = s.Runs;
  return Bench(s.Plain);
}

} // namespace

Command AddBenchCommand(CLI::App& app)
{
  auto s = std::make_shared<BenchCommandState>();
  CLI::App* c = app.add_subcommand("bench", "Median assembly and solve times at several mesh sizes."
    "\n\nusage: translucency bench [options]\n   or: translucency bench --linear-solvers [N1,N2,...] [options]");
  CLI::Option *edit = nullptr, *sp3 = nullptr;
  AddSharedBenchOptions(c, *s, edit, sp3);
  CLI::Option* linearSolvers = AddLinearSolverBenchOptions(c, *s);
  s->LinearSolvers = linearSolvers;
  CLI::Option* meshers = c->add_flag("--meshers", s->Meshers,
    "compare the tetrahedralisers instead: tetgen and hxt (when\n"
    "built), graded and --uniform-size, at --tets (default\n"
    "1000000), --runs (default 3): time, tets/s, min dihedral\n"
    "histogram, radius-edge ratios, edge-length spread");
  c->add_flag("--graded-only", s->GradedOnly,
     "with --meshers: the graded rows only (no --uniform-size rows)")
    ->needs(meshers);
  meshers->excludes(linearSolvers);
  edit->excludes(meshers);
  edit->excludes(linearSolvers);
  sp3->excludes(meshers);
  sp3->excludes(linearSolvers);
  CLI::Option* diffuseOptics = AddDiffuseOpticsBenchOptions(c, *s);
  for (CLI::Option* other : { linearSolvers, meshers, edit, sp3 })
    diffuseOptics->excludes(other);
  // The ParaView chain, filter by filter (issue 31).
  CLI::Option* pipeline = c->add_flag("--pipeline", s->Pipeline,
    "time the ParaView chain filter by filter (Assign marble ->\n"
    "Surface Irradiance -> Paint -> Solve Diffusion -> Outgoing\n"
    "Radiance, read from a .vtu): cold chain, relight (15\n"
    "degrees), paint stroke (~1 % of the tets), plane cut, at\n"
    "--tets (default 200000,1000000), --runs (default 3), in ms\n"
    "and SpMV units, with the relit and painted fluence against\n"
    "a solve to RelTol 1e-10");
  for (CLI::Option* other : { linearSolvers, meshers, edit, diffuseOptics })
    pipeline->excludes(other);
  c->add_option("--collimated", s->Collimated,
     "with --pipeline: Surface Irradiance's collimated model\n"
     "(default: by light kind, extended-moments here)")
    ->type_name("MODEL")
    ->check(OneOf("--collimated", CollimatedModelChoices()))
    ->needs(pipeline);
  return { c, [s]() { return RunBench(*s); } };
}

} // namespace translucency_app
