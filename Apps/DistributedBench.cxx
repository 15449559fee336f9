// translucency-distributed-bench: strong scaling of the distributed vertex
// solve (Solvers/Parallel/DistributedVertexSolver) on a box of Kuhn tets,
// cut into x slabs, one per rank. Documentation/Scaling.md has the figures.
//
//   mpiexec -n 2 translucency-distributed-bench [--tets N] [--solver divergence|fem]
//       [--coordinates] [--no-single] [--serial] [--strong T] [--agg L] [--pmax P]
//       [--interp I] [--coarsen C] [--tol TOL] [--threads T] [--rounds R]
//       [--own-hierarchies] [--relax R] [--keep-transpose] [--linear NAME]
//       [--change-tol T] [--hypre-pcg] [--fused]
//
// --change-tol T: the change rule (T = 3e-3 with --tol 1e-2 is Solve
// Diffusion's interactive default; Documentation/Solvers.md, "The interactive
// stopping rule"); --hypre-pcg: each channel by hypre's own PCG, the path
// before the three-channel PCG (DistributedVertexSolver::SetThreeChannelPCG);
// --fused: its channels' reductions fused (SetFusedReductions).
// --linear: the distributed linear solver by registry name or composition
// (default: the distributed solver's, "cg/boomeramg"; "cg/aggregation" is
// additive Schwarz with one aggregation cycle per rank's block);
// --linear-option NAME=VALUE (repeatable): one of its options, e.g.
// agg-cycle-index=1 (SchwarzAggregation.h), besides the BoomerAMG ones.
//
// In one run, --rounds times (default 2): first every rank of MPI_COMM_WORLD
// solves its slab (cold solve: numbering, assembly, AMG set-up, PCG; then a
// relight: new right-hand side, hierarchy kept, warm start; then three paint
// strokes, each changing mu_a x5 and mu_s' x2 in a half ball under the top
// face (~1 % of the tets): the first with a full hierarchy set-up, the
// second with the values-only set-up (the first after a set-up: the
// hypre matrices' entry places are found then), the third also values-only
// and across the ranks' slab boundary (x = 0.5 size: a paint after a paint;
// the changed rows only, DistributedVertexSolver::SetChangedRowsUpdate),
// all warm started; a new hierarchy is one
// BoomerAMG coarsening for the three channels, the other two with their own
// Galerkin levels on it (Solve Diffusion's default), unless --own-hierarchies;
// the relight must set up nothing: its numbering and hierarchy counts are
// checked), then rank 0
// alone (MPI_COMM_SELF; the others sleep) solves the whole box the same way,
// and the two fluences are compared at every point. --serial also compares
// with the serial core path (the solver's default linear solver: multigrid-agg
// from 20,000 unknowns, cg-jacobi below)
// on the whole box: what Solve Diffusion computes with one process.
// Times are the slowest rank's; memory is each rank's resident-set growth
// while its solver and piece are alive (after malloc_trim: live memory), and
// each process's peak resident set; the CPU time of each rank's Solve call
// (with OMPI_MCA_mpi_yield_when_idle=1 a waiting rank gives its core away, so
// this approximates the work a rank does, whatever the machine's load).

#include "DiffusionSolverFactory.h"
#include "Detectors.h"
#include "DistributedVertexSolver.h"
#include "Error.h"
#include "HypreSolver.h" // BoomerAMGOptions, EnsureHypreInitialized

#include <malloc.h>
#include <omp.h>
#include <mpi.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <iostream>
#include <string>
#include <vector>

#include <sys/resource.h>
#include <unistd.h>

namespace
{

/// A size of this process (bytes) from /proc/self/status: "VmRSS:" (resident
/// now) or "VmHWM:" (the peak).
double StatusBytes(const char* field = "VmRSS:")
{
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
  {
    if (line.rfind(field, 0) == 0)
      return std::atof(line.c_str() + std::strlen(field)) * 1024.0;
  }
  return 0.0;
}
double ResidentBytes()
{
  return StatusBytes();
}

/// CPU time of this process (ms, user + system).
double CpuMilliseconds()
{
  rusage usage;
  getrusage(RUSAGE_SELF, &usage);
  return 1000.0 * (usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
    (usage.ru_utime.tv_usec + usage.ru_stime.tv_usec) / 1000.0;
}

struct Piece
{
  std::vector<double> Points;
  std::vector<translucency::PointKey> Keys;
  std::vector<int> Tets;
  std::vector<long long> Ids; ///< global point id per local point
  translucency::OpticalProperties Material;
};

/// Slab [i0, i1) of cubes along x of an n^3 box of side `size` mm, 6 Kuhn tets per cube.
Piece MakeSlab(int n, int i0, int i1, double size, bool coordinateKeys)
{
  Piece p;
  const int m = n + 1;
  const double h = size / n;
  std::vector<int> local(static_cast<size_t>(i1 - i0 + 1) * m * m, -1);
  auto id = [&](int i, int j, int k) { return (static_cast<long long>(i) * m + j) * m + k; };
  auto point = [&](int i, int j, int k) {
    int& l = local[(static_cast<size_t>(i - i0) * m + j) * m + k];
    if (l < 0)
    {
      l = static_cast<int>(p.Ids.size());
      p.Ids.push_back(id(i, j, k));
      const double x[3] = { i * h, j * h, k * h };
      p.Points.insert(p.Points.end(), x, x + 3);
      p.Keys.push_back(coordinateKeys ? translucency::PointKeyFromCoordinates(x)
                                      : translucency::PointKeyFromId(id(i, j, k)));
    }
    return l;
  };
  static const int perms[6][3] = { { 0, 1, 2 }, { 0, 2, 1 }, { 1, 0, 2 }, { 1, 2, 0 },
    { 2, 0, 1 }, { 2, 1, 0 } };
  for (int i = i0; i < i1; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k)
      {
        const double cx = (i + 0.5) * h, cy = (j + 0.5) * h, cz = (k + 0.5) * h;
        for (const auto& perm : perms)
        {
          int v[3] = { i, j, k };
          p.Tets.push_back(point(v[0], v[1], v[2]));
          for (int a = 0; a < 3; ++a)
          {
            ++v[perm[a]];
            p.Tets.push_back(point(v[0], v[1], v[2]));
          }
          // A heterogeneous skin-like material: an inclusion and a layer.
          const bool inclusion = (cx - 0.6 * size) * (cx - 0.6 * size) +
              (cy - 0.5 * size) * (cy - 0.5 * size) + (cz - 0.5 * size) * (cz - 0.5 * size) <
            0.04 * size * size;
          const bool layer = cz > 0.8 * size;
          const double mu[3] = { 0.002, 0.005, 0.01 }, sig[3] = { 1.0, 1.5, 2.0 };
          for (int c = 0; c < 3; ++c)
          {
            p.Material.AbsorptionCoefficient.push_back(mu[c] * (inclusion ? 10.0 : 1.0));
            p.Material.ReducedScatteringCoefficient.push_back(sig[c] * (layer ? 0.5 : 1.0));
          }
          p.Material.RefractiveIndex.push_back(layer ? 1.4 : 1.3);
        }
      }
  return p;
}

/// Paint stroke k (1, 2 or 3): mu_a x5 and mu_s' x2 in the tets whose
/// centroid lies within 0.17 size of a point on the top face (a half ball,
/// ~1 % of the box), at x = 0.3 size (k = 1), 0.7 size (k = 2) or 0.5 size
/// (k = 3: across the boundary of 2 ranks' slabs).
void Paint(Piece& p, double size, int k)
{
  const double centre[3] = { (k == 1 ? 0.3 : k == 2 ? 0.7 : 0.5) * size, 0.5 * size, size };
  const double radius = 0.17 * size;
  for (size_t t = 0; t < p.Tets.size() / 4; ++t)
  {
    double x[3] = { 0.0, 0.0, 0.0 };
    for (int a = 0; a < 4; ++a)
      for (int d = 0; d < 3; ++d)
        x[d] += 0.25 * p.Points[3 * static_cast<size_t>(p.Tets[4 * t + a]) + d];
    const double r2 = (x[0] - centre[0]) * (x[0] - centre[0]) +
      (x[1] - centre[1]) * (x[1] - centre[1]) + (x[2] - centre[2]) * (x[2] - centre[2]);
    if (r2 >= radius * radius)
      continue;
    for (int c = 0; c < 3; ++c)
    {
      p.Material.AbsorptionCoefficient[3 * t + c] *= 5.0;
      p.Material.ReducedScatteringCoefficient[3 * t + c] *= 2.0;
    }
  }
}

std::vector<double> Irradiance(const Piece& p, double size, bool relight)
{
  std::vector<double> q(p.Points.size());
  for (size_t i = 0; i < p.Points.size() / 3; ++i)
  {
    const double* x = p.Points.data() + 3 * i;
    const double s = relight ? 0.5 + 0.5 * x[0] / size : 0.5 + 0.5 * x[2] / size;
    const double w[3] = { 1.0, relight ? 0.5 : 1.0, relight ? 0.2 : 1.0 };
    for (int c = 0; c < 3; ++c)
      q[3 * i + c] = s * w[c];
  }
  return q;
}

double Max(double v, MPI_Comm comm)
{
  double m = 0.0;
  MPI_Allreduce(&v, &m, 1, MPI_DOUBLE, MPI_MAX, comm);
  return m;
}

struct Result
{
  std::vector<long long> Ids;
  std::vector<double> Fluence;
  translucency::PowerBalance Balance; ///< of the last solve, over every rank
};

/// Times (ms) of every round, per "<label> <phase>" and metric, on rank 0:
/// wall (slowest rank) and CPU (the busiest rank's; the work, whatever the
/// machine's load). The serial path's CPU and wall times per round.
std::map<std::string, std::vector<std::array<double, 5>>> Rounds, RoundsCpu;
std::vector<double> SerialCpu, SerialWall;
/// --linear: the distributed linear solver ("" = the distributed solver's default).
std::string LinearSolverName;
/// --linear-option NAME=VALUE: added to the linear solver's options.
std::vector<std::pair<std::string, double>> LinearOptions;
/// --change-tol T: the change rule (DiffusionSolver::SetChangeTol; Solve
/// Diffusion's interactive default is 3e-3 with --tol 1e-2).
double ChangeTol = 0.0;
/// --hypre-pcg: each channel by hypre's PCG (SetThreeChannelPCG(false)).
bool HyprePCG = false;
/// --fused: the three channels' reductions fused (SetFusedReductions).
bool Fused = false;

double Median(std::vector<double> v)
{
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

/// Cold solve + relight on `comm`; prints one line per phase (rank 0 of comm).
Result Run(const char* label, MPI_Comm comm, int n, double size, const std::string& solverName,
  bool coordinates, const translucency::BoomerAMGOptions& options, double tol, int threads,
  bool shared)
{
  int rank = 0, ranks = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &ranks);
  malloc_trim(0);
  const double baseline = ResidentBytes();
  const int i0 = static_cast<int>(static_cast<long long>(n) * rank / ranks);
  const int i1 = static_cast<int>(static_cast<long long>(n) * (rank + 1) / ranks);
  Piece piece = MakeSlab(n, i0, i1, size, coordinates);
  Result result;
  {
    translucency::DistributedVertexSolver solver(comm, solverName);
    translucency::SolverOptions linearOptions = options.ToOptions();
    for (const auto& option : LinearOptions)
      linearOptions.Set(option.first, option.second);
    solver.SetLinearSolverOptions(linearOptions);
    if (!LinearSolverName.empty())
      solver.SetLinearSolver(LinearSolverName);
    solver.SetRelTol(tol);
    solver.SetChangeTol(ChangeTol);
    solver.SetThreeChannelPCG(!HyprePCG);
    solver.SetFusedReductions(Fused);
    solver.SetMaxIter(1000);
    solver.SetNumberOfThreads(threads);
    solver.SetSharedHierarchy(shared);
    static const char* phases[5] = { "cold", "relight", "paint (full set-up)",
      "paint (values-only set-up)", "paint (values-only, again, across the ranks)" };
    for (int phase = 0; phase < 5; ++phase)
    {
      const std::vector<double> q = Irradiance(piece, size, phase >= 1);
      if (phase >= 2)
      {
        Paint(piece, size, phase - 1);
        solver.SetValuesOnlySetup(phase >= 3);
      }
      translucency::SolverReport report;
      const long long numberings = solver.GetNumberOfNumberings(),
                      hierarchies = solver.GetNumberOfHierarchySetups();
      MPI_Barrier(comm);
      const double start = MPI_Wtime();
      const double cpuStart = CpuMilliseconds();
      solver.Solve(piece.Points, piece.Keys, piece.Tets, piece.Material, q, result.Fluence, report);
      static const char* expected[5] = { "full", "unchanged", "full", "values-only", "values-only" };
      if (report.Assembly != expected[phase])
        throw translucency::Error(std::string("the ") + phases[phase] + " solve took the '" +
          report.Assembly + "' path, not '" + expected[phase] + "'");
      // Set-ups by counters: a relight and a values-only paint renumber and
      // set up nothing; a cold solve numbers once and sets up one shared
      // hierarchy (three without sharing), unless a channel was re-solved.
      const long long newNumberings = solver.GetNumberOfNumberings() - numberings,
                      newHierarchies = solver.GetNumberOfHierarchySetups() - hierarchies;
      const long long wantNumberings = phase == 0 ? 1 : 0;
      const long long wantHierarchies = phase == 1 || phase >= 3 ? 0 : (shared ? 1 : 3);
      if (newNumberings != wantNumberings ||
        (!report.Resolved && newHierarchies != wantHierarchies))
        throw translucency::Error(std::string("the ") + phases[phase] + " solve built " +
          std::to_string(newNumberings) + " numberings and " + std::to_string(newHierarchies) +
          " hierarchies, not " + std::to_string(wantNumberings) + " and " +
          std::to_string(wantHierarchies));
      const double cpu = CpuMilliseconds() - cpuStart;
      std::vector<double> cpus(static_cast<size_t>(ranks));
      MPI_Gather(&cpu, 1, MPI_DOUBLE, cpus.data(), 1, MPI_DOUBLE, 0, comm);
      const double total = Max(1000.0 * (MPI_Wtime() - start), comm);
      const auto& t = solver.GetTimings();
      const double numbering = Max(t.Numbering, comm), assembly = Max(t.Assembly, comm),
                   amg = Max(t.AMGSetup, comm), solve = Max(t.Solve, comm);
      const double numberingCpu = Max(t.NumberingCpu, comm), assemblyCpu = Max(t.AssemblyCpu, comm),
                   amgCpu = Max(t.AMGSetupCpu, comm), solveCpu = Max(t.SolveCpu, comm);
      malloc_trim(0); // free heap pages back to the system: count what is live
      const double memory = ResidentBytes() - baseline;
      std::vector<double> memories(static_cast<size_t>(ranks)), peaks(memories);
      const double peak = StatusBytes("VmHWM:");
      MPI_Gather(&memory, 1, MPI_DOUBLE, memories.data(), 1, MPI_DOUBLE, 0, comm);
      MPI_Gather(&peak, 1, MPI_DOUBLE, peaks.data(), 1, MPI_DOUBLE, 0, comm);
      long long tets = static_cast<long long>(piece.Tets.size() / 4), allTets = 0;
      MPI_Allreduce(&tets, &allTets, 1, MPI_LONG_LONG, MPI_SUM, comm);
      if (rank == 0)
      {
        Rounds[std::string(label) + " " + phases[phase]].push_back(
          { numbering, assembly, amg, solve, total });
        const double cpuMax = *std::max_element(cpus.begin(), cpus.end());
        RoundsCpu[std::string(label) + " " + phases[phase]].push_back(
          { numberingCpu, assemblyCpu, amgCpu, solveCpu, cpuMax });
        std::printf("%s ranks %d %s tets %lld unknowns %lld: numbering %.0f ms, assembly %.0f ms, "
                    "AMG set-up %.0f ms, solve %.0f ms (total %.0f ms); iterations %d %d %d, "
                    "residual %.1e; levels %d, operator complexity %.2f; assembly '%s', set-up "
                    "'%s'%s; memory MB per rank",
          label, ranks, phases[phase], allTets, solver.GetNumberOfRows(),
          numbering, assembly, amg, solve, total, report.Iterations[0], report.Iterations[1],
          report.Iterations[2], std::max({ report.Residual[0], report.Residual[1], report.Residual[2] }),
          solver.GetNumberOfLevels(0), solver.GetOperatorComplexity(0), report.Assembly.c_str(),
          report.LinearSetup.c_str(), report.Resolved ? " (re-solved)" : "");
        for (double mb : memories)
          std::printf(" %.0f", mb / 1e6);
        std::printf(" (%.0f MB per million tets per rank at %d ranks); process peak MB",
          *std::max_element(memories.begin(), memories.end()) / 1e6 / (allTets / 1e6 / ranks), ranks);
        for (double mb : peaks)
          std::printf(" %.0f", mb / 1e6);
        std::printf("; CPU ms per rank");
        for (double ms : cpus)
          std::printf(" %.0f", ms);
        std::printf("\n");
        std::fflush(stdout);
      }
    }
    result.Balance = solver.GetPowerBalance();
  }
  result.Ids = piece.Ids;
  return result;
}

/// Compares the gathered fluence of every rank (ids, 3 values per id) with
/// one rank's run of the same box on rank 0.
void CompareWithSingleRank(const std::vector<long long>& ids, const std::vector<double>& fluence,
  int size, int n, double sizeMm, const std::string& solver, bool coordinates,
  const translucency::BoomerAMGOptions& options, double tol, int threads, bool shared)
{
  const Result one =
    Run("single", MPI_COMM_SELF, n, sizeMm, solver, coordinates, options, tol, threads, shared);
  std::vector<size_t> where(one.Ids.size());
  for (size_t k = 0; k < one.Ids.size(); ++k)
    where[static_cast<size_t>(one.Ids[k])] = k;
  double worst = 0.0;
  for (size_t k = 0; k < ids.size(); ++k)
    for (int c = 0; c < 3; ++c)
    {
      const double a = fluence[3 * k + c],
                   b = one.Fluence[3 * where[static_cast<size_t>(ids[k])] + c];
      worst = std::max(worst, std::abs(a - b) / std::abs(b));
    }
  std::printf("max relative difference, %d ranks vs 1 (relit, three times painted fluence, every "
              "point of every rank): %.2e\n", size, worst);
  std::fflush(stdout);
}

/// The serial core path (Solve Diffusion with one process) on the whole
/// box: the relit fluence after the three paint strokes, to RelTol `tol` (the
/// last distributed solve used the values-only set-up), against the
/// gathered distributed fluence, and the power balances.
void CompareWithSerial(const std::vector<long long>& ids, const std::vector<double>& fluence,
  const Result& all, int size, int n, double sizeMm, const std::string& solver, bool coordinates,
  double tol)
{
  Piece whole = MakeSlab(n, 0, n, sizeMm, coordinates);
  Paint(whole, sizeMm, 1);
  Paint(whole, sizeMm, 2);
  Paint(whole, sizeMm, 3);
  translucency::TetMesh mesh;
  mesh.SetGeometry(whole.Points, whole.Tets);
  const std::vector<double> q = Irradiance(whole, sizeMm, true);
  auto reference = translucency::CreateDiffusionSolver(solver);
  reference->SetRelTol(tol);
  reference->SetMaxIter(100000);
  translucency::DiffusionProblem problem;
  problem.Mesh = &mesh;
  problem.Material = &whole.Material;
  problem.Irradiance = &q;
  std::vector<double> expected;
  translucency::SolverReport report;
  const double start = MPI_Wtime();
  const double cpuStart = CpuMilliseconds();
  reference->Solve(problem, expected, report);
  SerialCpu.push_back(CpuMilliseconds() - cpuStart);
  SerialWall.push_back(1000.0 * (MPI_Wtime() - start));
  std::vector<size_t> where(whole.Ids.size());
  for (size_t k = 0; k < whole.Ids.size(); ++k)
    where[static_cast<size_t>(whole.Ids[k])] = k;
  double worst = 0.0;
  for (size_t k = 0; k < ids.size(); ++k)
    for (int c = 0; c < 3; ++c)
    {
      const double b = expected[3 * where[static_cast<size_t>(ids[k])] + c];
      worst = std::max(worst, std::abs(fluence[3 * k + c] - b) / std::abs(b));
    }
  std::printf("serial %s (%s, %.0f ms: set-up %.0f ms, solve %.0f ms, iterations %d %d %d): max "
              "relative difference, %d ranks vs serial: %.2e\n",
    solver.c_str(), report.LinearSolver.c_str(), 1000.0 * (MPI_Wtime() - start),
    report.SetupMilliseconds, report.SolveMilliseconds, report.Iterations[0], report.Iterations[1],
    report.Iterations[2], size, worst);
  // The power balance summed over the ranks (physical faces only) vs
  // the serial ComputePowerBalance of the whole box on the serial
  // solution: equal up to the solver tolerance (both fluences are
  // within `tol` of the same system's solution).
  const translucency::PowerBalance serialBalance =
    translucency::ComputePowerBalance(mesh, whole.Material, expected, &q);
  double balanceWorst = 0.0;
  for (int c = 0; c < 3; ++c)
  {
    const double scale = serialBalance.BoundaryInjected[c];
    balanceWorst = std::max({ balanceWorst,
      std::abs(all.Balance.BoundaryInjected[c] - serialBalance.BoundaryInjected[c]) / scale,
      std::abs(all.Balance.Absorbed[c] - serialBalance.Absorbed[c]) / scale,
      std::abs(all.Balance.Escaped[c] - serialBalance.Escaped[c]) / scale });
  }
  double gap = 0.0;
  for (int c = 0; c < 3; ++c)
    gap = std::max(gap, std::abs(all.Balance.Absorbed[c] + all.Balance.Escaped[c] -
                          all.Balance.BoundaryInjected[c]) / all.Balance.BoundaryInjected[c]);
  std::printf("power balance, %d ranks vs serial (injected, absorbed, escaped; relative to "
              "the injected power), max difference: %.2e\n", size, balanceWorst);
  // fem's Robin terms use each face's own eta, as the balance does: it
  // closes to the solver tolerance. The divergence's use the
  // area-weighted eta of the vertex (paper's S_i), so with a varying
  // eta its gap is a discretisation difference, not an error.
  if (solver == "fem")
    std::printf("power balance, %d ranks: absorbed + escaped vs injected, max relative "
                "difference: %.2e\n", size, gap);
  else
    std::printf("power balance, %d ranks: absorbed + escaped - injected, relative gap "
                "%.2e (vertex-averaged boundary eta)\n", size, gap);
  std::fflush(stdout);
}

/// One line per configuration of `rounds` (CPU or wall time): the minimum
/// and median of each phase over the rounds.
void PrintRounds(const char* what,
  const std::map<std::string, std::vector<std::array<double, 5>>>& rounds)
{
  static const char* names[5] = { "numbering", "assembly", "AMG set-up", "solve", "total" };
  for (const auto& entry : rounds)
  {
    std::printf("summary %s%s over %zu rounds (min / median ms):", what, entry.first.c_str(),
      entry.second.size());
    for (int m = 0; m < 5; ++m)
    {
      std::vector<double> v;
      for (const auto& r : entry.second)
        v.push_back(r[m]);
      std::printf(" %s %.0f / %.0f%s", names[m], *std::min_element(v.begin(), v.end()),
        Median(v), m < 4 ? "," : "\n");
    }
  }
}

/// Rank 0's summary after the rounds: CPU per phase, the serial path, wall per phase.
void PrintSummary()
{
  PrintRounds("CPU ", RoundsCpu);
  if (!SerialCpu.empty())
    std::printf("summary serial path (cold: assembly, set-up, solve) over %zu rounds (min / "
                "median ms): CPU %.0f / %.0f, wall %.0f / %.0f\n",
      SerialCpu.size(), *std::min_element(SerialCpu.begin(), SerialCpu.end()),
      Median(SerialCpu), *std::min_element(SerialWall.begin(), SerialWall.end()),
      Median(SerialWall));
  PrintRounds("", Rounds);
}

} // namespace

int main(int argc, char* argv[])
{
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  long long targetTets = 1000000;
  std::string solver = "divergence";
  bool coordinates = false, single = true, serial = false, shared = true;
  double tol = 1e-8;
  int threads = 1;
  int rounds = 2;
  translucency::BoomerAMGOptions options = translucency::BoomerAMGOptions::Tuned();
  for (int a = 1; a < argc; ++a)
  {
    const std::string arg = argv[a];
    auto next = [&]() { return a + 1 < argc ? argv[++a] : ""; };
    if (arg == "--tets")
      targetTets = std::atoll(next());
    else if (arg == "--solver")
      solver = next();
    else if (arg == "--coordinates")
      coordinates = true;
    else if (arg == "--no-single")
      single = false;
    else if (arg == "--serial")
      serial = true;
    else if (arg == "--strong")
      options.StrongThreshold = std::atof(next());
    else if (arg == "--agg")
      options.AggNumLevels = std::atoi(next());
    else if (arg == "--pmax")
      options.PMaxElmts = std::atoi(next());
    else if (arg == "--interp")
      options.InterpType = std::atoi(next());
    else if (arg == "--coarsen")
      options.CoarsenType = std::atoi(next());
    else if (arg == "--tol")
      tol = std::atof(next());
    else if (arg == "--rounds")
      rounds = std::max(1, std::atoi(next()));
    else if (arg == "--threads")
      threads = std::atoi(next());
    else if (arg == "--own-hierarchies")
      shared = false;
    else if (arg == "--relax")
      options.RelaxType = std::atoi(next());
    else if (arg == "--keep-transpose")
      options.KeepTranspose = 1;
    else if (arg == "--linear")
      LinearSolverName = next();
    else if (arg == "--change-tol")
      ChangeTol = std::atof(next());
    else if (arg == "--hypre-pcg")
      HyprePCG = true;
    else if (arg == "--fused")
      Fused = true;
    else if (arg == "--linear-option" && a + 1 < argc &&
      std::strchr(argv[a + 1], '=') != nullptr)
    {
      const std::string option = next();
      const std::size_t eq = option.find('=');
      LinearOptions.emplace_back(option.substr(0, eq), std::atof(option.c_str() + eq + 1));
    }
    else
    {
      if (rank == 0)
        std::cerr << "usage: mpiexec -n RANKS translucency-distributed-bench [--tets N] [--solver "
                     "divergence|fem] [--coordinates] [--no-single] [--serial] [--strong T] [--agg L] "
                     "[--pmax P] [--interp I] [--coarsen C] [--tol TOL] [--threads T] [--rounds R] "
                     "[--own-hierarchies] [--relax R] [--keep-transpose] [--linear NAME] "
                     "[--linear-option NAME=VALUE] [--change-tol T] [--hypre-pcg] [--fused]\n";
      MPI_Finalize();
      return 2;
    }
  }
  // Every OpenMP region (the local topology too) on `threads` threads, so that
  // 1 rank and 2 ranks use the same cores per rank.
  omp_set_num_threads(std::max(1, threads));
  const int n = std::max(2, static_cast<int>(std::lround(std::cbrt(targetTets / 6.0))));
  const double sizeMm = 50.0;
  int code = 0;
  try
  {
    translucency::EnsureHypreInitialized();
    // Rounds alternate the two configurations, so that a change of the
    // machine's load shows in both.
    for (int round = 0; round < rounds; ++round)
    {
      if (rank == 0)
        std::printf("round %d\n", round + 1);
      const Result all =
        Run("distributed", MPI_COMM_WORLD, n, sizeMm, solver, coordinates, options, tol, threads,
          shared);
      // Rank 0 gathers the distributed fluence by global id.
      const int count = static_cast<int>(all.Ids.size());
      std::vector<int> counts(static_cast<size_t>(size)), offsets(static_cast<size_t>(size) + 1, 0);
      MPI_Gather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
      for (int r = 0; r < size; ++r)
        offsets[r + 1] = offsets[r] + counts[r];
      std::vector<long long> ids(static_cast<size_t>(offsets[size]));
      std::vector<double> fluence(3 * ids.size());
      MPI_Gatherv(all.Ids.data(), count, MPI_LONG_LONG, ids.data(), counts.data(), offsets.data(),
        MPI_LONG_LONG, 0, MPI_COMM_WORLD);
      for (int r = 0; r < size; ++r)
      {
        counts[r] *= 3;
        offsets[r] *= 3;
      }
      MPI_Gatherv(all.Fluence.data(), 3 * count, MPI_DOUBLE, fluence.data(), counts.data(),
        offsets.data(), MPI_DOUBLE, 0, MPI_COMM_WORLD);
      if (rank == 0 && single && size > 1)
      {
        CompareWithSingleRank(
          ids, fluence, size, n, sizeMm, solver, coordinates, options, tol, threads, shared);
      }
      if (rank == 0 && serial)
      {
        CompareWithSerial(ids, fluence, all, size, n, sizeMm, solver, coordinates, tol);
      }
      // The other ranks wait without spinning (a busy MPI wait would take a
      // core from rank 0's single-rank run).
      MPI_Request request;
      MPI_Ibarrier(MPI_COMM_WORLD, &request);
      int done = 0;
      while (!done)
      {
        MPI_Test(&request, &done, MPI_STATUS_IGNORE);
        if (!done)
          usleep(1000);
      }
    }
    if (rank == 0)
    {
      PrintSummary();
    }
  }
  catch (const std::exception& e)
  {
    std::cerr << "translucency-distributed-bench: error: " << e.what() << "\n";
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
  MPI_Finalize();
  return code;
}
