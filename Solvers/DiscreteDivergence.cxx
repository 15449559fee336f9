#include "DiscreteDivergence.h"

#include "Error.h"
#include "Fresnel.h"
#include "Radiance.h"
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
  long long first = LLONG_MAX;
#pragma omp parallel for reduction(min : first) schedule(static)
  for (long long k = 0; k < n; ++k)
  {
    if (!(std::isfinite(irradiance[k]) && irradiance[k] >= 0.0) && k < first)
    {
      first = k;
    }
  }
  if (first != LLONG_MAX)
  {
    std::ostringstream os;
    os << "Irradiance of point " << first / 3 << ", channel " << ChannelNames[first % 3] << " is "
       << irradiance[first] << " W/mm^2: must be finite and >= 0";
    throw Error(os.str());
  }
}

} // namespace

void DiscreteDivergence::Assemble(const TetMesh& mesh, const OpticalProperties& material,
  const std::vector<double>& irradiance, DiffusionSystem& system)
{
  const int numPoints = mesh.GetNumberOfPoints();
  const int numTets = mesh.GetNumberOfTets();
  material.Validate(numTets);
  CheckIrradiance(mesh, irradiance);

  const std::vector<double> pointEta = BoundaryPointRefractiveIndex(mesh, material.RefractiveIndex);

  const size_t nnz = mesh.GetColumnIndices().size();
  system.NumberOfUnknowns = numPoints;
  system.RowOffsets = mesh.GetRowOffsets();
  system.ColumnIndices = mesh.GetColumnIndices();
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    system.Values[c].resize(nnz);
    system.RightHandSide[c].setZero(numPoints);
  }

  const int numThreads = NumberOfThreads_ > 0 ? NumberOfThreads_ : omp_get_max_threads();
  const TetMesh::ScatterSchedule& schedule = mesh.GetScatterSchedule();
  const int numColours = schedule.GetNumberOfColours();
  const double* points = mesh.GetPoints().data();
  const int* tets = mesh.GetTets().data();
  const int* positions = mesh.GetTetNonZeroPositions().data();
  const double* muA = material.AbsorptionCoefficient.data();
  const double* sigmaS = material.ReducedScatteringCoefficient.data();
  double* values[NumberOfChannels] = { system.Values[0].data(), system.Values[1].data(),
    system.Values[2].data() };
  const long long numValues = static_cast<long long>(nnz);

#pragma omp parallel num_threads(numThreads)
  {
#pragma omp for schedule(static)
    for (long long k = 0; k < numValues; ++k)
    {
      values[0][k] = 0.0;
      values[1][k] = 0.0;
      values[2][k] = 0.0;
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
          const double e1[3] = { p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2] };
          const double e2[3] = { p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2] };
          const double e3[3] = { p3[0] - p0[0], p3[1] - p0[1], p3[2] - p0[2] };
          // N[a] = 2 S_a n_a: twice the area times the unit normal of the face
          // opposite vertex a, pointing towards a (TransCut eq. 4 notation).
          double n[4][3];
          n[1][0] = e2[1] * e3[2] - e2[2] * e3[1];
          n[1][1] = e2[2] * e3[0] - e2[0] * e3[2];
          n[1][2] = e2[0] * e3[1] - e2[1] * e3[0];
          n[2][0] = e3[1] * e1[2] - e3[2] * e1[1];
          n[2][1] = e3[2] * e1[0] - e3[0] * e1[2];
          n[2][2] = e3[0] * e1[1] - e3[1] * e1[0];
          n[3][0] = e1[1] * e2[2] - e1[2] * e2[1];
          n[3][1] = e1[2] * e2[0] - e1[0] * e2[2];
          n[3][2] = e1[0] * e2[1] - e1[1] * e2[0];
          // Closed surface: the face area vectors sum to zero.
          n[0][0] = -(n[1][0] + n[2][0] + n[3][0]);
          n[0][1] = -(n[1][1] + n[2][1] + n[3][1]);
          n[0][2] = -(n[1][2] + n[2][2] + n[3][2]);
          const double sixV = e1[0] * n[1][0] + e1[1] * n[1][1] + e1[2] * n[1][2];
          const double volume = sixV / 6.0;
          // Geometric edge weights g_ab = w_abt / kappa_t. The faces opposite
          // a and b meet at the opposite edge kl with interior dihedral angle
          // theta_kl: n_a.n_b = -cos(theta_kl) and sin(theta_kl) =
          // 3 V_t |kl| / (2 S_a S_b), so
          //   -(1/6) |kl| cot(theta_kl) = S_a S_b (n_a.n_b) / (9 V_t)
          //                             = N_a.N_b / (36 V_t)     (TransCut eq. 10, Sec. 3.3)
          const double scale = 1.0 / (6.0 * sixV);
          double g[4][4];
          for (int a = 0; a < 4; ++a)
          {
            for (int b = a + 1; b < 4; ++b)
            {
              g[a][b] = g[b][a] =
                (n[a][0] * n[b][0] + n[a][1] * n[b][1] + n[a][2] * n[b][2]) * scale;
            }
          }
          // -sum_j w_ijt (TransCut Sec. 3.3: w_iit = -(w_ijt + w_ikt + w_ilt)).
          for (int a = 0; a < 4; ++a)
          {
            double sum = 0.0;
            for (int b = 0; b < 4; ++b)
            {
              sum += b == a ? 0.0 : g[a][b];
            }
            g[a][a] = -sum;
          }
          const int* pos = positions + 16 * t;
          for (int c = 0; c < NumberOfChannels; ++c)
          {
            const double mu = muA[3 * t + c];
            const double kappa = 1.0 / (3.0 * (mu + sigmaS[3 * t + c]));
            const double four = 4.0 * kappa;
            const double mass = volume * mu; // V_t mu_t: the tet's share of V_i mu(x_i), eq. 13
            double* v = values[c];
            for (int a = 0; a < 4; ++a)
            {
              for (int b = 0; b < 4; ++b)
              {
                if (a == b)
                {
                  v[pos[5 * a]] += four * g[a][a] + mass; // TransCut eq. 13: -4 sum_j w_ij + V_i mu
                }
                else
                {
                  v[pos[4 * a + b]] += four * g[a][b]; // TransCut eq. 14: M_ij = 4 w_ij
                }
              }
            }
          }
        }
      }
    }
  }

  // Boundary rows: lumped Robin term and source (TransCut eq. 11-13).
  const std::vector<int>& boundaryPoints = mesh.GetBoundaryPoints();
  const std::vector<double>& boundaryArea = mesh.GetBoundaryAreas();
  const std::vector<int>& diagonal = mesh.GetDiagonalPositions();
  const int numBoundary = static_cast<int>(boundaryPoints.size());
#pragma omp parallel for schedule(static) num_threads(numThreads)
  for (int k = 0; k < numBoundary; ++k)
  {
    const int i = boundaryPoints[k];
    const double fdr = Fresnel::DiffuseReflectance(pointEta[i]);
    const double a = Fresnel::MismatchA(pointEta[i]);
    const double s = boundaryArea[i];
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      values[c][diagonal[i]] += 2.0 * s / (3.0 * a); // TransCut eq. 13, boundary case
      system.RightHandSide[c][i] =
        8.0 * s * irradiance[3 * static_cast<size_t>(i) + c] / (3.0 * a * (1.0 - fdr)); // eq. 12
    }
  }

  // Points used by no tet: identity row, zero right-hand side.
  const std::vector<int>& pointTetOffsets = mesh.GetPointTetOffsets();
#pragma omp parallel for schedule(static) num_threads(numThreads)
  for (int i = 0; i < numPoints; ++i)
  {
    if (pointTetOffsets[i + 1] == pointTetOffsets[i])
    {
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        values[c][diagonal[i]] = 1.0;
      }
    }
  }
}

void DiscreteDivergence::ToPointFluence(const TetMesh& mesh, const DiffusionSystem& system,
  const std::array<Eigen::VectorXd, NumberOfChannels>& solution,
  std::vector<double>& fluence) const
{
  const int numPoints = mesh.GetNumberOfPoints();
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    if (solution[c].size() != numPoints || system.NumberOfUnknowns != numPoints)
    {
      std::ostringstream os;
      os << "solution of channel " << ChannelNames[c] << " has " << solution[c].size()
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
