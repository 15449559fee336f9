#include "FiniteElement.h"

#include "Error.h"
#include "Fresnel.h"
#include "TetGeometry.h"
#include "TetMesh.h"

#include <omp.h>

#include <climits>
#include <cmath>
#include <sstream>

namespace translucency
{

namespace
{

const char* const ChannelNames[NumberOfChannels] = { "R", "G", "B" };

/// Throws if the irradiance has the wrong size or a value that is not finite
/// and >= 0 (serial; Assemble checks the values in parallel first and calls
/// this for the message).
void CheckIrradiance(const TetMesh& mesh, const std::vector<double>& irradiance)
{
  const size_t expected = 3 * static_cast<size_t>(mesh.GetNumberOfPoints());
  if (irradiance.size() != expected)
  {
    std::ostringstream os;
    os << "Irradiance has " << irradiance.size() << " values but the mesh has "
       << mesh.GetNumberOfPoints() << " points (" << expected << " values expected, 3 per point)";
    throw Error(os.str());
  }
  const long long n = static_cast<long long>(expected);
  for (long long k = 0; k < n; ++k)
  {
    if (!(std::isfinite(irradiance[k]) && irradiance[k] >= 0.0))
    {
      std::ostringstream os;
      os << "Irradiance of point " << k / 3 << ", channel " << ChannelNames[k % 3] << " is "
         << irradiance[k] << " W/mm^2: must be finite and >= 0";
      throw Error(os.str());
    }
  }
}

/// Local number (0..3) of point id in tet tv (the caller knows it is there).
inline int LocalIndex(const int* tv, int id)
{
  return tv[0] == id ? 0 : (tv[1] == id ? 1 : (tv[2] == id ? 2 : 3));
}

} // namespace

void FiniteElement::Assemble(const TetMesh& mesh,
  const OpticalProperties& material,
  const std::vector<double>& irradiance,
  DiffusionSystem& system)
{
  const int numPoints = mesh.GetNumberOfPoints();
  const int numTets = mesh.GetNumberOfTets();
  const size_t tetCount = static_cast<size_t>(numTets);
  if (numTets == 0)
  {
    throw Error("FiniteElement: the mesh has no tetrahedra");
  }
  if (material.AbsorptionCoefficient.size() != 3 * tetCount ||
    material.ReducedScatteringCoefficient.size() != 3 * tetCount ||
    material.RefractiveIndex.size() != tetCount)
  {
    material.Validate(numTets); // throws, naming the array
  }
  if (irradiance.size() != 3 * static_cast<size_t>(numPoints))
  {
    CheckIrradiance(mesh, irradiance); // throws
  }

  const size_t nnz = mesh.GetColumnIndices().size();
  system.NumberOfUnknowns = numPoints;
  system.RowOffsets = mesh.GetRowOffsets();
  system.ColumnIndices.resize(nnz); // filled in parallel below
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    system.Values[c].resize(nnz);
    system.RightHandSide[c].resize(numPoints);
  }

  const int numThreads = NumberOfThreads_ > 0 ? NumberOfThreads_ : omp_get_max_threads();
  const TetMesh::ScatterSchedule& schedule = mesh.GetScatterSchedule();
  const int numColours = schedule.GetNumberOfColours();
  const double* points = mesh.GetPoints().data();
  const int* tets = mesh.GetTets().data();
  const int* positions = mesh.GetTetNonZeroPositions().data();
  const double* muA = material.AbsorptionCoefficient.data();
  const double* sigmaS = material.ReducedScatteringCoefficient.data();
  const double* tetEta = material.RefractiveIndex.data();
  const double* q = irradiance.data();
  double* values[NumberOfChannels] = {
    system.Values[0].data(), system.Values[1].data(), system.Values[2].data()
  };
  double* rhs[NumberOfChannels] = {
    system.RightHandSide[0].data(), system.RightHandSide[1].data(), system.RightHandSide[2].data()
  };
  const long long numValues = static_cast<long long>(nnz);
  const long long numMaterialValues = static_cast<long long>(3 * tetCount);
  const long long numIrradianceValues = static_cast<long long>(irradiance.size());
  const int* meshColumns = mesh.GetColumnIndices().data();
  int* columns = system.ColumnIndices.data();
  const int* diagonal = mesh.GetDiagonalPositions().data();
  const int* pointTetOffsets = mesh.GetPointTetOffsets().data();
  const int* triangles = mesh.GetBoundaryTriangles().data();
  const int* triangleTets = mesh.GetBoundaryTriangleTets().data();
  const double* triangleAreas = mesh.GetBoundaryTriangleAreas().data();
  const int numTriangles = mesh.GetNumberOfBoundaryTriangles();

  // Boundary triangles ride along with the tet that owns them: each tet gets
  // a list (head, next) of its boundary triangles, built below, and adds
  // their Robin mass and load right after its own entries. A triangle's
  // vertices are vertices of its tet, so the scatter schedule that makes the
  // tet loop race-free and deterministic covers the triangles too.
  TriangleHead_.resize(tetCount);
  TriangleNext_.resize(static_cast<size_t>(numTriangles));
  int* head = TriangleHead_.data();
  int* next = TriangleNext_.data();

  // One parallel region, as in DiscreteDivergence: check values, clear,
  // link the boundary triangles to their tets, scatter colour by colour.
  int invalid = 0;
#pragma omp parallel num_threads(numThreads)
  {
#pragma omp for schedule(static) reduction(| : invalid)
    for (long long k = 0; k < numMaterialValues; ++k)
    {
      const double a = muA[k], s = sigmaS[k];
      const bool ok = std::isfinite(a) && a >= 0.0 && std::isfinite(s) && s >= 0.0 && a + s > 0.0 &&
        std::isfinite(tetEta[k / 3]) && tetEta[k / 3] > 0.0;
      invalid |= ok ? 0 : 1;
    }
#pragma omp for schedule(static) reduction(| : invalid)
    for (long long k = 0; k < numIrradianceValues; ++k)
    {
      invalid |= (std::isfinite(q[k]) && q[k] >= 0.0) ? 0 : 1;
    }
    // After the implicit barrier every thread sees the same flag.
    if (!invalid)
    {
#pragma omp for schedule(static) nowait
      for (int t = 0; t < numTets; ++t)
      {
        head[t] = -1;
      }
#pragma omp for schedule(static)
      for (long long k = 0; k < numValues; ++k)
      {
        columns[k] = meshColumns[k];
        values[0][k] = 0.0;
        values[1][k] = 0.0;
        values[2][k] = 0.0;
      }
      // Right-hand sides, and identity rows for points used by no tet (the
      // tet loop never touches those diagonals). The barrier at the end of
      // the single below completes this loop before the tet loop.
#pragma omp for schedule(static) nowait
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

      // Lists of boundary triangles per tet, in increasing triangle order
      // (serial: two writes per boundary triangle).
#pragma omp single
      for (int f = numTriangles - 1; f >= 0; --f)
      {
        const int t = triangleTets[f];
        next[f] = head[t];
        head[t] = f;
      }

      // Tets: colour classes in turn; within a class, vertex-disjoint chunks in
      // parallel, each chunk's tets in order (deterministic summation order).
      for (int colour = 0; colour < numColours; ++colour)
      {
#pragma omp for schedule(dynamic, 1)
        for (int chunk = schedule.ColourOffsets[colour]; chunk < schedule.ColourOffsets[colour + 1];
             ++chunk)
        {
          for (int s = schedule.ChunkOffsets[chunk]; s < schedule.ChunkOffsets[chunk + 1]; ++s)
          {
            const size_t t = static_cast<size_t>(schedule.Tets[s]);
            const int* tv = tets + 4 * t;
            const double* p0 = points + 3 * static_cast<size_t>(tv[0]);
            const double* p1 = points + 3 * static_cast<size_t>(tv[1]);
            const double* p2 = points + 3 * static_cast<size_t>(tv[2]);
            const double* p3 = points + 3 * static_cast<size_t>(tv[3]);
            const TetGeometry geometry = ComputeTetGeometry(p0, p1, p2, p3);
            const double volume = geometry.Volume;
            const double(&g)[4][4] = geometry.Stiffness; // g_ab = N_a.N_b / (36 V_t)
            const int* pos = positions + 16 * t;
            const int q00 = pos[0], q01 = pos[1], q02 = pos[2], q03 = pos[3];
            const int q10 = pos[4], q11 = pos[5], q12 = pos[6], q13 = pos[7];
            const int q20 = pos[8], q21 = pos[9], q22 = pos[10], q23 = pos[11];
            const int q30 = pos[12], q31 = pos[13], q32 = pos[14], q33 = pos[15];
            for (int c = 0; c < NumberOfChannels; ++c)
            {
              const double mu = muA[3 * t + c];
              const double four = 4.0 / (3.0 * (mu + sigmaS[3 * t + c])); // 4 kappa_t
              // 4 x consistent mass (V_t / 20)(1 + delta_ab) mu_t: V_t mu_t / 5
              // off the diagonal, twice that on it.
              const double mass = volume * mu * 0.2;
              const double mass2 = mass + mass;
              const double w01 = four * g[0][1] + mass, w02 = four * g[0][2] + mass,
                           w03 = four * g[0][3] + mass;
              const double w12 = four * g[1][2] + mass, w13 = four * g[1][3] + mass,
                           w23 = four * g[2][3] + mass;
              double* v = values[c];
              v[q00] += four * g[0][0] + mass2;
              v[q11] += four * g[1][1] + mass2;
              v[q22] += four * g[2][2] + mass2;
              v[q33] += four * g[3][3] + mass2;
              v[q01] += w01;
              v[q10] += w01;
              v[q02] += w02;
              v[q20] += w02;
              v[q03] += w03;
              v[q30] += w03;
              v[q12] += w12;
              v[q21] += w12;
              v[q13] += w13;
              v[q31] += w13;
              v[q23] += w23;
              v[q32] += w23;
            }
            // The tet's boundary triangles: consistent Robin mass and load,
            // with A and Fdr of this tet's refractive index (TransCut eq. 2).
            int f = head[t];
            if (f < 0)
            {
              continue;
            }
            const double eta = tetEta[t];
            const double fdr = Fresnel::DiffuseReflectance(eta);
            const double a = Fresnel::MismatchA(eta);
            for (; f >= 0; f = next[f])
            {
              const int* tri = triangles + 3 * static_cast<size_t>(f);
              const int la = LocalIndex(tv, tri[0]), lb = LocalIndex(tv, tri[1]),
                        lc = LocalIndex(tv, tri[2]);
              const int paa = pos[5 * la], pbb = pos[5 * lb], pcc = pos[5 * lc];
              const int pab = pos[4 * la + lb], pba = pos[4 * lb + la];
              const int pac = pos[4 * la + lc], pca = pos[4 * lc + la];
              const int pbc = pos[4 * lb + lc], pcb = pos[4 * lc + lb];
              const double area = triangleAreas[f];
              // 4 x (S_f / 12)(1 + delta_ab) / (2 A): S_f / (6 A) off the diagonal.
              const double robin = area / (6.0 * a);
              const double robin2 = robin + robin;
              // 4 x (2 / (A (1 - Fdr))) (S_f / 12) sum_b (1 + delta_ab) q_b
              //   = (2 S_f / (3 A (1 - Fdr))) (q_a + q_a + q_b + q_c).
              const double load = 2.0 * area / (3.0 * a * (1.0 - fdr));
              const double* qa = q + 3 * static_cast<size_t>(tri[0]);
              const double* qb = q + 3 * static_cast<size_t>(tri[1]);
              const double* qc = q + 3 * static_cast<size_t>(tri[2]);
              for (int c = 0; c < NumberOfChannels; ++c)
              {
                double* v = values[c];
                v[paa] += robin2;
                v[pbb] += robin2;
                v[pcc] += robin2;
                v[pab] += robin;
                v[pba] += robin;
                v[pac] += robin;
                v[pca] += robin;
                v[pbc] += robin;
                v[pcb] += robin;
                const double sum = qa[c] + qb[c] + qc[c];
                rhs[c][tri[0]] += load * (sum + qa[c]);
                rhs[c][tri[1]] += load * (sum + qb[c]);
                rhs[c][tri[2]] += load * (sum + qc[c]);
              }
            }
          }
        }
      }
    }
  }
  if (invalid)
  {
    // Serial re-checks that name the culprit.
    material.Validate(numTets);
    CheckIrradiance(mesh, irradiance);
    throw Error("FiniteElement: invalid material or irradiance");
  }
}

void FiniteElement::ToPointFluence(const TetMesh& mesh,
  const DiffusionSystem& system,
  const std::array<Eigen::VectorXd, NumberOfChannels>& solution,
  std::vector<double>& fluence) const
{
  const int numPoints = mesh.GetNumberOfPoints();
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    if (solution[c].size() != numPoints || system.NumberOfUnknowns != numPoints)
    {
      std::ostringstream os;
      os << "FiniteElement: solution of channel " << ChannelNames[c] << " has "
         << solution[c].size() << " values but the mesh has " << numPoints << " points";
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
