#include "DiscreteDivergence.h"

#include "Error.h"
#include "Fresnel.h"
#include "Radiance.h"
#include "TetContributions.h"
#include "TetGeometry.h"
#include "TetMesh.h"
#include "VertexAssembly.h"

#include <omp.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <sstream>

namespace translucency
{

void DiscreteDivergence::Assemble(const TetMesh& mesh,
  const OpticalProperties& material,
  const std::vector<double>& irradiance,
  DiffusionSystem& system)
{
  const int numTets = mesh.GetNumberOfTets();
  CheckAssemblySizes(mesh, material, irradiance);

  ResizeVertexSystem(mesh, system);
  const int numThreads = NumberOfThreads_ > 0 ? NumberOfThreads_ : omp_get_max_threads();
  const double* muA = material.AbsorptionCoefficient.data();
  const double* sigmaS = material.ReducedScatteringCoefficient.data();
  const double* tetEta = material.RefractiveIndex.data();
  const double* q = irradiance.data();
  const ChannelPointers channels(system);
  double* const* values = channels.Values;
  double* const* rhs = channels.RightHandSide;
  const std::vector<int>& boundaryPoints = mesh.GetBoundaryPoints();
  const std::vector<double>& boundaryArea = mesh.GetBoundaryAreas();
  const int* diagonal = mesh.GetDiagonalPositions().data();
  const int numBoundary = static_cast<int>(boundaryPoints.size());

  auto prepare = []() {};
  auto tetKernel = [&](size_t t, const int*, const int* pos, const TetGeometry& geometry) {
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      double diag[4], off[6]; // TransCut eq. 13-14 (TetContributions.h)
      DivergenceTetMatrix(geometry, muA[3 * t + c], sigmaS[3 * t + c], diag, off);
      ScatterTetMatrix(values[c], pos, diag, off);
    }
  };
  auto finish = [&]() {
    // Boundary rows: lumped Robin term and source (TransCut eq. 11-13).
#pragma omp for schedule(static)
    for (int k = 0; k < numBoundary; ++k)
    {
      const int i = boundaryPoints[k];
      // Area-weighted eta of the boundary triangles around i (the material
      // was checked in AssembleVertexSystem).
      const Fresnel::RobinCoefficients robinCoefficients = Fresnel::BoundaryCoefficients(
        BoundaryPointRefractiveIndexAt(mesh, tetEta, k), BoundaryRule_);
      const double fdr = robinCoefficients.Fdr;
      const double a = robinCoefficients.A;
      const double s = boundaryArea[i];
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        values[c][diagonal[i]] += DivergenceRobinDiagonal(s, a); // TransCut eq. 13, boundary case
        rhs[c][i] = DivergenceRobinLoad(s, q[3 * static_cast<size_t>(i) + c], a, fdr); // eq. 12
      }
    }
  };
  if (!AssembleVertexSystem(
        mesh, material, irradiance, system, numThreads, GeometryCache_, prepare, tetKernel, finish))
  {
    // Serial re-checks that name the culprit.
    material.Validate(numTets);
    CheckIrradiance(mesh, irradiance);
    throw Error("DiscreteDivergence: invalid material or irradiance");
  }
}

namespace
{
/// UpdateTets: the rows to rebuild (the vertices of the changed tets, in
/// order of first use; flagged in rowFlag), each changed tet's id and
/// coefficients checked.
void ChangedRows(const TetMesh& mesh, const OpticalProperties& material,
  const std::vector<int>& changedTets, std::vector<char>& rowFlag, std::vector<int>& rows)
{
  const int numTets = mesh.GetNumberOfTets();
  const double* muA = material.AbsorptionCoefficient.data();
  const double* sigmaS = material.ReducedScatteringCoefficient.data();
  const double* tetEta = material.RefractiveIndex.data();
  const int* tets = mesh.GetTets().data();
  rowFlag.assign(static_cast<size_t>(mesh.GetNumberOfPoints()), 0);
  rows.clear();
  for (int t : changedTets)
  {
    if (t < 0 || t >= numTets)
    {
      std::ostringstream os;
      os << "DiscreteDivergence::UpdateTets: tet id " << t << " is out of range (the mesh has "
         << numTets << " tets)";
      throw Error(os.str());
    }
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      const double a = muA[3 * t + c], s = sigmaS[3 * t + c];
      if (!(std::isfinite(a) && a >= 0.0 && std::isfinite(s) && s >= 0.0 && a + s > 0.0 &&
            std::isfinite(tetEta[t]) && tetEta[t] > 0.0))
      {
        std::ostringstream os;
        os << "tet " << t << ", channel " << ChannelName(c) << ": mu_a = " << a
           << " 1/mm, sigma_s' = " << s << " 1/mm, eta = " << tetEta[t]
           << ": need finite mu_a, sigma_s' >= 0 with mu_a + sigma_s' > 0 and eta > 0";
        throw Error(os.str());
      }
    }
    for (int a = 0; a < 4; ++a)
    {
      const int i = tets[4 * static_cast<size_t>(t) + a];
      if (!rowFlag[i])
      {
        rowFlag[i] = 1;
        rows.push_back(i);
      }
    }
  }
}

} // namespace

bool DiscreteDivergence::UpdateTets(const TetMesh& mesh,
  const OpticalProperties& material,
  const std::vector<double>& irradiance,
  const std::vector<int>& changedTets,
  DiffusionSystem& system) const
{
  const int numPoints = mesh.GetNumberOfPoints();
  const int numTets = mesh.GetNumberOfTets();
  const size_t tetCount = static_cast<size_t>(numTets);
  const size_t nnz = mesh.GetColumnIndices().size();
  if (system.NumberOfUnknowns != numPoints || system.RowOffsets.size() != mesh.GetRowOffsets().size() ||
    system.ColumnIndices.size() != nnz || system.Values[0].size() != nnz ||
    system.Values[1].size() != nnz || system.Values[2].size() != nnz ||
    system.RightHandSide[0].size() != numPoints)
  {
    std::ostringstream os;
    os << "DiscreteDivergence::UpdateTets: the system (" << system.NumberOfUnknowns
       << " unknowns, " << system.ColumnIndices.size() << " non-zeros) does not match the mesh ("
       << numPoints << " points, " << nnz << " non-zeros): call Assemble first";
    throw Error(os.str());
  }
  CheckAssemblySizes(mesh, material, irradiance);
  const double* muA = material.AbsorptionCoefficient.data();
  const double* sigmaS = material.ReducedScatteringCoefficient.data();
  const double* tetEta = material.RefractiveIndex.data();
  const int* tets = mesh.GetTets().data();

  // Rows to rebuild: the vertices of the changed tets.
  std::vector<char> rowFlag;
  std::vector<int> rows;
  ChangedRows(mesh, material, changedTets, rowFlag, rows);
  if (rows.empty())
  {
    return true;
  }

  // Clear the rows; flag every tet that contributes to one of them.
  const int* rowOffsets = mesh.GetRowOffsets().data();
  const int* pointTetOffsets = mesh.GetPointTetOffsets().data();
  const int* pointTets = mesh.GetPointTets().data();
  std::vector<char> tetFlag(tetCount, 0);
  for (int i : rows)
  {
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      std::fill(system.Values[c].begin() + rowOffsets[i], system.Values[c].begin() + rowOffsets[i + 1],
        0.0);
    }
    for (int k = pointTetOffsets[i]; k < pointTetOffsets[i + 1]; ++k)
    {
      tetFlag[pointTets[k]] = 1;
    }
  }

  // Re-sum in the order of the full assembly: the scatter schedule's order
  // (colours, chunks, tets), which is the order every entry receives its
  // contributions in Assemble. Same expressions as there (eq. 13-14).
  const double* points = mesh.GetPoints().data();
  const int* positions = mesh.GetTetNonZeroPositions().data();
  const bool cached = GeometryCache_.IsValidFor(mesh);
  for (int t0 : mesh.GetScatterSchedule().Tets)
  {
    if (!tetFlag[t0])
    {
      continue;
    }
    const size_t t = static_cast<size_t>(t0);
    const int* tv = tets + 4 * t;
    // The cached geometry has the bits ComputeTetGeometry gives.
    const TetGeometry geometry = cached ? GeometryCache_.Get(t)
                                        : ComputeTetGeometry(points + 3 * static_cast<size_t>(tv[0]),
                                            points + 3 * static_cast<size_t>(tv[1]),
                                            points + 3 * static_cast<size_t>(tv[2]),
                                            points + 3 * static_cast<size_t>(tv[3]));
    const double volume = geometry.Volume;
    const double(&g)[4][4] = geometry.Stiffness;
    const int* pos = positions + 16 * t;
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      const double mu = muA[3 * t + c];
      const double four = 4.0 / (3.0 * (mu + sigmaS[3 * t + c])); // 4 kappa_t
      const double mass = volume * mu;                             // eq. 13
      double* v = system.Values[c].data();
      for (int a = 0; a < 4; ++a)
      {
        if (!rowFlag[tv[a]])
        {
          continue;
        }
        for (int b = 0; b < 4; ++b)
        {
          // eq. 13 (diagonal) and eq. 14 (M_ij = 4 w_ij), as in Assemble.
          v[pos[4 * a + b]] += a == b ? four * g[a][a] + mass : four * g[a < b ? a : b][a < b ? b : a];
        }
      }
    }
  }

  // Boundary rows: lumped Robin term and source (eq. 11-13), as in Assemble.
  // Only the rebuilt rows' eta (a whole-mesh array cost more than a small
  // stroke); the same bits as in Assemble.
  const std::vector<int>& boundaryPoints = mesh.GetBoundaryPoints();
  const std::vector<double>& boundaryArea = mesh.GetBoundaryAreas();
  const int* diagonal = mesh.GetDiagonalPositions().data();
  const double* q = irradiance.data();
  for (int i : rows)
  {
    if (!mesh.IsBoundaryPoint(i))
    {
      continue;
    }
    const size_t k = static_cast<size_t>(
      std::lower_bound(boundaryPoints.begin(), boundaryPoints.end(), i) - boundaryPoints.begin());
    const Fresnel::RobinCoefficients robinCoefficients =
      Fresnel::BoundaryCoefficients(BoundaryPointRefractiveIndexAt(mesh, tetEta, k), BoundaryRule_);
    const double fdr = robinCoefficients.Fdr;
    const double a = robinCoefficients.A;
    const double s = boundaryArea[i];
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      system.Values[c][diagonal[i]] += 2.0 * s / (3.0 * a);
      system.RightHandSide[c][i] = 8.0 * s * q[3 * static_cast<size_t>(i) + c] / (3.0 * a * (1.0 - fdr));
    }
  }
  return true;
}

bool DiscreteDivergence::UpdateRightHandSide(const TetMesh& mesh,
  const OpticalProperties& material, const std::vector<double>& irradiance,
  DiffusionSystem& system) const
{
  const int numPoints = mesh.GetNumberOfPoints();
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    if (system.NumberOfUnknowns != numPoints ||
      system.RightHandSide[c].size() != static_cast<size_t>(numPoints))
    {
      std::ostringstream os;
      os << "DiscreteDivergence::UpdateRightHandSide: the system (" << system.NumberOfUnknowns
         << " unknowns) does not match the mesh (" << numPoints << " points): call Assemble first";
      throw Error(os.str());
    }
  }
  CheckAssemblySizes(mesh, material, irradiance);
  CheckIrradiance(mesh, irradiance);
  const double* tetEta = material.RefractiveIndex.data();
  const double* q = irradiance.data();
  const std::vector<int>& boundaryPoints = mesh.GetBoundaryPoints();
  const std::vector<double>& boundaryArea = mesh.GetBoundaryAreas();
  const int numBoundary = static_cast<int>(boundaryPoints.size());
  // Interior rows have no load; the boundary rows' as in Assemble (eq. 12).
#pragma omp parallel for schedule(static)
  for (int k = 0; k < numBoundary; ++k)
  {
    const int i = boundaryPoints[k];
    const Fresnel::RobinCoefficients robinCoefficients = Fresnel::BoundaryCoefficients(
      BoundaryPointRefractiveIndexAt(mesh, tetEta, k), BoundaryRule_);
    const double s = boundaryArea[i];
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      system.RightHandSide[c][i] = DivergenceRobinLoad(
        s, q[3 * static_cast<size_t>(i) + c], robinCoefficients.A, robinCoefficients.Fdr);
    }
  }
  return true;
}

void DiscreteDivergence::ToPointFluence(const TetMesh& mesh,
  const DiffusionSystem& system,
  const std::array<Eigen::VectorXd, NumberOfChannels>& solution,
  std::vector<double>& fluence) const
{
  VertexSolutionToPointFluence("DiscreteDivergence", mesh, system, solution, fluence);
}


bool DiscreteDivergence::AddMass(const TetMesh& mesh, const std::vector<double>& coefficient,
  std::array<std::vector<double>, NumberOfChannels>& values) const
{
  const int numTets = mesh.GetNumberOfTets();
  if (coefficient.size() != 3 * static_cast<std::size_t>(numTets) ||
    values[0].size() != static_cast<std::size_t>(mesh.GetNumberOfNonZeros()))
  {
    throw Error("divergence: AddMass needs 3 coefficients per tet and a system of this mesh");
  }
  const int* diagonal = mesh.GetDiagonalPositions().data();
  // Serial: each diagonal entry sums its tets in id order (the same bits at
  // any thread count).
  for (int t = 0; t < numTets; ++t)
  {
    const int* tet = mesh.GetTet(t);
    const double volume = mesh.GetTetVolume(t);
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      const double mass = volume * coefficient[3 * static_cast<std::size_t>(t) + c]; // eq. 13
      for (int a = 0; a < 4; ++a)
      {
        values[c][diagonal[tet[a]]] += mass;
      }
    }
  }
  return true;
}

} // namespace translucency
