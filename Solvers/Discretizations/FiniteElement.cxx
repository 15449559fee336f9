#include "FiniteElement.h"

#include "Error.h"
#include "Fresnel.h"
#include "TetContributions.h"
#include "TetGeometry.h"
#include "TetMesh.h"
#include "VertexAssembly.h"

#include <omp.h>

#include <cmath>
#include <sstream>

namespace translucency
{

namespace
{

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
  const int numTets = mesh.GetNumberOfTets();
  const size_t tetCount = static_cast<size_t>(numTets);
  if (numTets == 0)
  {
    throw Error("FiniteElement: the mesh has no tetrahedra");
  }
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

  auto prepare = [&]() {
#pragma omp for schedule(static)
    for (int t = 0; t < numTets; ++t)
    {
      head[t] = -1;
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
  };
  auto tetKernel = [&](size_t t, const int* tv, const int* pos, const TetGeometry& geometry) {
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      double diag[4], off[6]; // stiffness + consistent mass (TetContributions.h)
      FiniteElementTetMatrix(geometry, muA[3 * t + c], sigmaS[3 * t + c], diag, off);
      ScatterTetMatrix(values[c], pos, diag, off);
    }
    // The tet's boundary triangles: consistent Robin mass and load, with A
    // and Fdr of this tet's refractive index (TransCut eq. 2).
    int f = head[t];
    if (f < 0)
    {
      return;
    }
    const Fresnel::RobinCoefficients robinCoefficients =
      Fresnel::BoundaryCoefficients(tetEta[t], BoundaryRule_);
    const double fdr = robinCoefficients.Fdr;
    const double a = robinCoefficients.A;
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
      // 4 x (S_f / 12)(1 + delta_ab) / (2 A): S_f / (6 A) off the diagonal;
      // 4 x (2 / (A (1 - Fdr))) (S_f / 12) sum_b (1 + delta_ab) q_b
      //   = (2 S_f / (3 A (1 - Fdr))) (q_a + q_a + q_b + q_c).
      double robin, load;
      FiniteElementRobin(area, a, fdr, robin, load);
      const double robin2 = robin + robin;
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
  };
  auto finish = []() {};
  if (!AssembleVertexSystem(
        mesh, material, irradiance, system, numThreads, GeometryCache_, prepare, tetKernel, finish))
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
  VertexSolutionToPointFluence("FiniteElement", mesh, system, solution, fluence);
}


bool FiniteElement::AddMass(const TetMesh& mesh, const std::vector<double>& coefficient,
  std::array<std::vector<double>, NumberOfChannels>& values) const
{
  const int numTets = mesh.GetNumberOfTets();
  if (coefficient.size() != 3 * static_cast<std::size_t>(numTets) ||
    values[0].size() != static_cast<std::size_t>(mesh.GetNumberOfNonZeros()))
  {
    throw Error("fem: AddMass needs 3 coefficients per tet and a system of this mesh");
  }
  const int* positions = mesh.GetTetNonZeroPositions().data();
  for (int t = 0; t < numTets; ++t)
  {
    const double volume = mesh.GetTetVolume(t);
    const int* pos = positions + 16 * static_cast<std::size_t>(t);
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      // 4 x (V_t / 20)(1 + delta_ab) coefficient.
      const double mass = 0.2 * volume * coefficient[3 * static_cast<std::size_t>(t) + c];
      for (int a = 0; a < 4; ++a)
      {
        for (int b = 0; b < 4; ++b)
        {
          values[c][pos[4 * a + b]] += a == b ? 2.0 * mass : mass;
        }
      }
    }
  }
  return true;
}

} // namespace translucency
