// translucency bench --linear-solvers: every linear solver side by side on
// the bunny (Documentation/Performance.md, "Linear solvers").
//
// Per mesh size: topology, 3-channel assembly, one SpMV against the memory-
// bandwidth bound (bytes moved / a STREAM-triad bandwidth measured in the same
// run), a reference solution to a relative residual of 1e-10 (Jacobi-CG,
// restarted until the true residual is below it), then for each solver:
// set-up (pattern changed, and values only), a cold solve from zero and a
// warm solve after a 10-degree light rotation, each at the loosest tolerance
// of a fixed ladder that gives <= 1 % relative L2 error of the boundary
// fluence in every channel; "paint -> new fluence" and "cut -> new fluence"
// (with multigrid-agg); then the interactive figures of issue 22 next to their
// targets, and the memory per tet of every structure.

#include "BenchLinearSolvers.h"
#include "HypreMPI.h"
#include "MeshIO.h"
#include "Process.h"
#include "Utilities.h"

#include "AggregationMultigrid.h"
#include "ConjugateGradient.h"
#include "DiscreteDivergence.h"
#include "Error.h"
#include "LightSources.h"
#include "LinearSolver.h"
#include "OpticalProperties.h"
#include "Radiance.h"
#include "TetCut.h"
#include "TetMesh.h"
#include "TetPaint.h"

#include "vtkTetrahedralizeSurface.h"

#include <vtkNew.h>
#include <vtkPolyData.h>
#include <vtkUnstructuredGrid.h>

#include "vtk_nlohmannjson.h"
#include VTK_NLOHMANN_JSON(json.hpp)

#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>
#include <set>
#include <sstream>
#include <sys/resource.h>

namespace translucency_app
{
using json = nlohmann::json;
using Solution = std::array<Eigen::VectorXd, translucency::NumberOfChannels>;
using Stats = std::array<translucency::LinearSolveStats, translucency::NumberOfChannels>;

double TetrahedralizeForBench(vtkPolyData* surface, double targetTets,
  vtkSmartPointer<vtkUnstructuredGrid>& grid, std::vector<double>& points, std::vector<int>& tets)
{
  MessageCollector messages;
  const auto start = Clock::now();
  vtkNew<vtkTetrahedralizeSurface> tetra;
  messages.Watch(tetra);
  tetra->SetInputData(surface);
  // TetGen, not the default mesher: the benches' meshes (and their figures
  // in Performance.md) stay comparable with those of earlier sessions.
  tetra->SetMesher("tetgen");
  tetra->SetTargetNumberOfTets(static_cast<vtkIdType>(targetTets));
  tetra->Update();
  if (!messages.Errors.empty())
    throw translucency::Error(messages.Last());
  const double ms = MillisecondsSince(start);
  grid = tetra->GetOutput();
  GridToCoreArrays(grid, points, tets);
  return ms;
}

namespace
{

/// Relative tolerances tried, loosest first: the bench uses the first one
/// whose solution has <= 1 % boundary-fluence error in every channel.
const double ToleranceLadder[] = { 0.5, 0.3, 0.2, 0.1, 0.05, 0.03, 0.02, 0.01, 5e-3, 3e-3, 2e-3,
  1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5, 3e-6, 1e-6, 3e-7, 1e-7, 1e-8 };
constexpr double TargetError = 0.01;
constexpr double ReferenceTolerance = 1e-10;
constexpr int BenchMaxIter = 20000;

bool IsPeer(const std::string& name)
{
  static const std::set<std::string> peers = { "cg-jacobi", "cg-ichol", "cholmod", "hypre-amg",
    "hypre-amg-2ranks" };
  return peers.count(name) > 0 || name.rfind("hypre-amg-", 0) == 0;
}

/// max over channels of ||x_B - ref_B|| / ||ref_B|| over the boundary points B.
double BoundaryError(const Solution& x, const Solution& ref, const std::vector<int>& boundary)
{
  double worst = 0.0;
  for (int c = 0; c < 3; ++c)
  {
    double d2 = 0.0, r2 = 0.0;
    for (int i : boundary)
    {
      const double d = x[c][i] - ref[c][i];
      d2 += d * d;
      r2 += ref[c][i] * ref[c][i];
    }
    worst = std::max(worst, r2 > 0 ? std::sqrt(d2 / r2) : std::sqrt(d2));
  }
  return worst;
}

double TrueResidual(const translucency::DiffusionSystem& s, const Solution& x)
{
  double worst = 0.0;
  for (int c = 0; c < 3; ++c)
  {
    const double b = s.RightHandSide[c].norm();
    if (b > 0)
      worst = std::max(worst, (s.RightHandSide[c] - s.Matrix(c) * x[c]).norm() / b);
  }
  return worst;
}

/// Jacobi-CG to a true relative residual <= 1e-10 in every channel
/// (restarted from its result while the recurrence residual drifted).
Solution Reference(const translucency::DiffusionSystem& s, double& residual)
{
  translucency::ConjugateGradient cg;
  cg.SetRelTol(ReferenceTolerance);
  cg.SetMaxIter(200000);
  Solution x;
  cg.Solve(s, x, false);
  residual = TrueResidual(s, x);
  for (int restart = 0; restart < 5 && residual > ReferenceTolerance; ++restart)
  {
    cg.SetRelTol(0.5 * cg.GetRelTol());
    cg.Solve(s, x, true);
    residual = TrueResidual(s, x);
  }
  return x;
}

/// Directional light along `direction` (unit), irradiance 1 W/mm^2, shadows.
std::vector<double> Irradiance(const translucency::TetMesh& mesh,
  const translucency::OpticalProperties& material, const double direction[3])
{
  translucency::LightSource light;
  light.Direction = { direction[0], direction[1], direction[2] };
  std::vector<double> q;
  translucency::ComputeBoundaryIrradiance(mesh,
    translucency::PointRefractiveIndex(mesh, material.RefractiveIndex), { light }, 0.0, 0, true, q);
  return q;
}

/// STREAM triad a = b + s c over 3 x 2^24 doubles (400 MB) on all threads;
/// bandwidth in GB/s (STREAM's convention: 24 bytes per element), median.
double TriadBandwidth(int runs)
{
  const std::int64_t n = std::int64_t(1) << 24;
  std::unique_ptr<double[]> a(new double[n]), b(new double[n]), c(new double[n]);
#pragma omp parallel for schedule(static)
  for (std::int64_t i = 0; i < n; ++i)
  {
    a[i] = 0.0;
    b[i] = 1.0;
    c[i] = 2.0;
  }
  std::vector<double> gbs;
  for (int r = 0; r < std::max(runs, 3); ++r)
  {
    const auto start = Clock::now();
    const double s = 0.5 + r;
#pragma omp parallel for schedule(static)
    for (std::int64_t i = 0; i < n; ++i)
      a[i] = b[i] + s * c[i];
    const double ms = MillisecondsSince(start);
    gbs.push_back(24.0 * n / (ms * 1e6));
  }
  volatile double sink = a[n / 2];
  (void)sink;
  return Median(gbs);
}

/// The 1-minute load average (/proc/loadavg; -1 if unreadable): timings
/// taken while it exceeds the number of cores are inflated.
double LoadAverage()
{
  std::ifstream in("/proc/loadavg");
  double load = -1.0;
  in >> load;
  return in ? load : -1.0;
}

struct Timed
{
  double Ms = 0.0;
  Solution X;
  Stats S{};
};

Timed TimedSolve(translucency::LinearSolver& solver, const translucency::DiffusionSystem& s,
  const Solution* guess)
{
  Timed t;
  if (guess)
    t.X = *guess;
  const auto start = Clock::now();
  solver.Solve(s, t.X, guess != nullptr, t.S);
  t.Ms = MillisecondsSince(start);
  return t;
}

/// One point of the error-vs-time curve.
struct CurvePoint
{
  double Tolerance, Ms, Error, SpMV;
};

/// Solve at each ladder tolerance (once) until the error is <= 1 % (and,
/// with `curve`, on to 1e-5 error for the plot). Returns the index of the
/// loosest tolerance reaching 1 % (or -1), and fills the probe results.
int Calibrate(translucency::LinearSolver& solver, const translucency::DiffusionSystem& s,
  const Solution& ref, const std::vector<int>& boundary, const Solution* guess,
  std::vector<CurvePoint>* curve, std::vector<CurvePoint>& probes)
{
  int chosen = -1;
  const int count = static_cast<int>(sizeof(ToleranceLadder) / sizeof(double));
  for (int k = 0; k < count; ++k)
  {
    solver.SetRelTol(ToleranceLadder[k]);
    const Timed t = TimedSolve(solver, s, guess);
    const double error = BoundaryError(t.X, ref, boundary);
    double spmv = 0.0;
    bool direct = true;
    for (const auto& st : t.S)
    {
      spmv += st.SpMVEquivalents;
      direct = direct && st.Iterations == 0 && st.RelativeResidual < 1e-12;
    }
    probes.push_back({ ToleranceLadder[k], t.Ms, error, spmv });
    if (curve)
      curve->push_back(probes.back());
    if (chosen < 0 && error <= TargetError)
      chosen = k;
    if (direct && guess == nullptr)
    {
      // A direct solve does not depend on the tolerance.
      return chosen;
    }
    if (chosen >= 0 && (!curve || error < 1e-5))
      break;
  }
  return chosen;
}

/// The tolerance an interactive figure is timed at: Calibrate's choice (the
/// loosest reaching 1 % error from `guess`), or the tightest tried when none
/// did (`reached` false). `looser` is the next looser probe's error (-1: none).
void PickTolerance(translucency::LinearSolver& solver, const translucency::DiffusionSystem& s,
  const Solution& ref, const std::vector<int>& boundary, const Solution* guess, double& tolerance,
  double& looser, bool& reached)
{
  std::vector<CurvePoint> probes;
  int k = Calibrate(solver, s, ref, boundary, guess, nullptr, probes);
  reached = k >= 0;
  if (k < 0)
    k = static_cast<int>(probes.size()) - 1;
  tolerance = ToleranceLadder[k];
  looser = k > 0 ? probes[k - 1].Error : -1.0;
}

struct SolverRow
{
  std::string Name;
  double SetupMs = 0, ValuesSetupMs = 0, ColdMs = 0, WarmMs = 0;
  double ColdTol = 0, WarmTol = 0, ColdError = 0, WarmError = 0;
  double ColdLooserError = -1, WarmLooserError = -1; ///< error one ladder step looser (-1: none)
  double ColdSpMV = 0, WarmSpMV = 0;
  std::array<int, 3> ColdIters{}, WarmIters{};
  bool ColdReached = false, WarmReached = false;
  double MemoryBytes = 0;
};

json RowJson(const SolverRow& r, double topologyMs)
{
  return { { "solver", r.Name }, { "peer", IsPeer(r.Name) }, { "setup_ms", r.SetupMs },
    { "setup_with_topology_ms", r.SetupMs + topologyMs },
    { "values_only_setup_ms", r.ValuesSetupMs }, { "cold_ms", r.ColdMs },
    { "cold_tolerance", r.ColdTol }, { "cold_error", r.ColdError },
    { "cold_error_one_step_looser", r.ColdLooserError }, { "cold_reached_1pct", r.ColdReached },
    { "cold_iterations", r.ColdIters }, { "cold_spmv_equivalents", r.ColdSpMV },
    { "warm_ms", r.WarmMs }, { "warm_tolerance", r.WarmTol }, { "warm_error", r.WarmError },
    { "warm_error_one_step_looser", r.WarmLooserError }, { "warm_reached_1pct", r.WarmReached },
    { "warm_iterations", r.WarmIters }, { "warm_spmv_equivalents", r.WarmSpMV },
    { "memory_bytes", r.MemoryBytes } };
}

/// Everything of one mesh size the solvers share.
struct Problem
{
  translucency::TetMesh Mesh;
  translucency::OpticalProperties Material;
  translucency::DiffusionSystem System; ///< right-hand side of light 0
  Solution Rhs0, Rhs1;                  ///< light 0 and the 10-degree rotated light
  Solution Ref0, Ref1;
  double Dir0[3], Dir1[3];
};

SolverRow BenchSolver(const std::string& name, Problem& p, int runs,
  std::vector<CurvePoint>& curve, Solution& coldSolution)
{
  SolverRow row;
  row.Name = name;
  auto solver = translucency::CreateLinearSolver(name);
  solver->SetMaxIter(BenchMaxIter);
  const std::vector<int>& boundary = p.Mesh.GetBoundaryPoints();
  std::vector<double> setup, values;
  // Untimed first set-up: library initialisation (MPI_Init for hypre), page
  // faults of first allocations.
  solver->Setup(p.System, &p.Mesh, true);
  for (int r = 0; r < runs; ++r)
  {
    auto start = Clock::now();
    solver->Setup(p.System, &p.Mesh, true);
    setup.push_back(MillisecondsSince(start));
    start = Clock::now();
    solver->Setup(p.System, &p.Mesh, false);
    values.push_back(MillisecondsSince(start));
  }
  row.SetupMs = Median(setup);
  row.ValuesSetupMs = Median(values);
  row.MemoryBytes = static_cast<double>(solver->GetMemoryBytes());
  if (const auto* agg = dynamic_cast<const translucency::AggregationMultigridSolver*>(solver.get()))
  {
    std::cout << "  " << name << " hierarchy: " << agg->GetNumberOfLevels() << " levels (";
    for (int l = 0; l < agg->GetNumberOfLevels(); ++l)
      std::cout << (l ? " / " : "") << agg->GetLevelSize(l);
    std::cout << " vertices), operator complexity " << std::fixed << std::setprecision(2)
              << agg->GetOperatorComplexity() << std::defaultfloat << "\n";
  }

  // Cold: calibrate, then time at the chosen tolerance.
  p.System.RightHandSide = p.Rhs0;
  std::vector<CurvePoint> probes;
  int k = Calibrate(*solver, p.System, p.Ref0, boundary, nullptr, &curve, probes);
  row.ColdReached = k >= 0;
  if (k < 0)
    k = static_cast<int>(probes.size()) - 1;
  row.ColdTol = ToleranceLadder[k];
  row.ColdLooserError = k > 0 && k < static_cast<int>(probes.size()) ? probes[k - 1].Error : -1;
  solver->SetRelTol(row.ColdTol);
  std::vector<double> cold;
  Timed t;
  for (int r = 0; r < runs; ++r)
  {
    t = TimedSolve(*solver, p.System, nullptr);
    cold.push_back(t.Ms);
  }
  row.ColdMs = Median(cold);
  row.ColdError = BoundaryError(t.X, p.Ref0, boundary);
  for (int c = 0; c < 3; ++c)
  {
    row.ColdIters[c] = t.S[c].Iterations;
    row.ColdSpMV += t.S[c].SpMVEquivalents;
  }
  coldSolution = t.X;

  // Warm: the light turned 10 degrees, starting from the cold solution.
  p.System.RightHandSide = p.Rhs1;
  probes.clear();
  k = Calibrate(*solver, p.System, p.Ref1, boundary, &coldSolution, nullptr, probes);
  row.WarmReached = k >= 0;
  if (k < 0)
    k = static_cast<int>(probes.size()) - 1;
  row.WarmTol = ToleranceLadder[k];
  row.WarmLooserError = k > 0 ? probes[k - 1].Error : -1;
  solver->SetRelTol(row.WarmTol);
  std::vector<double> warm;
  for (int r = 0; r < runs; ++r)
  {
    t = TimedSolve(*solver, p.System, &coldSolution);
    warm.push_back(t.Ms);
  }
  row.WarmMs = Median(warm);
  row.WarmError = BoundaryError(t.X, p.Ref1, boundary);
  for (int c = 0; c < 3; ++c)
  {
    row.WarmIters[c] = t.S[c].Iterations;
    row.WarmSpMV += t.S[c].SpMVEquivalents;
  }
  p.System.RightHandSide = p.Rhs0;
  return row;
}

std::string TempPath(const std::string& tag)
{
  const char* dir = std::getenv("TMPDIR");
  std::ostringstream os;
  os << (dir && *dir ? dir : "/tmp") << "/translucency-bench-" << getpid() << "-" << tag;
  return os.str();
}

std::string ExecutableDirectory()
{
  char buffer[4096];
  const ssize_t len = readlink("/proc/self/exe", buffer, sizeof(buffer) - 1);
  if (len <= 0)
    return ".";
  std::string path(buffer, static_cast<size_t>(len));
  return path.substr(0, path.find_last_of('/'));
}

template <typename T>
void WriteRaw(std::ofstream& out, const T* data, std::size_t count)
{
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(count * sizeof(T)));
}

template <typename T>
bool ReadRaw(std::ifstream& in, T* data, std::size_t count)
{
  in.read(reinterpret_cast<char*>(data), static_cast<std::streamsize>(count * sizeof(T)));
  return static_cast<bool>(in);
}

/// hypre-amg on `ranks` MPI ranks (translucency-hypre-mpi under mpiexec) at
/// the tolerances the in-process run chose. Throws on failure.
SolverRow BenchHypreRanks(Problem& p, int ranks, int runs, const SolverRow& oneRank)
{
  const std::string exe = ExecutableDirectory() + "/translucency-hypre-mpi";
  if (access(exe.c_str(), X_OK) != 0)
    throw translucency::Error("--hypre-ranks: " + exe + " not found (built with hypre only)");
  const std::string in = TempPath("hypre-in.bin"), out = TempPath("hypre-out.bin"),
                    log = TempPath("hypre.log");
  const translucency::DiffusionSystem& s = p.System;
  const std::int32_t n = s.NumberOfUnknowns;
  {
    std::ofstream f(in, std::ios::binary | std::ios::trunc);
    WriteRaw(f, HypreInputMagic, 8);
    const std::int64_t nnz = static_cast<std::int64_t>(s.ColumnIndices.size());
    const std::int32_t r = runs, maxIter = BenchMaxIter;
    WriteRaw(f, &n, 1);
    WriteRaw(f, &nnz, 1);
    WriteRaw(f, &r, 1);
    WriteRaw(f, &maxIter, 1);
    WriteRaw(f, &oneRank.ColdTol, 1);
    WriteRaw(f, &oneRank.WarmTol, 1);
    WriteRaw(f, s.RowOffsets.data(), s.RowOffsets.size());
    WriteRaw(f, s.ColumnIndices.data(), s.ColumnIndices.size());
    for (int c = 0; c < 3; ++c)
      WriteRaw(f, s.Values[c].data(), s.Values[c].size());
    for (const Solution* rhs : { &p.Rhs0, &p.Rhs1 })
      for (int c = 0; c < 3; ++c)
        WriteRaw(f, (*rhs)[c].data(), n);
    if (!f)
      throw translucency::Error("--hypre-ranks: cannot write " + in);
  }
  // OMP_NUM_THREADS=1: the ranks are the parallelism (Debian's hypre has no
  // OpenMP anyway); --allow-run-as-root: Open MPI refuses root otherwise.
  // The in-process hypre-amg made this process an Open MPI singleton, whose
  // OMPI_* / PMIX_* variables would make mpiexec's children join it: drop them.
  const std::vector<std::string> cmd = { "mpiexec", "--allow-run-as-root", "--oversubscribe",
    "-n", std::to_string(ranks), exe, in, out };
  const std::vector<std::string> env = FilteredEnvironment(
    { "OMPI_", "PMIX_", "OPAL_", "ORTE_", "OMP_NUM_THREADS=" }, { "OMP_NUM_THREADS=1" });
  std::string spawnError;
  const int status = RunProgram(cmd, env, log, spawnError);
  std::remove(in.c_str());
  std::ifstream f(out, std::ios::binary);
  if (status != 0 || !f)
  {
    std::ifstream l(log);
    std::stringstream text;
    text << l.rdbuf();
    std::remove(log.c_str());
    std::remove(out.c_str());
    throw translucency::Error("--hypre-ranks: '" + CommandText(cmd) + "' failed (status " +
      std::to_string(status) + "): " + (spawnError.empty() ? text.str() : spawnError));
  }
  std::remove(log.c_str());
  char magic[8];
  std::int32_t header[2];
  double times[3];
  SolverRow row;
  row.Name = "hypre-amg-" + std::to_string(ranks) + "ranks";
  bool ok = ReadRaw(f, magic, 8) && std::memcmp(magic, HypreOutputMagic, 8) == 0 &&
    ReadRaw(f, header, 2) && header[0] == n && ReadRaw(f, times, 3);
  double work[3] = { 0, 0, 0 };
  for (int c = 0; ok && c < 3; ++c)
  {
    std::int32_t iters[2];
    double d[3];
    ok = ReadRaw(f, iters, 2) && ReadRaw(f, d, 3);
    row.ColdIters[c] = iters[0];
    row.WarmIters[c] = iters[1];
    work[c] = d[2];
    row.ColdSpMV += 1.0 + iters[0] * d[2];
    row.WarmSpMV += 1.0 + iters[1] * d[2];
  }
  Solution cold, warm;
  for (Solution* x : { &cold, &warm })
    for (int c = 0; ok && c < 3; ++c)
    {
      (*x)[c].resize(n);
      ok = ReadRaw(f, (*x)[c].data(), n);
    }
  f.close();
  std::remove(out.c_str());
  if (!ok)
    throw translucency::Error("--hypre-ranks: bad result file from " + exe);
  row.SetupMs = times[0];
  row.ValuesSetupMs = times[0];
  row.ColdMs = times[1];
  row.WarmMs = times[2];
  row.ColdTol = oneRank.ColdTol;
  row.WarmTol = oneRank.WarmTol;
  const std::vector<int>& boundary = p.Mesh.GetBoundaryPoints();
  row.ColdError = BoundaryError(cold, p.Ref0, boundary);
  row.WarmError = BoundaryError(warm, p.Ref1, boundary);
  row.ColdReached = row.ColdError <= TargetError;
  row.WarmReached = row.WarmError <= TargetError;
  return row;
}

/// Plane cut through the centre (normal +x, Solvers/TetCut), then topology,
/// irradiance, assembly, Setup(patternChanged = true) and a solve warm-started
/// from the kept vertices' fluence, with `solverName`. The tolerance is the
/// loosest of the ladder giving <= 1 % boundary error on the cut mesh (found
/// in an untimed first pass against a 1e-10 reference of the cut mesh).
json BenchCut(const std::string& solverName, const Problem& p, const Solution& previous, int runs)
{
  const std::vector<double>& points = p.Mesh.GetPoints();
  const std::vector<int>& tets = p.Mesh.GetTets();
  double lo = std::numeric_limits<double>::max(), hi = -lo;
  for (size_t i = 0; i < points.size(); i += 3)
  {
    lo = std::min(lo, points[i]);
    hi = std::max(hi, points[i]);
  }
  const double cx = 0.5 * (lo + hi);
  std::vector<double> cutMs, topoMs, lightMs, setupMs, asmMs, solveMs, totalMs;
  Solution x, ref;
  translucency::TetMesh mesh;
  translucency::DiffusionSystem system;
  int kept = 0, iterations = 0;
  double tolerance = 0.0, residual = 0.0, looser = -1.0;
  bool reached = false;
  for (int r = -1; r < runs; ++r) // r = -1: untimed calibration pass
  {
    auto solver = translucency::CreateLinearSolver(solverName);
    solver->SetRelTol(tolerance);
    solver->SetMaxIter(BenchMaxIter);
    const auto begin = Clock::now();
    auto start = begin;
    std::vector<double> side(points.size() / 3);
#pragma omp parallel for schedule(static)
    for (std::int64_t i = 0; i < static_cast<std::int64_t>(side.size()); ++i)
      side[i] = points[3 * i] - cx;
    translucency::TetCut cut;
    cut.Cut(points, tets, side, [cx](const double* y) { return y[0] - cx; });
    cutMs.push_back(MillisecondsSince(start));
    start = Clock::now();
    mesh.SetGeometry(cut.GetPoints(), cut.GetTets());
    topoMs.push_back(MillisecondsSince(start));
    kept = mesh.GetNumberOfTets();
    const translucency::MaterialPreset& marble = translucency::FindMaterialPreset("marble");
    const auto material = translucency::OpticalProperties::Uniform(
      kept, marble.Absorption, marble.ReducedScattering, marble.RefractiveIndex);
    start = Clock::now();
    const std::vector<double> q = Irradiance(mesh, material, p.Dir0);
    lightMs.push_back(MillisecondsSince(start));
    start = Clock::now();
    translucency::DiscreteDivergence().Assemble(mesh, material, q, system);
    asmMs.push_back(MillisecondsSince(start));
    start = Clock::now();
    solver->Setup(system, &mesh, true);
    setupMs.push_back(MillisecondsSince(start));
    // Warm start: the fluence the kept vertices had before the cut.
    const std::vector<int>& keptPoints = cut.GetKeptPoints();
    Solution guess;
    for (int c = 0; c < 3; ++c)
    {
      guess[c].resize(mesh.GetNumberOfPoints());
      for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
        guess[c][i] = previous[c][keptPoints[i]];
    }
    if (r < 0)
    {
      ref = Reference(system, residual);
      PickTolerance(*solver, system, ref, mesh.GetBoundaryPoints(), &guess, tolerance, looser,
        reached);
      cutMs.clear();
      topoMs.clear();
      lightMs.clear();
      asmMs.clear();
      setupMs.clear();
      continue;
    }
    x = guess;
    Stats stats;
    start = Clock::now();
    solver->Solve(system, x, true, stats);
    solveMs.push_back(MillisecondsSince(start));
    totalMs.push_back(MillisecondsSince(begin));
    iterations = stats[0].Iterations;
  }
  const double error = BoundaryError(x, ref, mesh.GetBoundaryPoints());
  const double cut = Median(cutMs), topo = Median(topoMs), light = Median(lightMs);
  const double setup = Median(setupMs), as = Median(asmMs), solve = Median(solveMs);
  std::cout << std::fixed << std::setprecision(1) << "  cut -> new fluence (" << solverName
            << ", tolerance " << std::setprecision(3) << tolerance << std::setprecision(1)
            << ", warm from the kept vertices): plane cut " << cut << " + topology " << topo
            << " + irradiance " << light << " + assembly " << as << " + setup " << setup
            << " + solve " << solve << " = " << Median(totalMs) << " ms (" << kept
            << " tets kept, R iterations " << iterations << ", boundary error "
            << std::setprecision(2) << 100.0 * error << " %); without the irradiance "
            << std::setprecision(1) << cut + topo + as + setup + solve << " ms\n"
            << std::defaultfloat;
  return { { "solver", solverName }, { "tolerance", tolerance }, { "cut_ms", cut },
    { "topology_ms", topo }, { "irradiance_ms", light }, { "assembly_ms", as },
    { "setup_ms", setup }, { "solve_ms", solve }, { "total_ms", Median(totalMs) },
    { "total_without_irradiance_ms", cut + topo + as + setup + solve }, { "tets_kept", kept },
    { "iterations_R", iterations }, { "error", error }, { "reached_1pct", reached },
    { "error_one_step_looser", looser }, { "reference_residual", residual } };
}

/// Paint stroke -> new fluence with `solverName` on the lit uncut mesh: a
/// stroke point on top of the object (width 2.4 % of the bounding-box
/// diagonal, ~1 % of the tets at 1M, as `bench --edit`) sets the ketchup
/// coefficients (translucency::TetPaint, cut-off 1e-6), then
/// DiscreteDivergence::UpdateTets rebuilds the touched rows, the solver's
/// values-only Setup and a solve warm-started from `previous` at the loosest
/// ladder tolerance giving <= 1 % boundary error (untimed calibration pass
/// against a 1e-10 reference of the painted system). Same-run baseline: the
/// same with a full 3-channel assembly instead of the row update.
json BenchPaint(const std::string& solverName, const Problem& p, const Solution& previous,
  int runs)
{
  const std::vector<double>& points = p.Mesh.GetPoints();
  double lo[3] = { 1e300, 1e300, 1e300 }, hi[3] = { -1e300, -1e300, -1e300 };
  for (size_t i = 0; i < points.size(); i += 3)
    for (int d = 0; d < 3; ++d)
    {
      lo[d] = std::min(lo[d], points[i + d]);
      hi[d] = std::max(hi[d], points[i + d]);
    }
  const double diag = std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) +
    (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
  const translucency::MaterialPreset& ketchup = translucency::FindMaterialPreset("ketchup");
  translucency::TetPaint paint;
  paint.SetStrokePoints({ 0.5 * (lo[0] + hi[0]), hi[1], 0.5 * (lo[2] + hi[2]) });
  paint.SetWidth(0.024 * diag);
  paint.SetTargetAbsorption({ ketchup.Absorption[0], ketchup.Absorption[1], ketchup.Absorption[2] });
  paint.SetTargetScattering({ ketchup.ReducedScattering[0], ketchup.ReducedScattering[1],
    ketchup.ReducedScattering[2] });
  const std::vector<double> q = Irradiance(p.Mesh, p.Material, p.Dir0);
  translucency::DiscreteDivergence disc;
  translucency::DiffusionSystem base;
  disc.Assemble(p.Mesh, p.Material, q, base);
  auto solver = translucency::CreateLinearSolver(solverName);
  solver->SetMaxIter(BenchMaxIter);
  solver->Setup(base, &p.Mesh, true);
  std::vector<double> paintMs, rowsMs, valuesMs, solveMs, totalMs, fullAsmMs, baselineMs;
  // Values-only set-up of every level (Setup with the pattern kept), the
  // set-up the row update replaces.
  std::vector<double> allLevelsMs;
  for (int r = 0; r < runs; ++r)
  {
    const auto start = Clock::now();
    solver->Setup(base, &p.Mesh, false);
    allLevelsMs.push_back(MillisecondsSince(start));
  }
  double tolerance = 0.0, looser = -1.0, error = 0.0, residual = 0.0;
  bool reached = false;
  int touched = 0, iterations = 0;
  Solution ref, x;
  for (int r = -1; r < runs; ++r) // r = -1: untimed calibration pass
  {
    translucency::OpticalProperties material = p.Material;
    translucency::DiffusionSystem system = base;
    solver->SetRelTol(tolerance);
    auto start = Clock::now();
    const auto begin = start;
    paint.Paint(points, p.Mesh.GetTets(), material.AbsorptionCoefficient,
      material.ReducedScatteringCoefficient, nullptr);
    paintMs.push_back(MillisecondsSince(start));
    touched = static_cast<int>(paint.GetChangedCells().size());
    start = Clock::now();
    disc.UpdateTets(p.Mesh, material, q, paint.GetChangedCells(), system);
    rowsMs.push_back(MillisecondsSince(start));
    start = Clock::now();
    {
      // The rows of the painted tets' vertices (multigrid-agg refreshes
      // their level-0 smoother and keeps its coarse levels).
      const std::vector<int>& tets = p.Mesh.GetTets();
      std::vector<int> rows;
      rows.reserve(4 * paint.GetChangedCells().size());
      for (const int t : paint.GetChangedCells())
        for (int v = 0; v < 4; ++v)
          rows.push_back(tets[4 * static_cast<size_t>(t) + v]);
      solver->SetupChangedRows(system, &p.Mesh, rows);
    }
    valuesMs.push_back(MillisecondsSince(start));
    if (r < 0)
    {
      ref = Reference(system, residual);
      PickTolerance(*solver, system, ref, p.Mesh.GetBoundaryPoints(), &previous, tolerance, looser,
        reached);
      paintMs.clear();
      rowsMs.clear();
      valuesMs.clear();
      continue;
    }
    x = previous;
    Stats stats;
    start = Clock::now();
    solver->Solve(system, x, true, stats);
    solveMs.push_back(MillisecondsSince(start));
    totalMs.push_back(MillisecondsSince(begin));
    iterations = stats[0].Iterations;
    error = BoundaryError(x, ref, p.Mesh.GetBoundaryPoints());
    // Baseline: the full 3-channel assembly instead of the row update.
    translucency::DiffusionSystem full;
    start = Clock::now();
    disc.Assemble(p.Mesh, material, q, full);
    fullAsmMs.push_back(MillisecondsSince(start));
    baselineMs.push_back(paintMs.back() + fullAsmMs.back() + valuesMs.back() + solveMs.back());
  }
  const double pm = Median(paintMs), rm = Median(rowsMs), vm = Median(valuesMs),
               sm = Median(solveMs), tm = Median(totalMs);
  std::cout << std::fixed << std::setprecision(1) << "  paint -> new fluence (" << solverName
            << ", tolerance " << std::setprecision(3) << tolerance << std::setprecision(1)
            << ", warm from the unpainted fluence): paint " << pm << " (" << touched << " tets, "
            << std::setprecision(2) << 100.0 * touched / p.Mesh.GetNumberOfTets()
            << " %) + rows " << rm << " + values-only setup " << vm << " + solve " << sm
            << std::setprecision(1) << " = " << tm << " ms (R iterations " << iterations
            << ", boundary error " << std::setprecision(2) << 100.0 * error
            << " %); same-run baseline with a full assembly instead of the rows "
            << std::setprecision(1) << Median(baselineMs)
            << " ms; values-only set-up of every level instead of the rows' " << Median(allLevelsMs)
            << " ms\n"
            << std::defaultfloat;
  return { { "solver", solverName }, { "tolerance", tolerance }, { "paint_ms", pm },
    { "rows_ms", rm }, { "values_setup_ms", vm }, { "solve_ms", sm }, { "total_ms", tm },
    { "tets_painted", touched }, { "iterations_R", iterations }, { "error", error },
    { "reached_1pct", reached }, { "error_one_step_looser", looser },
    { "reference_residual", residual }, { "full_assembly_ms", Median(fullAsmMs) },
    { "baseline_full_assembly_total_ms", Median(baselineMs) },
    { "values_setup_all_levels_ms", Median(allLevelsMs) } };
}

/// Relight while a light is dragged, with `solverName` (multigrid-agg):
/// the light turns in 10-degree steps about the x axis, -20, -10, 0
/// (light 0), then +10 degrees (light 1, timed), each solve warm-started
/// from the previous frame's solution at the same tolerance T (the first
/// from zero). With recycling the solver keeps the frames' solutions
/// (SetRecycledSolutions(3)) and starts +10 from the A-norm-best
/// combination of them (SolutionRecycler); without, from the 0-degree
/// solution only (the same-run baseline). T: the loosest ladder tolerance
/// giving <= 1 % boundary error at +10 degrees against the reference, each
/// variant calibrated on its own sequence (untimed pass); the history is
/// cleared and rebuilt before every timed frame.
json BenchDrag(const std::string& solverName, const Problem& p, int runs)
{
  translucency::DiscreteDivergence disc;
  const double s2 = std::sqrt(0.5);
  std::vector<Solution> rhs;
  for (const double degrees : { -20.0, -10.0 })
  {
    const double t = degrees * M_PI / 180.0;
    const double dir[3] = { 0.0, -s2 * std::cos(t) + s2 * std::sin(t),
      -s2 * std::sin(t) - s2 * std::cos(t) };
    translucency::DiffusionSystem s;
    disc.Assemble(p.Mesh, p.Material, Irradiance(p.Mesh, p.Material, dir), s);
    rhs.push_back(s.RightHandSide);
  }
  rhs.push_back(p.Rhs0);
  auto solver = translucency::CreateLinearSolver(solverName);
  auto* agg = dynamic_cast<translucency::AggregationMultigridSolver*>(solver.get());
  if (!agg)
    return json::object();
  solver->SetMaxIter(BenchMaxIter);
  translucency::DiffusionSystem system = p.System;
  solver->Setup(system, &p.Mesh, true);
  const std::vector<int>& boundary = p.Mesh.GetBoundaryPoints();
  // The frames before +10 degrees (untimed), then the timed one.
  auto frame = [&](double tol, Timed& t)
  {
    agg->ClearRecycledSolutions();
    solver->SetRelTol(tol);
    Solution x;
    for (std::size_t f = 0; f < rhs.size(); ++f)
    {
      system.RightHandSide = rhs[f];
      Stats stats;
      solver->Solve(system, x, f > 0, stats);
    }
    system.RightHandSide = p.Rhs1;
    t = TimedSolve(*solver, system, &x);
  };
  json out = { { "solver", solverName }, { "steps_degrees", 10 } };
  const int count = static_cast<int>(sizeof(ToleranceLadder) / sizeof(double));
  for (const int k : { 3, 0 })
  {
    agg->SetRecycledSolutions(k);
    int chosen = -1;
    double looser = -1.0;
    Timed t;
    for (int l = 0; l < count && chosen < 0; ++l)
    {
      frame(ToleranceLadder[l], t);
      const double error = BoundaryError(t.X, p.Ref1, boundary);
      if (error <= TargetError)
        chosen = l;
      else
        looser = error;
    }
    const bool reached = chosen >= 0;
    const double tol = ToleranceLadder[reached ? chosen : count - 1];
    std::vector<double> ms;
    for (int r = 0; r < runs; ++r)
    {
      frame(tol, t);
      ms.push_back(t.Ms);
    }
    double spmv = 0.0;
    for (const auto& st : t.S)
      spmv += st.SpMVEquivalents;
    const double error = BoundaryError(t.X, p.Ref1, boundary);
    const std::string key = k > 0 ? "recycled" : "previous_frame_only";
    out[key] = { { "recycled_solutions", k }, { "ms", Median(ms) }, { "tolerance", tol },
      { "iterations", { t.S[0].Iterations, t.S[1].Iterations, t.S[2].Iterations } },
      { "spmv_equivalents", spmv }, { "error", error }, { "reached_1pct", reached },
      { "error_one_step_looser", looser } };
    std::cout << std::fixed << std::setprecision(1) << "  relight during a drag (" << solverName
              << ", 10-degree steps, " << (k > 0 ? "3 recycled solutions" : "previous frame only")
              << "): " << Median(ms) << " ms (tolerance " << std::setprecision(2) << tol
              << ", iterations " << t.S[0].Iterations << "/" << t.S[1].Iterations << "/"
              << t.S[2].Iterations << ", " << std::setprecision(1) << spmv
              << " SpMVs, boundary error " << std::setprecision(2) << 100.0 * error << " %"
              << (reached ? "" : " !") << ")\n"
              << std::defaultfloat;
  }
  return out;
}

/// Peak resident set size of this process so far (bytes; getrusage).
double PeakRssBytes()
{
  struct rusage usage;
  getrusage(RUSAGE_SELF, &usage);
  return 1024.0 * static_cast<double>(usage.ru_maxrss);
}

std::string OneDecimal(double v)
{
  std::ostringstream os;
  os << std::fixed << std::setprecision(1) << v;
  return os.str();
}

/// One row of the issue-22 table: this run's figure, the idle
/// figure ("today", -1: none), the target, and a same-run baseline (-1: none).
struct TargetRow
{
  std::string Figure;
  double Ms, Today, Target, Baseline;
  std::string BaselineName;
};

/// Prints the interactive figures of issue 22 (section 3) next to their
/// targets. Absolute times depend on the machine's load: the "SpMVs" columns
/// divide by this run's one-channel SpMV, and the target's by the idle SpMV
/// of the same mesh (1.90 ms, Performance.md, session 16).
json PrintTargets(const std::vector<SolverRow>& rows, const json& entry,
  const std::string& cutSolver, double spmvMs)
{
  constexpr double IdleSpMVMs = 1.90;
  const SolverRow* agg = nullptr;
  const SolverRow* cg = nullptr;
  for (const SolverRow& r : rows)
  {
    if (r.Name == cutSolver)
      agg = &r;
    if (r.Name == "cg-jacobi")
      cg = &r;
  }
  std::vector<TargetRow> table;
  if (agg)
    table.push_back({ "warm relight, 3 channels (" + cutSolver + ")", agg->WarmMs, 28.9, 16.0,
      cg ? cg->WarmMs : -1.0, "cg-jacobi warm" });
  const json& paint = entry["paint"];
  table.push_back({ "paint 1 % -> new fluence (paint + rows + values set-up + warm solve)",
    paint["total_ms"].get<double>(), -1.0, 33.0,
    paint["baseline_full_assembly_total_ms"].get<double>(), "full assembly instead of rows" });
  if (entry.contains("cut"))
  {
    const json& cut = entry["cut"];
    table.push_back({ "plane cut -> new fluence (cut, topology, irradiance, assembly, hierarchy, solve)",
      cut["total_ms"].get<double>(), 241.0, 120.0, -1.0, "" });
    table.push_back({ "topology + hierarchy after a cut",
      cut["topology_ms"].get<double>() + cut["setup_ms"].get<double>(), 212.0, 120.0, -1.0, "" });
  }
  table.push_back({ "3-channel assembly", entry["assembly_3ch_ms"].get<double>(), 28.6, 22.0,
    3.0 * spmvMs, "3 SpMVs" });
  if (agg)
    table.push_back({ "cold 3-channel solve to 1 % (" + cutSolver + ")", agg->ColdMs, 52.0, 40.0,
      cg ? cg->ColdMs : -1.0, "cg-jacobi cold" });
  std::cout << "\n  issue 22 targets (this run; SpMVs = ms / this run's one SpMV of " << std::fixed
            << std::setprecision(2) << spmvMs << " ms; target SpMVs = target / the idle SpMV of "
            << IdleSpMVMs << " ms):\n"
            << "  " << std::left << std::setw(84) << "figure" << std::right << std::setw(9)
            << "ms" << std::setw(8) << "SpMVs" << std::setw(9) << "today" << std::setw(8)
            << "target" << std::setw(8) << "t.SpMVs" << std::setw(9) << "met ms" << std::setw(11)
            << "met SpMVs" << "  same-run baseline\n";
  json out = json::array();
  for (const TargetRow& t : table)
  {
    const double spmvs = t.Ms / spmvMs, targetSpmvs = t.Target / IdleSpMVMs;
    const bool met = spmvs <= targetSpmvs;
    std::cout << "  " << std::left << std::setw(84) << t.Figure << std::right
              << std::setprecision(1) << std::setw(9) << t.Ms << std::setw(8) << spmvs
              << std::setw(9) << (t.Today >= 0 ? OneDecimal(t.Today) : std::string("-"))
              << std::setw(8) << t.Target << std::setw(8) << targetSpmvs << std::setw(9)
              << (t.Ms <= t.Target ? "yes" : "no") << std::setw(11) << (met ? "yes" : "no");
    if (t.Baseline >= 0)
      std::cout << "  " << t.BaselineName << " " << t.Baseline << " ms (x" << std::setprecision(2)
                << t.Ms / t.Baseline << ")";
    std::cout << "\n";
    out.push_back({ { "figure", t.Figure }, { "ms", t.Ms }, { "spmvs", spmvs },
      { "today_idle_ms", t.Today }, { "target_ms", t.Target }, { "target_spmvs", targetSpmvs },
      { "met_in_spmvs", met }, { "met_in_ms", t.Ms <= t.Target }, { "baseline", t.BaselineName }, { "baseline_ms", t.Baseline } });
  }
  std::cout << "  (targets and today's figures: 1M tets, idle; met SpMVs = this run's figure in "
               "SpMVs <= the target in idle SpMVs, a load-independent reading while the machine "
               "is shared)\n" << std::defaultfloat;
  return out;
}

/// Bytes per tet of every structure of one lit, assembled, solvable mesh.
json PrintMemory(const Problem& p, const translucency::DiscreteDivergence& disc,
  const std::vector<double>& irradiance, const std::vector<SolverRow>& rows,
  const std::string& cutSolver)
{
  const double tets = p.Mesh.GetNumberOfTets();
  double hierarchy = -1.0;
  for (const SolverRow& r : rows)
    if (r.Name == cutSolver)
      hierarchy = r.MemoryBytes;
  double solution = 0.0, material = 0.0;
  for (int c = 0; c < 3; ++c)
    solution += 8.0 * p.Ref0[c].size();
  material = 8.0 * (p.Material.AbsorptionCoefficient.capacity() +
    p.Material.ReducedScatteringCoefficient.capacity() + p.Material.RefractiveIndex.capacity());
  const std::vector<std::pair<std::string, double>> parts = {
    { "mesh (points, tets)", static_cast<double>(p.Mesh.GetGeometryMemoryBytes()) },
    { "topology (volumes, boundary, CSR pattern, incidence, entry positions, schedule)",
      static_cast<double>(p.Mesh.GetTopologyMemoryBytes()) },
    { "material (mu_a, sigma_s', n per tet)", material },
    { "assembler geometry cache", static_cast<double>(disc.GetCacheMemoryBytes()) },
    { "3-channel system (pattern, values, right-hand sides)",
      static_cast<double>(p.System.GetMemoryBytes()) },
    { cutSolver + " hierarchy", hierarchy },
    { "irradiance (3 channels per point)", 8.0 * irradiance.capacity() },
    { "fluence (3 channels per point)", solution } };
  std::cout << "\n  memory at " << static_cast<long>(tets) << " tets (bytes per tet; MB):\n";
  json out = json::object();
  double total = 0.0;
  for (const auto& part : parts)
  {
    if (part.second < 0)
      continue;
    total += part.second;
    std::cout << "    " << std::left << std::setw(82) << part.first << std::right << std::fixed
              << std::setprecision(1) << std::setw(8) << part.second / tets << std::setw(9)
              << part.second / 1048576.0 << "\n";
    out[part.first] = part.second / tets;
  }
  const double peak = PeakRssBytes();
  std::cout << "    " << std::left << std::setw(82) << "sum of the above" << std::right
            << std::setw(8) << total / tets << std::setw(9) << total / 1048576.0 << "\n"
            << "    " << std::left << std::setw(82)
            << "peak RSS of this bench process so far (all solvers, references, TetGen)"
            << std::right << std::setw(8) << peak / tets << std::setw(9) << peak / 1048576.0
            << "\n" << std::defaultfloat;
  out["sum"] = total / tets;
  out["peak_rss_bytes"] = peak;
  return out;
}

void PrintRows(const std::vector<SolverRow>& rows, double topologyMs)
{
  // Ratios against the best peer of this size (setup + cold; warm).
  double bestCold = std::numeric_limits<double>::infinity(), bestWarm = bestCold;
  std::string bestColdName, bestWarmName;
  for (const SolverRow& r : rows)
  {
    if (!IsPeer(r.Name))
      continue;
    if (r.ColdReached && r.SetupMs + r.ColdMs < bestCold)
    {
      bestCold = r.SetupMs + r.ColdMs;
      bestColdName = r.Name;
    }
    if (r.WarmReached && r.WarmMs < bestWarm)
    {
      bestWarm = r.WarmMs;
      bestWarmName = r.Name;
    }
  }
  std::cout << "  " << std::left << std::setw(18) << "solver" << std::right << std::setw(10)
            << "setup" << std::setw(10) << "values" << std::setw(9) << "cold" << std::setw(8)
            << "tol" << std::setw(15) << "iters R/G/B" << std::setw(8) << "SpMVs" << std::setw(7)
            << "err%" << std::setw(9) << "warm" << std::setw(8) << "tol" << std::setw(15)
            << "iters R/G/B" << std::setw(8) << "SpMVs" << std::setw(7) << "err%"
            << std::setw(12) << "setup+cold" << std::setw(8) << "/best" << std::setw(8)
            << "warm/b" << "\n";
  for (const SolverRow& r : rows)
  {
    auto iters = [](const std::array<int, 3>& i) {
      return std::to_string(i[0]) + "/" + std::to_string(i[1]) + "/" + std::to_string(i[2]);
    };
    std::ostringstream tolC, tolW;
    tolC << std::setprecision(2) << r.ColdTol;
    tolW << std::setprecision(2) << r.WarmTol;
    std::cout << std::fixed << "  " << std::left << std::setw(18) << r.Name << std::right
              << std::setprecision(1) << std::setw(10) << r.SetupMs + topologyMs << std::setw(10)
              << r.ValuesSetupMs << std::setw(9) << r.ColdMs << std::setw(8) << tolC.str()
              << std::setw(15) << iters(r.ColdIters) << std::setw(8) << r.ColdSpMV
              << std::setprecision(2) << std::setw(7) << 100 * r.ColdError
              << (r.ColdReached ? "" : "!") << std::setprecision(1) << std::setw(9) << r.WarmMs
              << std::setw(8) << tolW.str() << std::setw(15) << iters(r.WarmIters) << std::setw(8)
              << r.WarmSpMV << std::setprecision(2) << std::setw(7) << 100 * r.WarmError
              << (r.WarmReached ? "" : "!") << std::setprecision(1) << std::setw(12)
              << r.SetupMs + r.ColdMs << std::setprecision(2) << std::setw(8)
              << (r.SetupMs + r.ColdMs) / bestCold << std::setw(8) << r.WarmMs / bestWarm << "\n"
              << std::defaultfloat;
  }
  std::cout << "  (ms, medians; setup includes the topology; values = Setup with the pattern "
               "kept; SpMVs = work in SpMV-equivalents, 3 channels; ratios against the best "
               "peer: "
            << bestColdName << " for setup+cold, " << bestWarmName << " for warm; ! = 1 % not "
            << "reached)\n";
}

} // namespace

std::string PlotDataPath(const std::string& plotPath)
{
  return std::filesystem::path(plotPath).replace_extension(".csv").string();
}

namespace
{

/// The set-up figures of one mesh size (ms, medians of the runs).
struct ProblemFigures
{
  double TetgenMs = 0.0, TopologyMs = 0.0, AssemblyMs = 0.0;
  /// The first assembly (a new system and geometry cache: allocation, first
  /// touch, the per-tet geometry computed); AssemblyMs is the median of the
  /// later runs (values only), or the first when --runs is 1.
  double AssemblyColdMs = 0.0;
  double SpmvMs = 0.0, SpmvBytes = 0.0, BoundMs = 0.0; ///< one SpMV, red channel
  double ReferenceResidual = 0.0;
  int Unknowns = 0;       ///< per channel
  double NonZeros = 0.0;  ///< of one channel's matrix
};

/// BenchLinearSolvers, one size: the problem of the solvers (the surface
/// tetrahedralized to `target` tets, marble, two lights, the assembled
/// system, the reference solutions), the timings of its set-up, and one
/// line about it on stdout. `disc` and `q0` (light 0's irradiance) are kept
/// for the memory figures.
ProblemFigures BuildBenchProblem(vtkPolyData* surface, vtkSmartPointer<vtkUnstructuredGrid>& grid,
  double target, int runs, double bandwidth, Problem& p, translucency::DiscreteDivergence& disc,
  std::vector<double>& q0)
{
  ProblemFigures f;
  std::vector<double> points;
  std::vector<int> tets;
  f.TetgenMs = TetrahedralizeForBench(surface, target, grid, points, tets);
  std::vector<double> topo;
  for (int r = 0; r < runs; ++r)
  {
    const auto start = Clock::now();
    p.Mesh.SetGeometry(points, tets);
    topo.push_back(MillisecondsSince(start));
  }
  f.TopologyMs = Median(topo);
  const translucency::MaterialPreset& marble = translucency::FindMaterialPreset("marble");
  p.Material = translucency::OpticalProperties::Uniform(p.Mesh.GetNumberOfTets(),
    marble.Absorption, marble.ReducedScattering, marble.RefractiveIndex);
  // Light 0 travels along (0, -1, -1) / sqrt(2) (as in `bench`); light 1
  // is light 0 turned 10 degrees about the x axis.
  const double s2 = std::sqrt(0.5), t10 = 10.0 * M_PI / 180.0;
  p.Dir0[0] = 0.0;
  p.Dir0[1] = -s2;
  p.Dir0[2] = -s2;
  p.Dir1[0] = 0.0;
  p.Dir1[1] = -s2 * std::cos(t10) + s2 * std::sin(t10);
  p.Dir1[2] = -s2 * std::sin(t10) - s2 * std::cos(t10);
  q0 = Irradiance(p.Mesh, p.Material, p.Dir0);
  const std::vector<double> q1 = Irradiance(p.Mesh, p.Material, p.Dir1);
  std::vector<double> assembly;
  for (int r = 0; r < runs; ++r)
  {
    const auto start = Clock::now();
    disc.Assemble(p.Mesh, p.Material, q0, p.System);
    assembly.push_back(MillisecondsSince(start));
  }
  // The first assembly is cold; a re-assembly (a light or material change)
  // is warm: reported apart, so that figures of different --runs compare.
  f.AssemblyColdMs = assembly.front();
  f.AssemblyMs = assembly.size() > 1
    ? Median(std::vector<double>(assembly.begin() + 1, assembly.end()))
    : assembly.front();
  p.Rhs0 = p.System.RightHandSide;
  {
    translucency::DiffusionSystem rotated;
    disc.Assemble(p.Mesh, p.Material, q1, rotated);
    p.Rhs1 = rotated.RightHandSide;
  }
  // One SpMV (red channel) and its bandwidth bound.
  const int n = p.System.NumberOfUnknowns;
  const double nnz = static_cast<double>(p.System.ColumnIndices.size());
  f.Unknowns = n;
  f.NonZeros = nnz;
  Eigen::VectorXd x = Eigen::VectorXd::Ones(n), y(n);
  std::vector<double> spmv;
  for (int r = 0; r < std::max(runs, 5); ++r)
  {
    const auto start = Clock::now();
    y.noalias() = p.System.Matrix(0) * x;
    spmv.push_back(MillisecondsSince(start));
  }
  f.SpmvMs = Median(spmv);
  // Values (8 B) and column indices (4 B) per nonzero, row offsets (4 B),
  // x read once and y written once (8 B each) per row: the minimum traffic.
  f.SpmvBytes = 12.0 * nnz + 4.0 * (n + 1) + 16.0 * n;
  f.BoundMs = f.SpmvBytes / (bandwidth * 1e6);
  double res0 = 0.0, res1 = 0.0;
  p.System.RightHandSide = p.Rhs1;
  p.Ref1 = Reference(p.System, res1);
  p.System.RightHandSide = p.Rhs0;
  p.Ref0 = Reference(p.System, res0);
  f.ReferenceResidual = std::max(res0, res1);

  std::cout << "\nbunny, target " << static_cast<long>(target) << ": " << p.Mesh.GetNumberOfTets()
            << " tets, " << n << " unknowns, " << static_cast<long>(nnz) << " nonzeros; TetGen "
            << std::fixed << std::setprecision(0) << f.TetgenMs << " ms (excluded); topology "
            << std::setprecision(1) << f.TopologyMs << " ms; 3-channel assembly " << f.AssemblyMs
            << " ms (the first, cold: " << f.AssemblyColdMs << " ms); one SpMV " << std::setprecision(3) << f.SpmvMs << " ms (bandwidth bound "
            << f.BoundMs << " ms); reference residual " << std::scientific << std::setprecision(1)
            << f.ReferenceResidual << "\n" << std::defaultfloat << std::flush;
  return f;
}

/// BenchLinearSolvers, one size: the row of every solver (and the
/// multi-rank hypre row after hypre-amg), their error-vs-time curves (CSV
/// lines and JSON); the cold solution of `cutSolver` in `cutCold` (empty
/// when it is not listed); a failed multi-rank hypre figure in
/// `hypreRanksError`.
std::vector<SolverRow> BenchSolverRows(const std::vector<std::string>& names, Problem& p,
  int runs, int hypreRanks, const std::string& cutSolver, std::vector<std::string>& csv,
  json& curveJson, Solution& cutCold, std::string& hypreRanksError)
{
  std::vector<SolverRow> rows;
  for (const std::string& name : names)
  {
    std::vector<CurvePoint> curve;
    Solution cold;
    rows.push_back(BenchSolver(name, p, runs, curve, cold));
    if (name == cutSolver)
      cutCold = cold;
    for (const CurvePoint& c : curve)
    {
      std::ostringstream line;
      line << p.Mesh.GetNumberOfTets() << "," << name << "," << c.Tolerance << "," << c.Ms
           << "," << c.Error << "," << c.SpMV;
      csv.push_back(line.str());
      curveJson.push_back({ { "solver", name }, { "tolerance", c.Tolerance },
        { "solve_ms", c.Ms }, { "error", c.Error }, { "spmv_equivalents", c.SpMV } });
    }
    if (name == "hypre-amg" && hypreRanks >= 2)
    {
      // A missing or broken mpiexec costs the multi-rank row, not the bench.
      try
      {
        rows.push_back(BenchHypreRanks(p, hypreRanks, runs, rows.back()));
      }
      catch (const translucency::Error& e)
      {
        hypreRanksError = e.what();
        std::cerr << "translucency: warning: no " << hypreRanks << "-rank hypre figure: "
                  << e.what() << "\n";
      }
    }
  }
  return rows;
}

/// BenchLinearSolvers: the curves as CSV next to `plotPath` and the plot
/// drawn by scripts/plot_linear_solvers.py (a failure only warns).
void WriteLinearSolverPlot(const std::string& plotPath, const std::vector<std::string>& csv)
{
  std::string error;
  EnsureParentDirectory(plotPath);
  const std::string csvPath = PlotDataPath(plotPath);
  std::string text;
  for (const std::string& line : csv)
    text += line + "\n";
  if (!WriteText(csvPath, text, error))
    throw translucency::Error(error);
  const std::string script =
    std::string(TRANSLUCENCY_SOURCE_DIR) + "/scripts/plot_linear_solvers.py";
  const std::vector<std::string> cmd = { TRANSLUCENCY_PYTHON, script, csvPath, plotPath };
  std::string spawnError;
  if (RunProgram(cmd, FilteredEnvironment({}), "", spawnError) != 0)
    std::cerr << "translucency: warning: plotting failed (needs python3-matplotlib"
              << (spawnError.empty() ? "" : "; " + spawnError) << "); the data is in "
              << csvPath << ", plot it with: " << CommandText(cmd) << "\n";
  else
    std::cout << "wrote " << plotPath << " (data " << csvPath << ")\n";
}

} // namespace

int BenchLinearSolvers(const LinearSolverBenchOptions& options)
{
  const std::string& meshPath = options.MeshPath;
  const std::string& jsonPath = options.JsonPath;
  const std::vector<double>& sizes = options.Tets;
  std::vector<std::string> names = options.Names;
  const int runs = options.Runs;
  const std::vector<std::string> available = translucency::GetLinearSolverNames();
  if (names.empty())
    names = available;
  for (std::string& n : names)
    n = translucency::CreateLinearSolver(n)->GetName(); // validates, canonical spelling
  const std::string defaultSolver = available.front();
  // The cut -> new fluence figure uses the solver with the cheapest set-up +
  // cold solve (multigrid-agg, Documentation/Multiresolution.md).
  const std::string cutSolver =
    std::find(available.begin(), available.end(), "multigrid-agg") != available.end()
    ? std::string("multigrid-agg")
    : defaultSolver;

  std::string error;
  vtkSmartPointer<vtkPolyData> surface;
  vtkSmartPointer<vtkUnstructuredGrid> grid;
  if (!ReadMesh(meshPath, surface, grid, error))
    throw translucency::Error(error);
  if (!surface)
    throw translucency::Error("bench needs a surface mesh (.ply, .stl, .obj, .vtp)");

  const double bandwidth = TriadBandwidth(runs);
  std::cout << "threads: " << omp_get_max_threads() << ", runs per figure: " << runs
            << " (medians); STREAM-triad bandwidth " << std::fixed << std::setprecision(2)
            << bandwidth << " GB/s; load average " << LoadAverage()
            << " (times are inflated when it exceeds the cores)\n" << std::defaultfloat;
  json results = json::array();
  std::vector<std::string> csv = { "tets,solver,tolerance,solve_ms,error,spmv_equivalents" };
  for (double target : sizes)
  {
    Problem p;
    translucency::DiscreteDivergence disc;
    std::vector<double> q0;
    const ProblemFigures f =
      BuildBenchProblem(surface, grid, target, runs, bandwidth, p, disc, q0);
    std::string hypreRanksError;
    json curveJson = json::array();
    Solution defaultCold;
    const std::vector<SolverRow> rows = BenchSolverRows(names, p, runs, options.HypreRanks,
      cutSolver, csv, curveJson, defaultCold, hypreRanksError);
    PrintRows(rows, f.TopologyMs);
    std::cout << std::flush;
    json entry = { { "target_tets", target }, { "tets", p.Mesh.GetNumberOfTets() },
      { "unknowns", f.Unknowns }, { "nonzeros", f.NonZeros },
      { "tetgen_ms", f.TetgenMs }, { "topology_ms", f.TopologyMs },
      { "assembly_3ch_ms", f.AssemblyMs }, { "assembly_3ch_cold_ms", f.AssemblyColdMs },
      { "spmv_1ch_ms", f.SpmvMs },
      { "spmv_bytes", f.SpmvBytes }, { "spmv_bandwidth_bound_ms", f.BoundMs },
      { "stream_triad_gbs", bandwidth }, { "reference_residual", f.ReferenceResidual },
      { "target_error", TargetError }, { "default_solver", defaultSolver },
      { "cut_solver", cutSolver }, { "load_average_1min", LoadAverage() },
      { "curve", curveJson } };
    for (const SolverRow& r : rows)
      entry["solvers"].push_back(RowJson(r, f.TopologyMs));
    if (!hypreRanksError.empty())
      entry["hypre_ranks_error"] = hypreRanksError;
    if (defaultCold[0].size() == 0)
    {
      // The cut solver was not in the list: solve once for the warm starts.
      auto solver = translucency::CreateLinearSolver(cutSolver);
      solver->SetRelTol(1e-3);
      solver->Setup(p.System, &p.Mesh, true);
      Stats stats;
      solver->Solve(p.System, defaultCold, false, stats);
    }
    entry["paint"] = BenchPaint(cutSolver, p, defaultCold, runs);
    if (cutSolver == "multigrid-agg")
      entry["drag"] = BenchDrag(cutSolver, p, runs);
    if (options.DoCut)
      entry["cut"] = BenchCut(cutSolver, p, defaultCold, runs);
    entry["targets"] = PrintTargets(rows, entry, cutSolver, f.SpmvMs);
    entry["memory"] = PrintMemory(p, disc, q0, rows, cutSolver);
    results.push_back(entry);
  }
  if (!jsonPath.empty())
  {
    EnsureParentDirectory(jsonPath);
    if (!WriteText(jsonPath, results.dump(2) + "\n", error))
      throw translucency::Error(error);
  }
  if (!options.PlotPath.empty())
    WriteLinearSolverPlot(options.PlotPath, csv);
  return 0;
}

} // namespace translucency_app
