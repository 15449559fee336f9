// `translucency bench --pipeline`: the ParaView chain timed filter by filter
// (BenchPipeline.h).

#include "BenchPipeline.h"

#include "BenchLinearSolvers.h"
#include "MeshIO.h"
#include "Utilities.h"

#include "DiscreteDivergence.h"
#include "Error.h"
#include "OpticalProperties.h"
#include "TetMesh.h"

#include "vtkAssignScatteringCoefficients.h"
#include "vtkOutgoingRadiance.h"
#include "vtkPaintScatteringCoefficients.h"
#include "vtkSolveDiffusion.h"
#include "vtkStrokeCut.h"
#include "vtkSurfaceIrradiance.h"

#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkNew.h>
#include <vtkPlane.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include "vtk_nlohmannjson.h"
#include VTK_NLOHMANN_JSON(json.hpp)

#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>

namespace translucency_app
{
namespace
{
using json = nlohmann::json;

/// The filters of the chain, in order (the table's columns).
const char* const FilterNames[] = { "assign", "irradiance", "paint", "cut", "solve", "radiance" };
/// The steps (the table's rows).
const char* const StepNames[] = { "cold", "relight", "paint", "cut" };

/// Wall time (ms) of one algorithm's Update(); throws if it failed.
double TimedUpdate(vtkAlgorithm* algorithm, const std::string& what)
{
  const auto start = Clock::now();
  algorithm->Update();
  const double ms = MillisecondsSince(start);
  if (algorithm->GetErrorCode() != 0 || !algorithm->GetOutputDataObject(0))
  {
    throw translucency::Error("bench --pipeline: " + what + " failed");
  }
  return ms;
}

/// Relative boundary RMS difference of the point array `name` (3 components)
/// between `a` and the reference `b`, the largest over the channels.
double BoundaryError(vtkDataSet* a, vtkDataSet* b, const char* name, const std::vector<int>& boundary)
{
  vtkDataArray* x = a->GetPointData()->GetArray(name);
  vtkDataArray* y = b->GetPointData()->GetArray(name);
  if (!x || !y || x->GetNumberOfTuples() != y->GetNumberOfTuples())
  {
    throw translucency::Error(std::string("bench --pipeline: no comparable '") + name + "' arrays");
  }
  double worst = 0.0;
  for (int c = 0; c < 3; ++c)
  {
    double num = 0.0, den = 0.0;
    for (int i : boundary)
    {
      const double d = x->GetComponent(i, c) - y->GetComponent(i, c);
      num += d * d;
      den += y->GetComponent(i, c) * y->GetComponent(i, c);
    }
    worst = std::max(worst, den > 0.0 ? std::sqrt(num / den) : std::sqrt(num));
  }
  return worst;
}

/// Largest |a - b| over every value of the point array `name`, relative to the largest |b|.
double MaximumRelativeDifference(vtkDataSet* a, vtkDataSet* b, const char* name)
{
  vtkDataArray* x = a->GetPointData()->GetArray(name);
  vtkDataArray* y = b->GetPointData()->GetArray(name);
  if (!x || !y || x->GetNumberOfTuples() != y->GetNumberOfTuples() ||
    x->GetNumberOfComponents() != y->GetNumberOfComponents())
  {
    throw translucency::Error(std::string("bench --pipeline: no comparable '") + name + "' arrays");
  }
  double diff = 0.0, scale = 0.0;
  for (vtkIdType i = 0; i < x->GetNumberOfTuples(); ++i)
  {
    for (int c = 0; c < x->GetNumberOfComponents(); ++c)
    {
      diff = std::max(diff, std::abs(x->GetComponent(i, c) - y->GetComponent(i, c)));
      scale = std::max(scale, std::abs(y->GetComponent(i, c)));
    }
  }
  return scale > 0.0 ? diff / scale : diff;
}

/// The key light turned by `degrees` about the x axis from (0, -1, -1).
void SetKeyLight(vtkSurfaceIrradiance* light, double degrees)
{
  const double t = degrees * 3.14159265358979323846 / 180.0;
  light->RemoveAllDirectionalLights();
  light->AddDirectionalLight(0.0, -std::cos(t) + std::sin(t), -std::sin(t) - std::cos(t), 1.0);
}

/// One chain of filters, as a user builds it.
struct Chain
{
  vtkNew<vtkXMLUnstructuredGridReader> Reader;
  vtkNew<vtkAssignScatteringCoefficients> Assign;
  vtkNew<vtkSurfaceIrradiance> Light;
  vtkNew<vtkPaintScatteringCoefficients> Paint;
  vtkNew<vtkStrokeCut> Cut;
  vtkNew<vtkSolveDiffusion> Solve;
  vtkNew<vtkOutgoingRadiance> Radiance;

  Chain(const std::string& path, const std::string& collimated)
  {
    Reader->SetFileName(path.c_str());
    Assign->SetInputConnection(Reader->GetOutputPort());
    Assign->SetMaterialName("marble");
    Light->SetInputConnection(Assign->GetOutputPort());
    SetKeyLight(Light, 0.0);
    Light->SetUniformLightIrradiance(0.1);
    Light->SetCollimatedModelByName(collimated.c_str()); // checked by --collimated
    Paint->SetInputConnection(Light->GetOutputPort());
    Solve->SetInputConnection(Paint->GetOutputPort());
    Radiance->SetInputConnection(Solve->GetOutputPort());
  }
};

/// Per step, per filter, the times of every run; per step the iterations.
struct StepTimes
{
  std::map<std::string, std::vector<double>> Filters;
  std::vector<double> Iterations;
};

/// Sum of the solve's iterations over the three channels.
double TotalIterations(vtkSolveDiffusion* solve)
{
  return solve->GetNumberOfIterations(0) + solve->GetNumberOfIterations(1) +
    solve->GetNumberOfIterations(2);
}

/// The SpMV time (ms, median of `runs`) of the 1-channel discrete divergence
/// matrix of the mesh.
double MeasureSpMV(const std::vector<double>& points, const std::vector<int>& tets, int runs,
  std::vector<int>& boundary)
{
  translucency::TetMesh mesh;
  mesh.SetGeometry(points, tets);
  boundary = mesh.GetBoundaryPoints();
  const translucency::MaterialPreset& marble = translucency::FindMaterialPreset("marble");
  const auto material = translucency::OpticalProperties::Uniform(
    mesh.GetNumberOfTets(), marble.Absorption, marble.ReducedScattering, marble.RefractiveIndex);
  std::vector<double> q(3 * static_cast<size_t>(mesh.GetNumberOfPoints()), 0.0);
  translucency::DiscreteDivergence disc;
  translucency::DiffusionSystem system;
  disc.Assemble(mesh, material, q, system);
  Eigen::VectorXd x = Eigen::VectorXd::Ones(system.NumberOfUnknowns), y(system.NumberOfUnknowns);
  std::vector<double> times;
  for (int r = 0; r < std::max(runs, 5); ++r)
  {
    const auto start = Clock::now();
    y.noalias() = system.Matrix(0) * x;
    times.push_back(MillisecondsSince(start));
  }
  return Median(times);
}

/// One run of the four steps on a new chain; adds its times to `steps` and,
/// when `check` is set, the accuracy figures to `accuracy`.
void RunOnce(const std::string& path, const std::string& collimated, const double bounds[6],
  const std::vector<int>& boundary, int run, bool check, std::map<std::string, StepTimes>& steps,
  json& accuracy)
{
  Chain chain(path, collimated);
  const double centre[3] = { 0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3]),
    0.5 * (bounds[4] + bounds[5]) };
  const double diag = std::sqrt((bounds[1] - bounds[0]) * (bounds[1] - bounds[0]) +
    (bounds[3] - bounds[2]) * (bounds[3] - bounds[2]) +
    (bounds[5] - bounds[4]) * (bounds[5] - bounds[4]));
  // The stroke of the cold chain lies outside the object (paints nothing).
  chain.Paint->AddStrokePoint(bounds[1] + diag, centre[1], centre[2]);
  chain.Paint->SetWidth(0.01 * diag);
  TimedUpdate(chain.Reader, "reading the mesh");

  StepTimes& cold = steps["cold"];
  cold.Filters["assign"].push_back(TimedUpdate(chain.Assign, "Assign"));
  cold.Filters["irradiance"].push_back(TimedUpdate(chain.Light, "Surface Irradiance"));
  cold.Filters["paint"].push_back(TimedUpdate(chain.Paint, "Paint"));
  cold.Filters["solve"].push_back(TimedUpdate(chain.Solve, "Solve Diffusion"));
  cold.Filters["radiance"].push_back(TimedUpdate(chain.Radiance, "Outgoing Radiance"));
  cold.Iterations.push_back(TotalIterations(chain.Solve));

  // Relight: the key light turned 15 degrees.
  StepTimes& relight = steps["relight"];
  SetKeyLight(chain.Light, 15.0);
  relight.Filters["irradiance"].push_back(TimedUpdate(chain.Light, "Surface Irradiance"));
  relight.Filters["paint"].push_back(TimedUpdate(chain.Paint, "Paint"));
  relight.Filters["solve"].push_back(TimedUpdate(chain.Solve, "Solve Diffusion"));
  // The solve's own phases: set-up (assembly of the right-hand side) and the
  // linear solve; the rest of the filter's time is conversion and output.
  relight.Filters["solve.setup"].push_back(chain.Solve->GetAssemblyTime());
  relight.Filters["solve.linear"].push_back(chain.Solve->GetSolveTime());
  relight.Filters["radiance"].push_back(TimedUpdate(chain.Radiance, "Outgoing Radiance"));
  relight.Iterations.push_back(TotalIterations(chain.Solve));
  if (check)
  {
    // The relit irradiance against a new filter (no cache), the relit
    // fluence against a solve to 1e-10 of the same input.
    vtkNew<vtkSurfaceIrradiance> fresh;
    fresh->SetInputData(chain.Assign->GetOutput());
    SetKeyLight(fresh, 15.0);
    fresh->SetUniformLightIrradiance(0.1);
    fresh->SetCollimatedModelByName(collimated.c_str());
    TimedUpdate(fresh, "Surface Irradiance (reference)");
    accuracy["relight_irradiance_max_relative_difference"] =
      MaximumRelativeDifference(chain.Light->GetOutput(), fresh->GetOutput(), "Irradiance");
    vtkNew<vtkSolveDiffusion> tight;
    tight->SetInputData(chain.Paint->GetOutput());
    tight->SetRelTol(1e-10);
    TimedUpdate(tight, "Solve Diffusion (reference)");
    accuracy["relight_fluence_boundary_error"] =
      BoundaryError(chain.Solve->GetOutput(), tight->GetOutput(), "Fluence", boundary);
  }

  // Paint: the stroke moved onto the top of the object, about 1 % of the tets.
  StepTimes& paint = steps["paint"];
  chain.Paint->RemoveAllStrokePoints();
  chain.Paint->AddStrokePoint(centre[0], bounds[3], centre[2]);
  chain.Paint->SetWidth(0.024 * diag * (1.0 + 0.01 * run));
  paint.Filters["paint"].push_back(TimedUpdate(chain.Paint, "Paint"));
  paint.Filters["solve"].push_back(TimedUpdate(chain.Solve, "Solve Diffusion"));
  paint.Filters["solve.setup"].push_back(chain.Solve->GetAssemblyTime());
  paint.Filters["solve.linear"].push_back(chain.Solve->GetSolveTime());
  paint.Filters["radiance"].push_back(TimedUpdate(chain.Radiance, "Outgoing Radiance"));
  paint.Iterations.push_back(TotalIterations(chain.Solve));
  if (check)
  {
    vtkNew<vtkSolveDiffusion> tight;
    tight->SetInputData(chain.Paint->GetOutput());
    tight->SetRelTol(1e-10);
    TimedUpdate(tight, "Solve Diffusion (reference)");
    accuracy["paint_fluence_boundary_error"] =
      BoundaryError(chain.Solve->GetOutput(), tight->GetOutput(), "Fluence", boundary);
    vtkDataArray* painted =
      chain.Paint->GetOutput()->GetFieldData()->GetArray("PaintedCellIds");
    accuracy["tets_painted"] = painted ? painted->GetNumberOfTuples() : 0;
  }

  // Cut: a plane through the centre between Paint and Solve Diffusion.
  StepTimes& cut = steps["cut"];
  vtkNew<vtkPlane> plane;
  plane->SetOrigin(centre);
  plane->SetNormal(1.0, 0.0, 0.0);
  chain.Cut->SetCutFunction(plane);
  chain.Cut->SetInputConnection(chain.Paint->GetOutputPort());
  chain.Solve->SetInputConnection(chain.Cut->GetOutputPort());
  cut.Filters["cut"].push_back(TimedUpdate(chain.Cut, "Stroke Cut"));
  cut.Filters["solve"].push_back(TimedUpdate(chain.Solve, "Solve Diffusion"));
  cut.Filters["radiance"].push_back(TimedUpdate(chain.Radiance, "Outgoing Radiance"));
  cut.Iterations.push_back(TotalIterations(chain.Solve));
}

/// Each run's figures, beside the medians printed at the end (a run that
/// differs from the others shows here).
void PrintRun(int run, std::map<std::string, StepTimes>& steps)
{
  std::cout << "  run " << run + 1 << ":";
  for (const char* step : { "cold", "relight", "paint", "cut" })
  {
    double total = 0.0;
    for (const auto& [name, times] : steps[step].Filters)
      if (name.find('.') == std::string::npos)
        total += times.back();
    std::cout << " " << step << " " << std::fixed << std::setprecision(1) << total << " ms";
  }
  std::cout << " (relight: irradiance " << steps["relight"].Filters["irradiance"].back()
            << ", solve set-up " << steps["relight"].Filters["solve.setup"].back() << ")"
            << std::defaultfloat << std::endl;
}

double LoadAverage()
{
  double load[1] = { 0.0 };
  return getloadavg(load, 1) == 1 ? load[0] : -1.0;
}

} // namespace

int BenchPipeline(const PipelineBenchOptions& o)
{
  std::string error;
  vtkSmartPointer<vtkPolyData> surface;
  vtkSmartPointer<vtkUnstructuredGrid> grid;
  if (!ReadMesh(o.MeshPath, surface, grid, error))
    throw translucency::Error(error);
  if (!surface && !grid)
    throw translucency::Error(
      "bench --pipeline needs a surface mesh (.ply, .stl, .obj, .vtp) or a tetrahedral .vtu");
  // A tetrahedral mesh is used as it is (one size: --tets is ignored), so
  // that runs compare on the same tets without meshing again.
  const std::vector<double> targets =
    surface ? o.Tets : std::vector<double>{ static_cast<double>(grid->GetNumberOfCells()) };

  json results = json::array();
  std::cout << "pipeline bench: threads " << omp_get_max_threads() << ", runs per figure " << o.Runs
            << " (medians), collimated model " << o.Collimated << "; each cell: ms (SpMV units)\n";
  for (double target : targets)
  {
    vtkSmartPointer<vtkUnstructuredGrid> tetrahedralized;
    std::vector<double> points;
    std::vector<int> tets;
    if (surface)
    {
      TetrahedralizeForBench(surface, target, tetrahedralized, points, tets);
    }
    else
    {
      tetrahedralized = grid;
      GridToCoreArrays(grid, points, tets);
    }
    // The mesh a user would load: a .vtu written once.
    const std::filesystem::path path = std::filesystem::temp_directory_path() /
      ("translucency-bench-pipeline-" + std::to_string(getpid()) + "-" +
        std::to_string(static_cast<long long>(target)) + ".vtu");
    vtkNew<vtkXMLUnstructuredGridWriter> writer;
    writer->SetFileName(path.string().c_str());
    writer->SetInputData(tetrahedralized);
    writer->SetDataModeToAppended();
    writer->EncodeAppendedDataOff();
    if (writer->Write() != 1)
      throw translucency::Error("bench --pipeline: cannot write " + path.string());
    double bounds[6];
    tetrahedralized->GetBounds(bounds);
    std::vector<int> boundary;
    const double spmv = MeasureSpMV(points, tets, o.Runs, boundary);

    std::map<std::string, StepTimes> steps;
    json accuracy;
    const double loadBefore = LoadAverage();
    try
    {
      for (int r = 0; r < o.Runs; ++r)
      {
        RunOnce(path.string(), o.Collimated, bounds, boundary, r, r == o.Runs - 1, steps, accuracy);
        PrintRun(r, steps);
      }
    }
    catch (...)
    {
      std::filesystem::remove(path);
      throw;
    }
    std::filesystem::remove(path);
    const double loadAfter = LoadAverage();

    std::cout << "\n  " << tetrahedralized->GetNumberOfCells() << " tets, "
              << tetrahedralized->GetNumberOfPoints() << " points; 1 SpMV = " << std::fixed
              << std::setprecision(3) << spmv << " ms; load average " << std::setprecision(2)
              << loadBefore << " -> " << loadAfter << "\n";
    std::cout << "  " << std::left << std::setw(9) << "step";
    for (const char* f : FilterNames)
      std::cout << std::right << std::setw(16) << f;
    std::cout << std::setw(18) << "total" << std::setw(8) << "iters" << "\n";
    json row = { { "target_tets", target }, { "tets", tetrahedralized->GetNumberOfCells() },
      { "points", tetrahedralized->GetNumberOfPoints() }, { "spmv_1ch_ms_median", spmv },
      { "threads", omp_get_max_threads() }, { "runs", o.Runs }, { "collimated", o.Collimated },
      { "load_average_before", loadBefore }, { "load_average_after", loadAfter } };
    for (const char* step : StepNames)
    {
      const StepTimes& s = steps[step];
      json stepJson;
      double total = 0.0;
      std::cout << "  " << std::left << std::setw(9) << step << std::right;
      for (const char* f : FilterNames)
      {
        auto it = s.Filters.find(f);
        if (it == s.Filters.end())
        {
          std::cout << std::setw(16) << "-";
          continue;
        }
        const double ms = Median(it->second);
        total += ms;
        std::ostringstream cell;
        cell << std::fixed << std::setprecision(1) << ms << " (" << std::setprecision(0)
             << ms / spmv << ")";
        std::cout << std::setw(16) << cell.str();
        stepJson[std::string(f) + "_ms_median"] = ms;
      }
      std::ostringstream cell;
      cell << std::fixed << std::setprecision(1) << total << " (" << std::setprecision(0)
           << total / spmv << ")";
      const double iterations = Median(s.Iterations);
      std::cout << std::setw(18) << cell.str() << std::setw(8) << iterations << "\n";
      stepJson["total_ms"] = total;
      stepJson["total_spmv"] = total / spmv;
      stepJson["iterations_3ch_median"] = iterations;
      row[step] = stepJson;
    }
    std::cout << std::left << std::setprecision(3) << std::scientific
              << "  relit irradiance vs a new filter: max relative difference "
              << accuracy.value("relight_irradiance_max_relative_difference", -1.0) << "\n"
              << std::fixed << std::setprecision(3)
              << "  boundary RMS error vs RelTol 1e-10: relight "
              << 100.0 * accuracy.value("relight_fluence_boundary_error", -1.0) << " %, paint "
              << 100.0 * accuracy.value("paint_fluence_boundary_error", -1.0) << " % ("
              << accuracy.value("tets_painted", 0) << " tets painted)\n"
              << std::right << std::defaultfloat;
    for (const char* step : { "relight", "paint" })
    {
      // The solve split: set-up, linear solve, the filter's rest.
      const StepTimes& r = steps[step];
      const double total = Median(r.Filters.at("solve"));
      const double setup = Median(r.Filters.at("solve.setup"));
      const double linear = Median(r.Filters.at("solve.linear"));
      std::cout << std::fixed << std::setprecision(1) << "  " << step << " solve " << total
                << " ms: set-up " << setup << ", linear solve " << linear
                << ", the filter's conversions and output " << total - setup - linear << " ("
                << std::setprecision(0) << setup / spmv << " + " << linear / spmv << " + "
                << (total - setup - linear) / spmv << " SpMV units)\n"
                << std::defaultfloat;
      row[step]["solve_setup_median_ms"] = setup;
      row[step]["solve_linear_median_ms"] = linear;
    }
    row["accuracy"] = accuracy;
    results.push_back(row);
  }
  if (!o.JsonPath.empty() && !WriteText(o.JsonPath, results.dump(2) + "\n", error))
    throw translucency::Error(error);
  return 0;
}

} // namespace translucency_app
