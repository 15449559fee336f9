// `translucency bench --diffuse-optics` (BenchDiffuseOptics.h).

#include "BenchDiffuseOptics.h"
#include "BenchLinearSolvers.h"
#include "MeshIO.h"
#include "Utilities.h"

#include "DiffusionSolverFactory.h"
#include "Error.h"
#include "OpticalProperties.h"
#include "TetMesh.h"
#include "TimeResolved.h"
#include "Timer.h"

#include "vtkAssignScatteringCoefficients.h"
#include "vtkSurfaceIrradiance.h"

#include <vtkDataArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>

#include "vtk_nlohmannjson.h"
#include VTK_NLOHMANN_JSON(json.hpp)

#include <omp.h>

#include <array>
#include <ctime>
#include <complex>
#include <fstream>
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
using translucency::DiffusionProblem;
using translucency::SolverReport;

/// The 1-, 5- and 15-minute load averages (/proc/loadavg), "?" if unreadable.
std::string LoadAverage()
{
  std::ifstream in("/proc/loadavg");
  double a = 0.0, b = 0.0, c = 0.0;
  if (!(in >> a >> b >> c))
  {
    return "?";
  }
  std::ostringstream out;
  out << a << " " << b << " " << c;
  return out.str();
}

/// The bench's scene at about `target` tets: the surface tetrahedralised,
/// marble, one directional light (as the plain bench).
struct Scene
{
  translucency::TetMesh Mesh;
  translucency::OpticalProperties Material;
  std::vector<double> Irradiance;
  DiffusionProblem Problem() const
  {
    DiffusionProblem p;
    p.Mesh = &Mesh;
    p.Material = &Material;
    p.Irradiance = &Irradiance;
    return p;
  }
};

void MakeScene(vtkPolyData* surface, double target, Scene& scene)
{
  vtkSmartPointer<vtkUnstructuredGrid> grid;
  std::vector<double> points;
  std::vector<int> tets;
  TetrahedralizeForBench(surface, target, grid, points, tets);
  vtkNew<vtkAssignScatteringCoefficients> assign;
  assign->SetInputData(grid);
  vtkNew<vtkSurfaceIrradiance> light;
  light->SetInputConnection(assign->GetOutputPort());
  light->AddDirectionalLight(0, -1, -1, 1.0);
  light->SetUniformLightIrradiance(0.1);
  light->SetUniformLightSamples(0);
  light->Update();
  vtkUnstructuredGrid* g = light->GetOutput();
  vtkDataArray* qa = g->GetPointData()->GetArray("Irradiance");
  if (!qa || g->GetNumberOfPoints() != static_cast<vtkIdType>(points.size() / 3))
  {
    throw translucency::Error("bench --diffuse-optics: the lighting of the bench mesh failed");
  }
  scene.Mesh.SetGeometry(points, tets);
  const translucency::MaterialPreset& marble = translucency::FindMaterialPreset("marble");
  scene.Material = translucency::OpticalProperties::Uniform(scene.Mesh.GetNumberOfTets(),
    marble.Absorption, marble.ReducedScattering, marble.RefractiveIndex);
  scene.Irradiance.assign(3 * static_cast<std::size_t>(g->GetNumberOfPoints()), 0.0);
  for (vtkIdType i = 0; i < g->GetNumberOfPoints(); ++i)
  {
    for (int c = 0; c < 3; ++c)
    {
      scene.Irradiance[3 * i + c] = qa->GetComponent(i, c);
    }
  }
}

/// Medians of one way of solving: set-up (assembly, mass, hierarchy), solve,
/// their sum, and the iterations of the last run.
struct Timing
{
  std::vector<double> Setup, Solve, Total;
  /// Process CPU time of the whole call (all threads), ms: less sensitive to
  /// a loaded machine than the wall times at one thread.
  std::vector<double> Cpu;
  std::array<int, 3> Iterations{};
  std::string LinearSolver;
  bool Converged = true;
  void Add(const SolverReport& report, std::clock_t cpuStart)
  {
    Cpu.push_back(1000.0 * static_cast<double>(std::clock() - cpuStart) / CLOCKS_PER_SEC);
    Setup.push_back(report.SetupMilliseconds);
    Solve.push_back(report.SolveMilliseconds);
    Total.push_back(report.SetupMilliseconds + report.SolveMilliseconds);
    Iterations = report.Iterations;
    LinearSolver = report.LinearSolver;
    for (int c = 0; c < 3; ++c)
    {
      Converged = Converged && report.Converged[c];
    }
  }
  json Json(double cwSolve, double cwTotal) const
  {
    return { { "linear_solver", LinearSolver }, { "setup_ms_median", Median(Setup) },
      { "solve_ms_median", Median(Solve) }, { "total_ms_median", Median(Total) },
      { "cpu_ms_median", Median(Cpu) },
      { "iterations", Iterations }, { "converged", Converged },
      { "solve_over_cw_solve", Median(Solve) / cwSolve },
      { "total_over_cw_total", Median(Total) / cwTotal } };
  }
};

void PrintRow(const std::string& what, const Timing& t, double cwSolve, double cwTotal)
{
  std::ostringstream iterations;
  iterations << t.Iterations[0] << "/" << t.Iterations[1] << "/" << t.Iterations[2];
  std::cout << std::fixed << std::setprecision(1) << "    " << std::left << std::setw(30) << what
            << std::setw(22) << t.LinearSolver << std::right << std::setw(14)
            << iterations.str() << std::setw(10) << Median(t.Setup) << std::setw(10)
            << Median(t.Solve) << std::setw(10) << Median(t.Total) << std::setprecision(2)
            << std::setw(9) << Median(t.Solve) / cwSolve << std::setw(9)
            << Median(t.Total) / cwTotal << std::setprecision(0) << std::setw(10) << Median(t.Cpu)
            << (t.Converged ? "" : "  NOT CONVERGED") << "\n"
            << std::defaultfloat;
}

json FrequencyTable(const Scene& scene, double target, double frequency, int runs)
{
  const DiffusionProblem problem = scene.Problem();
  Timing cw, jacobi, multigrid;
  for (int r = 0; r < runs; ++r)
  {
    // Fresh solver objects: cold solves (assembly and hierarchy included).
    SolverReport report;
    {
      auto solver = translucency::CreateDiffusionSolver("divergence");
      std::vector<double> fluence;
      const std::clock_t cpu = std::clock();
      solver->Solve(problem, fluence, report);
      cw.Add(report, cpu);
    }
    for (Timing* t : { &jacobi, &multigrid })
    {
      auto solver = translucency::CreateDiffusionSolver("divergence");
      solver->SetLinearSolver(t == &jacobi ? "cg-jacobi" : "multigrid-agg");
      std::vector<std::complex<double>> fluence;
      const std::clock_t cpu = std::clock();
      solver->SolveFrequencyDomain(problem, frequency, fluence, report);
      t->Add(report, cpu);
    }
  }
  const double cwSolve = Median(cw.Solve), cwTotal = Median(cw.Total);
  std::cout << "  " << static_cast<long>(target) << " target: " << scene.Mesh.GetNumberOfTets()
            << " tets, " << scene.Mesh.GetNumberOfPoints() << " unknowns per channel, "
            << frequency << " Hz\n";
  std::cout << "    " << std::left << std::setw(30) << "solve" << std::setw(22) << "linear solver"
            << std::right << std::setw(14) << "iters R/G/B" << std::setw(10) << "setup" << std::setw(10)
            << "solve" << std::setw(10) << "total" << std::setw(9) << "solve/CW" << std::setw(9)
            << "total/CW" << std::setw(10) << "cpu" << "   (ms)\n";
  PrintRow("continuous wave (baseline)", cw, cwSolve, cwTotal);
  PrintRow("frequency domain, Jacobi", jacobi, cwSolve, cwTotal);
  PrintRow("frequency domain, multigrid", multigrid, cwSolve, cwTotal);
  return { { "target_tets", target }, { "tets", scene.Mesh.GetNumberOfTets() },
    { "unknowns", scene.Mesh.GetNumberOfPoints() }, { "frequency_hz", frequency },
    { "cw", cw.Json(cwSolve, cwTotal) }, { "fd_jacobi", jacobi.Json(cwSolve, cwTotal) },
    { "fd_multigrid", multigrid.Json(cwSolve, cwTotal) } };
}

json GateTable(const Scene& scene, double target, int gates, int stepsPerGate, int runs)
{
  const DiffusionProblem problem = scene.Problem();
  translucency::TimeGates timeGates;
  timeGates.Start = 0.0;
  timeGates.End = 5.0;
  timeGates.Count = gates;
  timeGates.StepsPerGate = stepsPerGate;
  // Two detectors on the boundary (the first and the middle boundary point).
  std::vector<translucency::Detector> detectors(2);
  const std::vector<int>& boundary = scene.Mesh.GetBoundaryPoints();
  for (int k = 0; k < 2 && !boundary.empty(); ++k)
  {
    const double* x = scene.Mesh.GetPoint(boundary[k * (boundary.size() / 2)]);
    detectors[k].Position = { x[0], x[1], x[2] };
  }
  // The step solvers: cg-jacobi, multigrid-agg from the extrapolation alone
  // (before session 21), multigrid-agg with the recycled step solutions
  // (the default).
  constexpr int Rows = 3;
  const char* names[Rows] = { "cg-jacobi", "multigrid-agg", "multigrid-agg" };
  const int recycled[Rows] = { 0, 0, 4 };
  std::array<Timing, Rows> timing;
  std::array<long long, Rows> steps{};
  for (int r = 0; r < runs; ++r)
  {
    for (int k = 0; k < Rows; ++k)
    {
      auto solver = translucency::CreateDiffusionSolver("divergence");
      solver->SetLinearSolver(names[k]);
      solver->SetOptions(translucency::SolverOptions{
        { translucency::DiffusionOption::TimeStepRecycled, static_cast<double>(recycled[k]) } });
      translucency::TimeResolvedResult result;
      SolverReport report;
      const std::clock_t cpu = std::clock();
      solver->SolveTimeResolved(problem, timeGates, detectors, {}, result, report);
      timing[k].Add(report, cpu);
      steps[k] = result.NumberOfSteps;
    }
  }
  const double oldSolve = Median(timing[1].Solve), oldTotal = Median(timing[1].Total);
  std::cout << "  " << static_cast<long>(target) << " target: " << scene.Mesh.GetNumberOfTets()
            << " tets, " << scene.Mesh.GetNumberOfPoints() << " unknowns per channel, "
            << gates << " gates over 0-5 ns, " << steps[2] << " steps\n";
  std::cout << "    " << std::left << std::setw(30) << "time gates" << std::setw(22)
            << "step solver" << std::right << std::setw(14) << "iters R/G/B" << std::setw(10)
            << "setup" << std::setw(10) << "solve" << std::setw(10) << "total" << std::setw(9)
            << "/before" << std::setw(9) << "/before" << std::setw(10) << "cpu" << "   (ms)\n";
  PrintRow("Jacobi step solver", timing[0], oldSolve, oldTotal);
  PrintRow("multigrid, extrapolated", timing[1], oldSolve, oldTotal);
  PrintRow("multigrid, recycled (default)", timing[2], oldSolve, oldTotal);
  return { { "target_tets", target }, { "tets", scene.Mesh.GetNumberOfTets() },
    { "unknowns", scene.Mesh.GetNumberOfPoints() }, { "gates", gates }, { "steps", steps[2] },
    { "cg_jacobi", timing[0].Json(oldSolve, oldTotal) },
    { "multigrid_agg_extrapolated", timing[1].Json(oldSolve, oldTotal) },
    { "multigrid_agg", timing[2].Json(oldSolve, oldTotal) } };
}

} // namespace

int BenchDiffuseOptics(const DiffuseOpticsBenchOptions& o)
{
  std::string error;
  vtkSmartPointer<vtkPolyData> surface;
  vtkSmartPointer<vtkUnstructuredGrid> grid;
  if (!ReadMesh(o.MeshPath, surface, grid, error))
  {
    throw translucency::Error(error);
  }
  if (!surface)
  {
    throw translucency::Error("bench needs a surface mesh (.ply, .stl, .obj, .vtp)");
  }
  std::cout << "threads: " << omp_get_max_threads() << ", runs per figure: " << o.Runs
            << " (medians), load average at start: " << LoadAverage()
            << "\ndivergence, marble, one directional light, relative residual 1e-6\n\n";
  json results = { { "frequency_domain", json::array() } };
  for (double target : o.Tets)
  {
    Scene scene;
    MakeScene(surface, target, scene);
    results["frequency_domain"].push_back(FrequencyTable(scene, target, o.Frequency, o.Runs));
  }
  if (o.GateTets > 0)
  {
    Scene scene;
    MakeScene(surface, o.GateTets, scene);
    std::cout << "\n";
    results["time_gates"] = GateTable(scene, o.GateTets, o.Gates, o.StepsPerGate, o.Runs);
  }
  std::cout << "load average at the end: " << LoadAverage() << "\n";
  results["load_average_end"] = LoadAverage();
  if (!o.JsonPath.empty() && !WriteText(o.JsonPath, results.dump(2) + "\n", error))
  {
    throw translucency::Error(error);
  }
  return 0;
}

} // namespace translucency_app
