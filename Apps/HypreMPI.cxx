// translucency-hypre-mpi IN OUT: hypre BoomerAMG-PCG (HypreBoomerAMGPCG, the
// building block of the in-process "hypre-amg" solver) on all ranks of
// MPI_COMM_WORLD, rows split into contiguous blocks. Run by
// `translucency bench --linear-solvers` through mpiexec for its multi-rank
// figure; see HypreMPI.h for the file formats.

#include "HypreMPI.h"

#include "Error.h"
#include "HypreSolver.h"

#include <mpi.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace
{

template <typename T>
void Read(std::ifstream& in, T* data, std::size_t count, const std::string& path)
{
  in.read(reinterpret_cast<char*>(data), static_cast<std::streamsize>(count * sizeof(T)));
  if (!in)
    throw translucency::Error("translucency-hypre-mpi: '" + path + "' is truncated");
}

template <typename T>
void Write(std::ofstream& out, const T* data, std::size_t count)
{
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(count * sizeof(T)));
}

double Median(std::vector<double> v)
{
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

/// Seconds since `start` on the slowest rank (everyone waits for everyone).
double SlowestSince(double start)
{
  const double mine = MPI_Wtime() - start;
  double slowest = 0.0;
  MPI_Allreduce(&mine, &slowest, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  return slowest * 1000.0;
}

int Run(const std::string& inPath, const std::string& outPath)
{
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);

  std::ifstream in(inPath, std::ios::binary);
  if (!in)
    throw translucency::Error("translucency-hypre-mpi: cannot open '" + inPath + "'");
  char magic[8];
  Read(in, magic, 8, inPath);
  if (std::memcmp(magic, translucency_app::HypreInputMagic, 8) != 0)
    throw translucency::Error("translucency-hypre-mpi: '" + inPath + "' is not a bench problem file");
  std::int32_t n = 0, runs = 0, maxIter = 0;
  std::int64_t nnz = 0;
  double coldTol = 0.0, warmTol = 0.0;
  Read(in, &n, 1, inPath);
  Read(in, &nnz, 1, inPath);
  Read(in, &runs, 1, inPath);
  Read(in, &maxIter, 1, inPath);
  Read(in, &coldTol, 1, inPath);
  Read(in, &warmTol, 1, inPath);
  if (n <= 0 || nnz <= 0 || runs <= 0 || maxIter <= 0 || !(coldTol > 0) || !(warmTol > 0))
    throw translucency::Error("translucency-hypre-mpi: bad header in '" + inPath + "'");
  std::vector<std::int32_t> offsets(n + 1), columns(nnz);
  std::array<std::vector<double>, 3> values, cold, warm;
  Read(in, offsets.data(), offsets.size(), inPath);
  Read(in, columns.data(), columns.size(), inPath);
  for (auto& v : values)
  {
    v.resize(nnz);
    Read(in, v.data(), v.size(), inPath);
  }
  for (auto* rhs : { &cold, &warm })
    for (auto& v : *rhs)
    {
      v.resize(n);
      Read(in, v.data(), v.size(), inPath);
    }
  if (offsets[0] != 0 || offsets[n] != nnz)
    throw translucency::Error("translucency-hypre-mpi: inconsistent row offsets in '" + inPath + "'");

  // Contiguous row blocks; local offsets from 0.
  const int begin = static_cast<int>(static_cast<std::int64_t>(n) * rank / size);
  const int end = static_cast<int>(static_cast<std::int64_t>(n) * (rank + 1) / size);
  const int rows = end - begin;
  std::vector<int> localOffsets(rows + 1);
  for (int i = 0; i <= rows; ++i)
    localOffsets[i] = offsets[begin + i] - offsets[begin];
  const std::size_t first = static_cast<std::size_t>(offsets[begin]);

  std::array<std::unique_ptr<translucency::HypreBoomerAMGPCG>, 3> solvers;
  std::array<std::vector<double>, 3> xCold, xWarm;
  std::array<int, 3> coldIters{}, warmIters{};
  std::array<double, 3> coldRes{}, warmRes{}, work{};
  std::vector<double> setupMs, coldMs, warmMs;
  for (int r = 0; r < runs; ++r)
  {
    MPI_Barrier(MPI_COMM_WORLD);
    double start = MPI_Wtime();
    for (int c = 0; c < 3; ++c)
    {
      solvers[c] = std::make_unique<translucency::HypreBoomerAMGPCG>(MPI_COMM_WORLD);
      solvers[c]->Setup(begin, end, localOffsets.data(), columns.data() + first,
        values[c].data() + first);
    }
    setupMs.push_back(SlowestSince(start));
    MPI_Barrier(MPI_COMM_WORLD);
    start = MPI_Wtime();
    for (int c = 0; c < 3; ++c)
    {
      xCold[c].assign(rows, 0.0);
      coldIters[c] = solvers[c]->Solve(cold[c].data() + begin, xCold[c].data(), false, coldTol,
        maxIter, coldRes[c]);
    }
    coldMs.push_back(SlowestSince(start));
    for (int c = 0; c < 3; ++c)
      xWarm[c] = xCold[c];
    MPI_Barrier(MPI_COMM_WORLD);
    start = MPI_Wtime();
    for (int c = 0; c < 3; ++c)
    {
      warmIters[c] = solvers[c]->Solve(warm[c].data() + begin, xWarm[c].data(), true, warmTol,
        maxIter, warmRes[c]);
    }
    warmMs.push_back(SlowestSince(start));
    for (int c = 0; c < 3; ++c)
      work[c] = solvers[c]->GetSpMVEquivalentsPerIteration();
  }

  // Gather the solutions on rank 0.
  std::vector<int> counts(size), displs(size);
  for (int p = 0; p < size; ++p)
  {
    const int b = static_cast<int>(static_cast<std::int64_t>(n) * p / size);
    const int e = static_cast<int>(static_cast<std::int64_t>(n) * (p + 1) / size);
    counts[p] = e - b;
    displs[p] = b;
  }
  std::array<std::vector<double>, 3> gCold, gWarm;
  for (int c = 0; c < 3; ++c)
  {
    gCold[c].resize(rank == 0 ? n : 0);
    gWarm[c].resize(rank == 0 ? n : 0);
    MPI_Gatherv(xCold[c].data(), rows, MPI_DOUBLE, gCold[c].data(), counts.data(), displs.data(),
      MPI_DOUBLE, 0, MPI_COMM_WORLD);
    MPI_Gatherv(xWarm[c].data(), rows, MPI_DOUBLE, gWarm[c].data(), counts.data(), displs.data(),
      MPI_DOUBLE, 0, MPI_COMM_WORLD);
  }
  if (rank == 0)
  {
    const std::string tmp = outPath + ".tmp";
    {
      std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
      Write(out, translucency_app::HypreOutputMagic, 8);
      const std::int32_t header[2] = { n, size };
      Write(out, header, 2);
      const double times[3] = { Median(setupMs), Median(coldMs), Median(warmMs) };
      Write(out, times, 3);
      for (int c = 0; c < 3; ++c)
      {
        const std::int32_t iters[2] = { coldIters[c], warmIters[c] };
        Write(out, iters, 2);
        const double d[3] = { coldRes[c], warmRes[c], work[c] };
        Write(out, d, 3);
      }
      for (int c = 0; c < 3; ++c)
        Write(out, gCold[c].data(), n);
      for (int c = 0; c < 3; ++c)
        Write(out, gWarm[c].data(), n);
      if (!out)
        throw translucency::Error("translucency-hypre-mpi: cannot write '" + tmp + "'");
    }
    if (std::rename(tmp.c_str(), outPath.c_str()) != 0)
      throw translucency::Error("translucency-hypre-mpi: cannot rename '" + tmp + "' to '" + outPath + "'");
  }
  return 0;
}

} // namespace

int main(int argc, char* argv[])
{
  MPI_Init(&argc, &argv);
  int code = 0;
  if (argc != 3)
  {
    std::cerr << "usage: mpiexec -n RANKS translucency-hypre-mpi PROBLEM_IN RESULT_OUT\n"
                 "(run by translucency bench --linear-solvers; formats in Apps/HypreMPI.h)\n";
    code = 2;
  }
  else
  {
    try
    {
      translucency::EnsureHypreInitialized(); // HYPRE_Init (MPI is up already)
      code = Run(argv[1], argv[2]);
    }
    catch (const std::exception& e)
    {
      std::cerr << "translucency-hypre-mpi: error: " << e.what() << "\n";
      MPI_Abort(MPI_COMM_WORLD, 1);
    }
  }
  MPI_Finalize();
  return code;
}
