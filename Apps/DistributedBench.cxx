// translucency-distributed-bench: strong scaling of the distributed vertex
// solve (Solvers/Parallel/DistributedVertexSolver) on a box of Kuhn tets,
// cut into x slabs, one per rank. Documentation/Scaling.md has the figures.
//
//   mpiexec -n 2 translucency-distributed-bench [--tets N] [--solver divergence|fem]
//       [--coordinates] [--strong T] [--agg L] [--pmax P] [--interp I] [--tol TOL]
//
// In one run: first every rank of MPI_COMM_WORLD solves its slab (cold solve:
// numbering, assembly, AMG set-up, PCG; then a relight: new right-hand side,
// hierarchy kept, warm start), then rank 0 alone (MPI_COMM_SELF) solves the
// whole box the same way, and the two fluences are compared at every point.
// Times are the slowest rank's; memory is each rank's resident-set growth
// while its solver and piece are alive.

#include "DistributedVertexSolver.h"
#include "Error.h"

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

namespace
{

/// Resident set size of this process (bytes), from /proc/self/status.
double ResidentBytes()
{
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
  {
    if (line.rfind("VmRSS:", 0) == 0)
      return std::atof(line.c_str() + 6) * 1024.0;
  }
  return 0.0;
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
};

/// Cold solve + relight on `comm`; prints one line per phase (rank 0 of comm).
Result Run(const char* label, MPI_Comm comm, int n, double size, const std::string& solverName,
  bool coordinates, const translucency::BoomerAMGOptions& options, double tol, int threads)
{
  int rank = 0, ranks = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &ranks);
  const double baseline = ResidentBytes();
  const int i0 = static_cast<int>(static_cast<long long>(n) * rank / ranks);
  const int i1 = static_cast<int>(static_cast<long long>(n) * (rank + 1) / ranks);
  Piece piece = MakeSlab(n, i0, i1, size, coordinates);
  Result result;
  {
    translucency::DistributedVertexSolver solver(comm, solverName);
    solver.SetAMGOptions(options);
    solver.SetRelTol(tol);
    solver.SetMaxIter(1000);
    solver.SetNumberOfThreads(threads);
    for (int phase = 0; phase < 2; ++phase)
    {
      const std::vector<double> q = Irradiance(piece, size, phase == 1);
      translucency::SolverReport report;
      MPI_Barrier(comm);
      const double start = MPI_Wtime();
      solver.Solve(piece.Points, piece.Keys, piece.Tets, piece.Material, q, result.Fluence, report);
      const double total = Max(1000.0 * (MPI_Wtime() - start), comm);
      const auto& t = solver.GetTimings();
      const double numbering = Max(t.Numbering, comm), assembly = Max(t.Assembly, comm),
                   amg = Max(t.AMGSetup, comm), solve = Max(t.Solve, comm);
      const double memory = ResidentBytes() - baseline;
      std::vector<double> memories(static_cast<size_t>(ranks));
      MPI_Gather(&memory, 1, MPI_DOUBLE, memories.data(), 1, MPI_DOUBLE, 0, comm);
      long long tets = static_cast<long long>(piece.Tets.size() / 4), allTets = 0;
      MPI_Allreduce(&tets, &allTets, 1, MPI_LONG_LONG, MPI_SUM, comm);
      if (rank == 0)
      {
        std::printf("%s ranks %d %s tets %lld unknowns %lld: numbering %.0f ms, assembly %.0f ms, "
                    "AMG set-up %.0f ms, solve %.0f ms (total %.0f ms); iterations %d %d %d, "
                    "residual %.1e; levels %d, operator complexity %.2f; assembly '%s'; memory MB "
                    "per rank",
          label, ranks, phase == 0 ? "cold" : "relight", allTets, solver.GetNumberOfRows(),
          numbering, assembly, amg, solve, total, report.Iterations[0], report.Iterations[1],
          report.Iterations[2], std::max({ report.Residual[0], report.Residual[1], report.Residual[2] }),
          solver.GetNumberOfLevels(0), solver.GetOperatorComplexity(0), report.Assembly.c_str());
        for (double mb : memories)
          std::printf(" %.0f", mb / 1e6);
        std::printf(" (%.0f MB per million tets per rank at %d ranks)\n",
          *std::max_element(memories.begin(), memories.end()) / 1e6 / (allTets / 1e6 / ranks), ranks);
        std::fflush(stdout);
      }
    }
  }
  result.Ids = piece.Ids;
  return result;
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
  bool coordinates = false, single = true;
  double tol = 1e-8;
  int threads = 1;
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
    else if (arg == "--strong")
      options.StrongThreshold = std::atof(next());
    else if (arg == "--agg")
      options.AggNumLevels = std::atoi(next());
    else if (arg == "--pmax")
      options.PMaxElmts = std::atoi(next());
    else if (arg == "--interp")
      options.InterpType = std::atoi(next());
    else if (arg == "--tol")
      tol = std::atof(next());
    else if (arg == "--threads")
      threads = std::atoi(next());
    else
    {
      if (rank == 0)
        std::cerr << "usage: mpiexec -n RANKS translucency-distributed-bench [--tets N] [--solver "
                     "divergence|fem] [--coordinates] [--no-single] [--strong T] [--agg L] "
                     "[--pmax P] [--interp I] [--tol TOL] [--threads T]\n";
      MPI_Finalize();
      return 2;
    }
  }
  const int n = std::max(2, static_cast<int>(std::lround(std::cbrt(targetTets / 6.0))));
  const double sizeMm = 50.0;
  int code = 0;
  try
  {
    translucency::EnsureHypreInitialized();
    const Result all = Run("distributed", MPI_COMM_WORLD, n, sizeMm, solver, coordinates, options, tol, threads);
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
      const Result one = Run("single", MPI_COMM_SELF, n, sizeMm, solver, coordinates, options, tol, threads);
      std::vector<size_t> where(one.Ids.size());
      for (size_t k = 0; k < one.Ids.size(); ++k)
        where[static_cast<size_t>(one.Ids[k])] = k;
      double worst = 0.0;
      for (size_t k = 0; k < ids.size(); ++k)
        for (int c = 0; c < 3; ++c)
        {
          const double a = fluence[3 * k + c], b = one.Fluence[3 * where[static_cast<size_t>(ids[k])] + c];
          worst = std::max(worst, std::abs(a - b) / std::abs(b));
        }
      std::printf("max relative difference, %d ranks vs 1 (relit fluence, every point of every "
                  "rank): %.2e\n", size, worst);
    }
  }
  catch (const std::exception& e)
  {
    std::cerr << "translucency-distributed-bench: error: " << e.what() << "\n";
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  MPI_Finalize();
  return code;
}
