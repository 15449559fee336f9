/**
 * @file VertexAssembly.h
 * @brief The part of the vertex assemblies (DiscreteDivergence,
 * FiniteElement) they have in common: input checks, the system set-up on the
 * mesh's CSR pattern, the per-tet geometry cache and the deterministic
 * parallel scatter over tets.
 *
 * Private header of the Solvers library (not installed, not part of its API).
 */
#pragma once

#include "DiffusionSystem.h"
#include "Error.h"
#include "OpticalProperties.h"
#include "TetGeometry.h"
#include "TetMesh.h"

#include <omp.h>

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <vector>

namespace translucency
{

/// "R", "G", "B".
inline const char* ChannelName(int c)
{
  static const char* const names[NumberOfChannels] = { "R", "G", "B" };
  return names[c];
}

/// Throws if the irradiance has the wrong size or a value that is not finite
/// and >= 0, naming the first bad point and channel (serial).
inline void CheckIrradiance(const TetMesh& mesh, const std::vector<double>& irradiance)
{
  const size_t expected = 3 * static_cast<size_t>(mesh.GetNumberOfPoints());
  if (irradiance.size() != expected)
  {
    std::ostringstream os;
    os << "Irradiance has " << irradiance.size() << " values but the mesh has "
       << mesh.GetNumberOfPoints() << " points (" << expected << " values expected, 3 per point)";
    throw Error(os.str());
  }
  for (size_t k = 0; k < expected; ++k)
  {
    if (!(std::isfinite(irradiance[k]) && irradiance[k] >= 0.0))
    {
      std::ostringstream os;
      os << "Irradiance of point " << k / 3 << ", channel " << ChannelName(static_cast<int>(k % 3))
         << " is " << irradiance[k] << " W/mm^2: must be finite and >= 0";
      throw Error(os.str());
    }
  }
}

/// Throws, naming the array, if the material or the irradiance does not
/// have one value set per tet / point (the cheap size check every assembly
/// starts with; the values themselves are checked during the assembly).
inline void CheckAssemblySizes(
  const TetMesh& mesh, const OpticalProperties& material, const std::vector<double>& irradiance)
{
  const size_t tetCount = static_cast<size_t>(mesh.GetNumberOfTets());
  if (material.AbsorptionCoefficient.size() != 3 * tetCount ||
    material.ReducedScatteringCoefficient.size() != 3 * tetCount ||
    material.RefractiveIndex.size() != tetCount)
  {
    material.Validate(mesh.GetNumberOfTets()); // throws, naming the array
  }
  if (irradiance.size() != 3 * static_cast<size_t>(mesh.GetNumberOfPoints()))
  {
    CheckIrradiance(mesh, irradiance); // throws
  }
}

/// Raw pointers to the three channels' matrix values and right-hand sides
/// of a sized system (for the assembly kernels).
struct ChannelPointers
{
  double* Values[NumberOfChannels];
  double* RightHandSide[NumberOfChannels];

  explicit ChannelPointers(DiffusionSystem& system)
  {
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      Values[c] = system.Values[c].data();
      RightHandSide[c] = system.RightHandSide[c].data();
    }
  }
};

/**
 * Adds a tet's symmetric 4x4 matrix to the CSR values `v`: diag[a] at entry
 * (a, a), off = (01, 02, 03, 12, 13, 23) at (a, b) and (b, a). `pos` holds
 * the tet's 16 entry positions, entry 4a + b = (row tv[a], column tv[b])
 * (TetMesh::GetTetNonZeroPositions).
 */
inline void ScatterTetMatrix(double* v, const int* pos, const double diag[4], const double off[6])
{
  v[pos[0]] += diag[0];
  v[pos[5]] += diag[1];
  v[pos[10]] += diag[2];
  v[pos[15]] += diag[3];
  v[pos[1]] += off[0];
  v[pos[4]] += off[0];
  v[pos[2]] += off[1];
  v[pos[8]] += off[1];
  v[pos[3]] += off[2];
  v[pos[12]] += off[2];
  v[pos[6]] += off[3];
  v[pos[9]] += off[3];
  v[pos[7]] += off[4];
  v[pos[13]] += off[4];
  v[pos[11]] += off[5];
  v[pos[14]] += off[5];
}

/// Size `system` for the mesh's CSR pattern (values and right-hand sides
/// are filled by AssembleVertexSystem).
inline void ResizeVertexSystem(const TetMesh& mesh, DiffusionSystem& system)
{
  const size_t nnz = mesh.GetColumnIndices().size();
  system.NumberOfUnknowns = mesh.GetNumberOfPoints();
  system.RowOffsets = mesh.GetRowOffsets();
  system.ColumnIndices.resize(nnz);
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    system.Values[c].resize(nnz);
    system.RightHandSide[c].resize(mesh.GetNumberOfPoints());
  }
}

/// Tets ahead in the scatter order whose 16 entries AssembleVertexSystem
/// prefetches in every channel (at 1M tets on 2 cores, same run: the 16
/// entries 8 tets ahead 0.88x of the 4 diagonal entries 4 tets ahead; 4 and
/// 12 tets ahead 0.91x and 0.92x; the whole rows of the 4 vertices 1.24x).
constexpr int PrefetchDistance = 8;

/**
 * AssembleVertexSystem, 4. (inside its parallel region: orphaned work-
 * sharing) the tets: colour classes in turn; within a class, vertex-
 * disjoint chunks in parallel, each chunk's tets in order, each given to
 * `tetKernel` with its geometry (computed and stored in `cache` when
 * `fill`, else read from it).
 */
template <typename TetKernel>
inline void ScatterTets(const TetMesh& mesh, bool fill, TetGeometryCache& cache,
  double* const* values, TetKernel&& tetKernel)
{
  const TetMesh::ScatterSchedule& schedule = mesh.GetScatterSchedule();
  const int numColours = schedule.GetNumberOfColours();
  const double* points = mesh.GetPoints().data();
  const int* tets = mesh.GetTets().data();
  const int* positions = mesh.GetTetNonZeroPositions().data();
  for (int colour = 0; colour < numColours; ++colour)
  {
#pragma omp for schedule(dynamic, 1)
    for (int chunk = schedule.ColourOffsets[colour]; chunk < schedule.ColourOffsets[colour + 1];
         ++chunk)
    {
      const int chunkEnd = schedule.ChunkOffsets[chunk + 1];
      for (int s = schedule.ChunkOffsets[chunk]; s < chunkEnd; ++s)
      {
        const size_t t = static_cast<size_t>(schedule.Tets[s]);
        if (s + PrefetchDistance < chunkEnd)
        {
          // The entries the tet PrefetchDistance ahead will add to: much
          // of the scatter's time is waiting on these misses, far below
          // the bandwidth (the rows are not in an order a hardware
          // prefetcher follows).
          const int* ahead =
            positions + 16 * static_cast<size_t>(schedule.Tets[s + PrefetchDistance]);
          for (int c = 0; c < NumberOfChannels; ++c)
          {
            for (int e = 0; e < 16; ++e)
            {
              __builtin_prefetch(values[c] + ahead[e], 1);
            }
          }
        }
        const int* tv = tets + 4 * t;
        const TetGeometry geometry =
          fill ? cache.ComputeAndStore(points, tv, t) : cache.Get(t);
        tetKernel(t, tv, positions + 16 * t, geometry);
      }
    }
  }
}

/**
 * Assemble a vertex system on the mesh's CSR pattern: sizes `system`
 * (ResizeVertexSystem: a caller may size it first to take pointers into it),
 * then one OpenMP parallel region that
 *  1. checks every irradiance value (finite, >= 0) and every material
 *     value (finite mu_a, sigma_s' >= 0 with mu_a + sigma_s' > 0, finite
 *     eta > 0); if one is invalid it returns false with `system` not
 *     meaningful and the kernel never called (the caller re-checks serially
 *     to name it);
 *  2. copies the column indices, clears the values and right-hand sides and
 *     puts identity rows at points used by no tet;
 *  3. runs `prepare()` (orphaned OpenMP work-sharing allowed; a barrier
 *     precedes and follows it);
 *  4. calls `tetKernel(t, tv, positions, geometry)` for every tet: tv its 4
 *     vertex ids, positions its 16 CSR positions (entry 4a+b = row tv[a],
 *     column tv[b]), geometry its volume and g_ab (from `cache` when valid
 *     for this geometry, else computed and stored there). Tets are processed
 *     in the mesh's scatter schedule (colour classes of vertex-disjoint
 *     chunks, each chunk's tets in order), so the kernel may add to the rows
 *     of its tet's vertices without races and every entry sums its
 *     contributions in the same order for any number of threads;
 *  5. runs `finish()` (orphaned OpenMP work-sharing allowed).
 * The caller has checked the sizes of `material` and `irradiance`.
 */
template <typename Prepare, typename TetKernel, typename Finish>
bool AssembleVertexSystem(const TetMesh& mesh, const OpticalProperties& material,
  const std::vector<double>& irradiance, DiffusionSystem& system, int numThreads,
  TetGeometryCache& cache, Prepare&& prepare, TetKernel&& tetKernel, Finish&& finish)
{
  const int numPoints = mesh.GetNumberOfPoints();
  const int numTets = mesh.GetNumberOfTets();
  const size_t nnz = mesh.GetColumnIndices().size();
  ResizeVertexSystem(mesh, system);
  const bool fill = !cache.IsValidFor(mesh);
  if (fill)
  {
    cache.BeginFill(mesh);
  }

  const double* muA = material.AbsorptionCoefficient.data();
  const double* sigmaS = material.ReducedScatteringCoefficient.data();
  const double* tetEta = material.RefractiveIndex.data();
  const double* q = irradiance.data();
  const ChannelPointers channels(system);
  double* const* values = channels.Values;
  double* const* rhs = channels.RightHandSide;
  const long long numValues = static_cast<long long>(nnz);
  const long long numIrradianceValues = static_cast<long long>(irradiance.size());
  const long long numCoefficientValues = 3 * static_cast<long long>(numTets);
  const int* meshColumns = mesh.GetColumnIndices().data();
  int* columns = system.ColumnIndices.data();
  const int* diagonal = mesh.GetDiagonalPositions().data();
  const int* pointTetOffsets = mesh.GetPointTetOffsets().data();

  // One parallel region (fork/join and barriers are what costs on a busy
  // machine).
  int invalid = 0;
  // Reductions of the checks (shared: the worksharing loops combine into them).
  double qLow = DBL_MAX, qHigh = 0.0, qSum = 0.0;
  double cLow = DBL_MAX, cHigh = 0.0, cPositive = DBL_MAX, cSum = 0.0;
  double eLow = DBL_MAX, eHigh = 0.0, eSum = 0.0;
#pragma omp parallel num_threads(numThreads)
  {
    // 1. Irradiance and material values, in streaming passes (checking each
    // tet inside the scatter loop, step 4, cost about 15 % of the assembly
    // at 1M tets). Each pass is a min / max / sum reduction that the
    // compiler vectorises (`omp simd`; the comparisons with a logical result
    // stayed scalar, about 11 % of the assembly at 1M tets): a value is
    // valid if the minimum is >= 0 (or > 0), the maximum <= DBL_MAX (no
    // infinity) and the sum is not NaN (a NaN propagates through the sum;
    // the values are >= 0 then, so the sum cannot be -inf + inf).
#pragma omp for simd schedule(static) reduction(min : qLow) reduction(max : qHigh) reduction(+ : qSum)
    for (long long k = 0; k < numIrradianceValues; ++k)
    {
      const double v = q[k];
      qLow = v < qLow ? v : qLow;
      qHigh = v > qHigh ? v : qHigh;
      qSum += v;
    }
    // Finite mu_a, sigma_s' >= 0 with mu_a + sigma_s' > 0.
#pragma omp for simd schedule(static) reduction(min : cLow, cPositive) reduction(max : cHigh) reduction(+ : cSum)
    for (long long k = 0; k < numCoefficientValues; ++k)
    {
      const double a = muA[k], sig = sigmaS[k];
      const double low = a < sig ? a : sig, high = a > sig ? a : sig, sum = a + sig;
      cLow = low < cLow ? low : cLow;
      cHigh = high > cHigh ? high : cHigh;
      cPositive = sum < cPositive ? sum : cPositive;
      cSum += sum;
    }
    // Finite eta > 0.
#pragma omp for simd schedule(static) reduction(min : eLow) reduction(max : eHigh) reduction(+ : eSum)
    for (int t = 0; t < numTets; ++t)
    {
      const double v = tetEta[t];
      eLow = v < eLow ? v : eLow;
      eHigh = v > eHigh ? v : eHigh;
      eSum += v;
    }
    // After the implicit barrier every thread has the same reductions.
#pragma omp single
    invalid = (qLow >= 0.0 && qHigh <= DBL_MAX && !std::isnan(qSum) && cLow >= 0.0 && cHigh <= DBL_MAX &&
                cPositive > 0.0 && !std::isnan(cSum) && eLow > 0.0 && eHigh <= DBL_MAX && !std::isnan(eSum))
      ? 0
      : 1;
    // After the barrier of `single` every thread sees the same flag.
    if (!invalid)
    {
      // 2. Pattern, cleared values; right-hand sides and identity rows for
      // points used by no tet (the tets never touch those diagonals).
#pragma omp for schedule(static)
      for (long long k = 0; k < numValues; ++k)
      {
        columns[k] = meshColumns[k];
        values[0][k] = 0.0;
        values[1][k] = 0.0;
        values[2][k] = 0.0;
      }
#pragma omp for schedule(static)
      for (int i = 0; i < numPoints; ++i)
      {
        const bool orphan = pointTetOffsets[i + 1] == pointTetOffsets[i];
        for (int c = 0; c < NumberOfChannels; ++c)
        {
          rhs[c][i] = 0.0;
          if (orphan)
          {
            values[c][diagonal[i]] = 1.0;
          }
        }
      }
      // 3.
      prepare();
#pragma omp barrier
      // 4. Tets: colour classes in turn; within a class, vertex-disjoint
      // chunks in parallel, each chunk's tets in order.
      ScatterTets(mesh, fill, cache, values, tetKernel);
      // 5.
      finish();
    }
  }
  if (!invalid && fill)
  {
    cache.EndFill(mesh);
  }
  return !invalid;
}

/// Vertex unknowns are the mesh points: copy the three channels' solutions
/// into fluence (3 values per point), checking their sizes.
inline void VertexSolutionToPointFluence(const char* who, const TetMesh& mesh,
  const DiffusionSystem& system, const std::array<Eigen::VectorXd, NumberOfChannels>& solution,
  std::vector<double>& fluence)
{
  const int numPoints = mesh.GetNumberOfPoints();
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    if (solution[c].size() != numPoints || system.NumberOfUnknowns != numPoints)
    {
      std::ostringstream os;
      os << who << ": solution of channel " << ChannelName(c) << " has " << solution[c].size()
         << " values but the mesh has " << numPoints << " points";
      throw Error(os.str());
    }
  }
  fluence.resize(3 * static_cast<size_t>(numPoints));
#pragma omp parallel for schedule(static)
  for (int i = 0; i < numPoints; ++i)
  {
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      fluence[3 * static_cast<size_t>(i) + c] = solution[c][i];
    }
  }
}

} // namespace translucency
