#include "Sp3Solver.h"

#include "AggregationMultigrid.h"
#include "Error.h"
#include "Fresnel.h"
#include "LinearSolver.h"
#include "ResourceLimits.h"
#include "Strings.h"
#include "TetMesh.h"
#include "TetLocator.h"
#include "Timer.h"
#include "VertexAssembly.h"
#include "VertexDiffusionSolver.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <exception>
#include <functional>
#include <map>
#include <sstream>

namespace translucency
{

Sp3BoundaryCoefficients Sp3BoundaryCoefficients::Compute(double eta)
{
  if (!std::isfinite(eta) || !(eta > 0.0))
  {
    std::ostringstream os;
    os << "sp3: refractive index " << eta << " (expected finite and > 0)";
    throw Error(os.str());
  }
  const std::array<double, 7> r = Fresnel::ReflectanceHalfRangeMoments(eta);
  Sp3BoundaryCoefficients k;
  // Klose & Larsen 2006, eq. 28a-b (the SP3 partly reflecting boundary
  // conditions; the coefficients here from the Marshak conditions with
  // weights P_1 and P_3, Sp3Solver.h).
  k.A1 = -r[1];
  k.B1 = 3.0 * r[2];
  k.C1 = 0.5 * (5.0 * r[3] - 3.0 * r[1]);
  k.D1 = 0.5 * (3.0 * r[2] - 5.0 * r[4]);
  k.A2 = -2.25 * r[1] + 7.5 * r[3] - 6.25 * r[5];
  k.B2 = 15.75 * r[2] - 52.5 * r[4] + 43.75 * r[6];
  k.C2 = k.C1;
  k.D2 = k.D1;
  // With J_1 = -(1/(3 mu_a1)) n.grad phi_1 and J_2 = -(1/(7 mu_a3)) n.grad
  // phi_2 the two conditions read
  //   (1 + B1) J_1 - 7 D1 J_2 = (1/2 + A1) phi_1 - (1/8 + C1) phi_2 - 2 q,
  //   -3 D2 J_1 + (1 + B2) J_2 = -(1/8 + C2) phi_1 + (7/24 + A2) phi_2 + q/2.
  const double m11 = 1.0 + k.B1, m12 = -7.0 * k.D1, m21 = -3.0 * k.D2, m22 = 1.0 + k.B2;
  const double det = m11 * m22 - m12 * m21;
  if (!(std::abs(det) > 1e-12))
  {
    std::ostringstream os;
    os << "sp3: the boundary conditions are singular at refractive index " << eta;
    throw Error(os.str());
  }
  auto solve = [&](double b1, double b2, double& j1, double& j2) {
    j1 = (b1 * m22 - m12 * b2) / det;
    j2 = (m11 * b2 - m21 * b1) / det;
  };
  solve(0.5 + k.A1, -(0.125 + k.C2), k.F11, k.F21);
  solve(-(0.125 + k.C1), 7.0 / 24.0 + k.A2, k.F12, k.F22);
  solve(-2.0, 0.5, k.S1, k.S2);
  // Exitance: J_out = (1/2) sum_n (2n+1) (-1)^n phi_n T_n with the
  // transmitted half-range integrals T_n = int_0^1 (1 - R) P_n(mu) mu dmu and
  // phi_0 = phi_1 - (2/3) phi_2, phi_1 = -J_1, phi_2 = phi_2 / 3,
  // phi_3 = -J_2 (the Legendre moments along the inward normal).
  const double t0 = 0.5 - r[1];
  const double t1 = 1.0 / 3.0 - r[2];
  const double t2 = 0.125 - 0.5 * (3.0 * r[3] - r[1]);
  const double t3 = -0.5 * (5.0 * r[4] - 3.0 * r[2]);
  k.E1 = 0.5 * (t0 + 3.0 * k.F11 * t1 + 7.0 * k.F21 * t3);
  k.E2 = 0.5 * (-2.0 / 3.0 * t0 + 3.0 * k.F12 * t1 + 5.0 / 3.0 * t2 + 7.0 * k.F22 * t3);
  k.E3 = 0.5 * (3.0 * k.S1 * t1 + 7.0 * k.S2 * t3);
  return k;
}

double Sp3OutgoingRadiance(const Sp3BoundaryCoefficients& k, double eta, double phi1, double phi2,
  double q, double cosOut, RadianceReadout readout)
{
  if (!(cosOut > 0.0))
  {
    return 0.0;
  }
  const double c = std::min(cosOut, 1.0);
  // Snell: the internal cosine of the direction that leaves at cosOut.
  const double mu = std::sqrt(std::max(0.0, 1.0 - (1.0 - c * c) / (eta * eta)));
  const double transmitted = 1.0 - Fresnel::Reflectance(c, eta);
  const double j1 = k.F11 * phi1 + k.F12 * phi2 + k.S1 * q;
  const double j2 = k.F21 * phi1 + k.F22 * phi2 + k.S2 * q;
  const double p2 = 0.5 * (3.0 * mu * mu - 1.0);
  const double p3 = 0.5 * (5.0 * mu * mu * mu - 3.0 * mu);
  const double inside = (phi1 - (2.0 / 3.0) * phi2 + 3.0 * j1 * mu + (5.0 / 3.0) * phi2 * p2 +
                          7.0 * j2 * p3) /
    (4.0 * 3.14159265358979323846);
  const double scale = readout == RadianceReadout::Paper ? 1.0 : 1.0 / (eta * eta);
  return std::max(0.0, transmitted * inside * scale);
}

std::vector<double> Sp3BoundaryRadiance(const TetMesh& mesh, const std::vector<double>& phi1,
  const std::vector<double>& phi2, const std::vector<double>& irradiance,
  const std::vector<double>& pointEta, const double* viewPoint, RadianceReadout readout)
{
  const std::size_t numPoints = static_cast<std::size_t>(mesh.GetNumberOfPoints());
  if (phi1.size() != 3 * numPoints || phi2.size() != 3 * numPoints ||
    irradiance.size() != 3 * numPoints || pointEta.size() != numPoints)
  {
    std::ostringstream os;
    os << "sp3 radiance: the mesh has " << numPoints << " points but phi_1 has " << phi1.size()
       << " values, phi_2 " << phi2.size() << ", irradiance " << irradiance.size() << " and eta "
       << pointEta.size() << " (3, 3, 3 and 1 per point expected)";
    throw Error(os.str());
  }
  const std::vector<int>& boundary = mesh.GetBoundaryPoints();
  const std::vector<double>& normals = mesh.GetPointNormals();
  // The boundary coefficients per distinct eta (serially; usually one).
  std::map<double, Sp3BoundaryCoefficients> coefficients;
  for (const int i : boundary)
  {
    const double eta = pointEta[static_cast<std::size_t>(i)];
    if (coefficients.find(eta) == coefficients.end())
    {
      coefficients.emplace(eta, Sp3BoundaryCoefficients::Compute(eta));
    }
  }
  const long long n = static_cast<long long>(boundary.size());
  std::vector<double> radiance(3 * boundary.size());
#pragma omp parallel for schedule(static)
  for (long long k = 0; k < n; ++k)
  {
    const std::size_t i = static_cast<std::size_t>(boundary[static_cast<std::size_t>(k)]);
    const double* nrm = &normals[3 * i];
    const double cosOut = ViewCosine(viewPoint, mesh.GetPoint(static_cast<int>(i)), nrm);
    const Sp3BoundaryCoefficients& coefficient = coefficients.find(pointEta[i])->second;
    for (int c = 0; c < 3; ++c)
    {
      radiance[3 * static_cast<std::size_t>(k) + c] = Sp3OutgoingRadiance(coefficient,
        pointEta[i], phi1[3 * i + c], phi2[3 * i + c], irradiance[3 * i + c], cosOut, readout);
    }
  }
  RequireFinite(radiance, "Radiance", OverflowCause());
  return radiance;
}

/// The assembled blocks: A11 and A22 as systems (the multigrid cycles are
/// set up on them), A12 and A21 on the same pattern (in continuous wave A21
/// is assembled only in the rows of boundary-triangle vertices, RowsA21, and
/// is 0 elsewhere: there it equals A12, which BlockProduct reads in its
/// place); in the frequency domain the imaginary parts B of the four blocks
/// and of the right-hand sides (empty in continuous wave).
struct Sp3Solver::Blocks
{
  DiffusionSystem A11, A22;
  std::array<std::vector<double>, NumberOfChannels> A12, A21;
  std::array<std::vector<double>, NumberOfChannels> B11, B12, B21, B22;
  std::array<std::vector<double>, NumberOfChannels> ImaginaryRhs1, ImaginaryRhs2;
  /// multigrid-agg on A11 and A22, one aggregation hierarchy (Cycle2's is
  /// Cycle1's: SetUpPreconditioner).
  std::unique_ptr<AggregationMultigridSolver> Cycle1, Cycle2;
  std::vector<double> InverseDiagonal;          ///< Jacobi: 2 N x 3 interleaved
  std::vector<unsigned char> OwnA21; ///< per row: A21 differs from A12 (BlockProduct)
  /// Per point: A21's row is assembled (RowsA21 of the assembly kernels).
  std::vector<unsigned char> RowsA21;
  /// The material of the blocks of the last continuous-wave assembly
  /// (AssembledValid: they hold it): the blocks are a function of the mesh
  /// geometry, the material and omega only, so a continuous-wave solve on
  /// the same mesh with an equal material (a relight, new sources) rebuilds
  /// only the right-hand sides and keeps the cycles' set-up.
  OpticalProperties AssembledMaterial;
  bool AssembledValid = false;
  bool Multigrid = false;
  bool CyclesReady = false; ///< the hierarchy is this mesh's
  bool CyclesSetUp = false; ///< the cycles are set up on the blocks' values
};

Sp3Solver::Sp3Solver()
  : Blocks_(new Blocks)
{
}

Sp3Solver::~Sp3Solver() = default;

void Sp3Solver::Reset()
{
  X_.clear();
  LastMesh_ = nullptr;
  LastPoints_ = -1;
  LastTets_ = -1;
  LastRevision_ = 0;
  Blocks_->CyclesReady = false;
  Blocks_->CyclesSetUp = false;
  Blocks_->AssembledValid = false;
}

namespace
{

constexpr double SpeedOfLight = SpeedOfLightMillimetresPerNanosecond * 1e9; // mm/s

inline int LocalIndex(const int* tv, int id)
{
  return tv[0] == id ? 0 : (tv[1] == id ? 1 : (tv[2] == id ? 2 : 3));
}

/// The per-eta boundary coefficients of a mesh's tets (one Compute per
/// distinct value; meshes usually have one).
std::vector<Sp3BoundaryCoefficients> CoefficientsPerTet(
  const TetMesh& mesh, const OpticalProperties& material, std::vector<int>& index)
{
  std::map<double, int> seen;
  std::vector<Sp3BoundaryCoefficients> out;
  const std::vector<int>& triangleTets = mesh.GetBoundaryTriangleTets();
  index.assign(static_cast<std::size_t>(mesh.GetNumberOfTets()), -1);
  for (const int t : triangleTets)
  {
    const double eta = material.RefractiveIndex[static_cast<std::size_t>(t)];
    auto it = seen.find(eta);
    if (it == seen.end())
    {
      it = seen.emplace(eta, static_cast<int>(out.size())).first;
      out.push_back(Sp3BoundaryCoefficients::Compute(eta));
    }
    index[static_cast<std::size_t>(t)] = it->second;
  }
  return out;
}

/// The coefficients of the SP3 equations of one tet and channel: T =
/// std::complex<double> in the frequency domain, double in continuous wave
/// (the same expressions; with a zero imaginary part every operation's
/// real part is the real operation's, libgcc's complex division by (c, 0)
/// included: (a + 0 (0 / c)) / c, so continuous wave gets the same bits
/// without the complex divisions: with A21's rows below, a full assembly
/// on cached geometry at 1M tets took about a third less, Solvers.md SP3
/// "Cost").
template <typename T>
struct TetCoefficients
{
  T D1, D2, M1, M2, M12;
};

/// mu_a (1/mm), sigma_s' (1/mm), g, and a = mu_a + i alpha, alpha = omega
/// eta / c (1/mm; a = mu_a, real, in continuous wave).
template <typename T>
TetCoefficients<T> ComputeTetCoefficients(double sigmaS, double g, T a)
{
  // mu_an = mu_a + mu_s (1 - g^n) with mu_s = sigma_s' / (1 - g) (Klose &
  // Larsen 2006, the SP_N absorption moments; section and equation numbers
  // unverified: the paper is not in shared/papers, Solvers.md "SP3" derives
  // what is used here).
  // The frequency domain: the time derivative (eta / c) d/dt of the
  // transport equation adds i omega eta / c to mu_t, hence to every mu_an.
  const T muA1 = a + sigmaS;
  const T muA2 = a + sigmaS * (1.0 + g);
  const T muA3 = a + sigmaS * (1.0 + g + g * g);
  // The SP3 equations in their composite moments (Klose & Larsen 2006;
  // derived from the planar P3 equations in Solvers.md "SP3"): diffusion
  // coefficients 1/(3 mu_a1), 1/(7 mu_a3); mass coefficients mu_a,
  // (4/9) mu_a + (5/9) mu_a2 and the coupling -(2/3) mu_a.
  TetCoefficients<T> k;
  k.D1 = 1.0 / (3.0 * muA1);
  k.D2 = 1.0 / (7.0 * muA3);
  k.M1 = a;
  k.M2 = (4.0 / 9.0) * a + (5.0 / 9.0) * muA2;
  k.M12 = -(2.0 / 3.0) * a;
  return k;
}

/// Raw pointers to the values the assembly kernels write, per channel:
/// the real parts of the four blocks and both right-hand sides, and in the
/// frequency domain the imaginary parts of the blocks (else null).
struct BlockPointers
{
  double* V11[NumberOfChannels]{};
  double* V12[NumberOfChannels]{};
  double* V21[NumberOfChannels]{};
  double* V22[NumberOfChannels]{};
  double* W11[NumberOfChannels]{};
  double* W12[NumberOfChannels]{};
  double* W21[NumberOfChannels]{};
  double* W22[NumberOfChannels]{};
  double* Rhs1[NumberOfChannels]{};
  double* Rhs2[NumberOfChannels]{};
  /// Continuous wave: per point, 1 if A21's row is assembled (a vertex of
  /// a boundary triangle; Sp3Solver::Blocks::A21).
  const unsigned char* RowsA21 = nullptr;
  bool Complex = false;
};

/// A tet's stiffness and consistent mass (V_t / 20)(1 + delta_ab) into the
/// four blocks, every channel.
void AddTetBlocks(const BlockPointers& b, std::size_t t, const int* tv, const int* pos,
  const TetGeometry& geometry, const OpticalProperties& material, double alpha)
{
  const double(&g)[4][4] = geometry.Stiffness;
  const double mass = geometry.Volume / 20.0;
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    const double muA = material.AbsorptionCoefficient[3 * t + c];
    const double sigmaS = material.ReducedScatteringCoefficient[3 * t + c];
    const double anisotropy = material.GetAnisotropy(static_cast<int>(t), c);
    if (!b.Complex)
    {
      const TetCoefficients<double> k = ComputeTetCoefficients(sigmaS, anisotropy, muA);
      for (int i = 0; i < 4; ++i)
      {
        // A21's row only where it can differ from A12's (the tets' part
        // is the same: the Fresnel boundary rows make the difference).
        const bool rowA21 = b.RowsA21[tv[i]] != 0;
        for (int j = 0; j < 4; ++j)
        {
          const int p = pos[4 * i + j];
          const double mij = i == j ? 2.0 * mass : mass;
          b.V11[c][p] += k.D1 * g[i][j] + k.M1 * mij;
          b.V22[c][p] += k.D2 * g[i][j] + k.M2 * mij;
          b.V12[c][p] += k.M12 * mij;
          if (rowA21)
          {
            b.V21[c][p] += k.M12 * mij;
          }
        }
      }
      continue;
    }
    const TetCoefficients<std::complex<double>> k =
      ComputeTetCoefficients(sigmaS, anisotropy, std::complex<double>(muA, alpha));
    for (int i = 0; i < 4; ++i)
    {
      for (int j = 0; j < 4; ++j)
      {
        const int p = pos[4 * i + j];
        const double mij = i == j ? 2.0 * mass : mass;
        b.V11[c][p] += k.D1.real() * g[i][j] + k.M1.real() * mij;
        b.V22[c][p] += k.D2.real() * g[i][j] + k.M2.real() * mij;
        b.V12[c][p] += k.M12.real() * mij;
        b.V21[c][p] += k.M12.real() * mij;
        if (b.Complex)
        {
          b.W11[c][p] += k.D1.imag() * g[i][j] + k.M1.imag() * mij;
          b.W22[c][p] += k.D2.imag() * g[i][j] + k.M2.imag() * mij;
          b.W12[c][p] += k.M12.imag() * mij;
          b.W21[c][p] += k.M12.imag() * mij;
        }
      }
    }
  }
}

/// The boundary load of a boundary triangle (the S q part of the currents
/// J_1, J_2, moved to the right-hand side; consistent: int q v = (S_f /
/// 12)(q_i + sum_j q_j)), every channel. Shared by the full assembly and
/// the right-hand sides' (Sp3Solver::AssembleRightHandSides): the same
/// operations in the same order, so the same bits.
inline void AddBoundaryLoad(double* const* rhs1, double* const* rhs2,
  const Sp3BoundaryCoefficients& k, const int* tri, double area, const double* q)
{
  const double m = area / 12.0;
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    double qSum = 0.0;
    for (int i = 0; i < 3; ++i)
    {
      qSum += q[3 * static_cast<std::size_t>(tri[i]) + c];
    }
    for (int i = 0; i < 3; ++i)
    {
      const double load = m * (qSum + q[3 * static_cast<std::size_t>(tri[i]) + c]);
      rhs1[c][tri[i]] -= k.S1 * load;
      rhs2[c][tri[i]] -= k.S2 * load;
    }
  }
}

/// A boundary triangle of tet vertices `tv`: the currents J_1, J_2 of the
/// boundary conditions (Sp3BoundaryCoefficients) as consistent boundary
/// mass (S_f / 12)(1 + delta_ab) and load (real: the boundary data q is
/// modulated at phase 0 in the frequency domain).
void AddBoundaryTriangle(const BlockPointers& b, const Sp3BoundaryCoefficients& k,
  const int* tv, const int* pos, const int* tri, double area, const double* q)
{
  const int local[3] = { LocalIndex(tv, tri[0]), LocalIndex(tv, tri[1]), LocalIndex(tv, tri[2]) };
  const double m = area / 12.0;
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    for (int i = 0; i < 3; ++i)
    {
      for (int j = 0; j < 3; ++j)
      {
        const int p = pos[4 * local[i] + local[j]];
        const double mij = i == j ? 2.0 * m : m;
        b.V11[c][p] += k.F11 * mij;
        b.V12[c][p] += k.F12 * mij;
        b.V21[c][p] += k.F21 * mij;
        b.V22[c][p] += k.F22 * mij;
      }
    }
  }
  AddBoundaryLoad(b.Rhs1, b.Rhs2, k, tri, area, q);
}

} // namespace

void Sp3Solver::SizeBlocks(const TetMesh& mesh, bool complex)
{
  Blocks& b = *Blocks_;
  ResizeVertexSystem(mesh, b.A11);
  ResizeVertexSystem(mesh, b.A22);
  b.A22.ColumnIndices = mesh.GetColumnIndices();
  const std::size_t nnz = mesh.GetColumnIndices().size();
  const std::size_t n = static_cast<std::size_t>(mesh.GetNumberOfPoints());
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    b.A12[c].resize(nnz);
    b.A21[c].resize(nnz);
    for (auto* values : { &b.B11, &b.B12, &b.B21, &b.B22 })
    {
      if (complex)
      {
        (*values)[c].assign(nnz, 0.0);
      }
      else
      {
        (*values)[c].clear();
      }
    }
    b.ImaginaryRhs1[c].assign(complex ? n : 0, 0.0);
    b.ImaginaryRhs2[c].assign(complex ? n : 0, 0.0);
  }
}

bool Sp3Solver::Assemble(const DiffusionProblem& problem, const std::vector<double>& sourceLoad,
  const std::vector<double>& imaginaryLoad, double omega)
{
  const TetMesh& mesh = *problem.Mesh;
  const OpticalProperties& material = *problem.Material;
  const std::vector<double>& irradiance = *problem.Irradiance;
  const int numTets = mesh.GetNumberOfTets();
  const int numPoints = mesh.GetNumberOfPoints();
  Blocks& b = *Blocks_;
  std::vector<int> etaIndex;
  const std::vector<Sp3BoundaryCoefficients> coefficients =
    CoefficientsPerTet(mesh, material, etaIndex);
  if (omega == 0.0 && b.AssembledValid && b.A11.NumberOfUnknowns == numPoints &&
    material.AbsorptionCoefficient == b.AssembledMaterial.AbsorptionCoefficient &&
    material.ReducedScatteringCoefficient == b.AssembledMaterial.ReducedScatteringCoefficient &&
    material.RefractiveIndex == b.AssembledMaterial.RefractiveIndex &&
    material.Anisotropy == b.AssembledMaterial.Anisotropy)
  {
    // The same mesh (PrepareProblem resets on another) and material: the
    // blocks are those assembled; only the right-hand sides change.
    AssembleRightHandSides(problem, coefficients, etaIndex);
    AddLoads(numPoints, sourceLoad, imaginaryLoad);
    return false;
  }
  // A full assembly: the cycles' set-up and the kept material no longer
  // describe the blocks until it and the set-up succeed.
  b.AssembledValid = false;
  b.CyclesSetUp = false;
  SizeBlocks(mesh, omega > 0.0);

  BlockPointers p;
  p.Complex = omega > 0.0;
  // The rows of A21 that can differ from A12's: those of boundary-triangle
  // vertices (continuous wave; the frequency domain's product reads all).
  b.RowsA21.assign(static_cast<std::size_t>(mesh.GetNumberOfPoints()), p.Complex ? 1 : 0);
  for (const int v : mesh.GetBoundaryTriangles())
  {
    b.RowsA21[static_cast<std::size_t>(v)] = 1;
  }
  p.RowsA21 = b.RowsA21.data();
  ChannelPointers channels1(b.A11);
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    p.V11[c] = channels1.Values[c];
    p.Rhs1[c] = channels1.RightHandSide[c];
    p.V22[c] = b.A22.Values[c].data();
    p.V12[c] = b.A12[c].data();
    p.V21[c] = b.A21[c].data();
    p.Rhs2[c] = b.A22.RightHandSide[c].data();
    if (p.Complex)
    {
      p.W11[c] = b.B11[c].data();
      p.W12[c] = b.B12[c].data();
      p.W21[c] = b.B21[c].data();
      p.W22[c] = b.B22[c].data();
    }
  }
  const double* q = irradiance.data();
  const int* triangles = mesh.GetBoundaryTriangles().data();
  const int* triangleTets = mesh.GetBoundaryTriangleTets().data();
  const double* triangleAreas = mesh.GetBoundaryTriangleAreas().data();
  const int numTriangles = mesh.GetNumberOfBoundaryTriangles();
  const int* diagonal = mesh.GetDiagonalPositions().data();
  const int* pointTetOffsets = mesh.GetPointTetOffsets().data();
  TriangleHead_.resize(static_cast<std::size_t>(numTets));
  TriangleNext_.resize(static_cast<std::size_t>(numTriangles));
  int* head = TriangleHead_.data();
  int* next = TriangleNext_.data();
  const long long numValues = static_cast<long long>(mesh.GetColumnIndices().size());
  const int numThreads = NumberOfThreads_ > 0 ? NumberOfThreads_ : omp_get_max_threads();

  auto prepare = [&]() {
    // A11 is cleared by AssembleVertexSystem; the other blocks here, with
    // identity rows of A22 at orphan points and the boundary triangles of
    // each tet as linked lists (head, next).
#pragma omp for schedule(static)
    for (long long k = 0; k < numValues; ++k)
    {
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        p.V22[c][k] = 0.0;
        p.V12[c][k] = 0.0;
        p.V21[c][k] = 0.0;
      }
    }
#pragma omp for schedule(static)
    for (int i = 0; i < numPoints; ++i)
    {
      const bool orphan = pointTetOffsets[i + 1] == pointTetOffsets[i];
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        p.Rhs2[c][i] = 0.0;
        if (orphan)
        {
          p.V22[c][diagonal[i]] = 1.0;
        }
      }
    }
#pragma omp for schedule(static)
    for (int t = 0; t < numTets; ++t)
    {
      head[t] = -1;
    }
#pragma omp single
    for (int f = numTriangles - 1; f >= 0; --f)
    {
      const int t = triangleTets[f];
      next[f] = head[t];
      head[t] = f;
    }
  };
  auto tetKernel = [&](std::size_t t, const int* tv, const int* pos, const TetGeometry& geometry) {
    // alpha = omega eta_t / c (1/mm): the frequency domain's i omega / v.
    const double alpha = omega > 0.0 ? omega * material.RefractiveIndex[t] / SpeedOfLight : 0.0;
    AddTetBlocks(p, t, tv, pos, geometry, material, alpha);
    for (int f = head[t]; f >= 0; f = next[f])
    {
      AddBoundaryTriangle(p, coefficients[static_cast<std::size_t>(etaIndex[t])], tv, pos,
        triangles + 3 * static_cast<std::size_t>(f), triangleAreas[f], q);
    }
  };
  auto finish = []() {};
  if (!AssembleVertexSystem(
        mesh, material, irradiance, b.A11, numThreads, GeometryCache_, prepare, tetKernel, finish))
  {
    material.Validate(numTets);
    CheckIrradiance(mesh, irradiance);
    throw Error("sp3: invalid material or irradiance");
  }
  AddLoads(numPoints, sourceLoad, imaginaryLoad);
  if (omega == 0.0)
  {
    b.AssembledMaterial.AbsorptionCoefficient = material.AbsorptionCoefficient;
    b.AssembledMaterial.ReducedScatteringCoefficient = material.ReducedScatteringCoefficient;
    b.AssembledMaterial.RefractiveIndex = material.RefractiveIndex;
    b.AssembledMaterial.Anisotropy = material.Anisotropy;
    b.AssembledValid = true;
  }
  return true;
}

void Sp3Solver::AssembleRightHandSides(const DiffusionProblem& problem,
  const std::vector<Sp3BoundaryCoefficients>& coefficients, const std::vector<int>& etaIndex)
{
  const TetMesh& mesh = *problem.Mesh;
  const std::vector<double>& irradiance = *problem.Irradiance;
  CheckIrradiance(mesh, irradiance); // what the full assembly checks of it
  Blocks& b = *Blocks_;
  double* rhs1[NumberOfChannels];
  double* rhs2[NumberOfChannels];
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    std::fill(b.A11.RightHandSide[c].begin(), b.A11.RightHandSide[c].end(), 0.0);
    std::fill(b.A22.RightHandSide[c].begin(), b.A22.RightHandSide[c].end(), 0.0);
    rhs1[c] = b.A11.RightHandSide[c].data();
    rhs2[c] = b.A22.RightHandSide[c].data();
  }
  // The boundary triangles in the order of the full assembly (the scatter
  // schedule's tets in turn, each tet's triangles by the lists it built:
  // TriangleHead_, TriangleNext_), so every row sums its loads in the same
  // order: the same bits.
  const int* triangles = mesh.GetBoundaryTriangles().data();
  const double* triangleAreas = mesh.GetBoundaryTriangleAreas().data();
  const double* q = irradiance.data();
  for (const int t : mesh.GetScatterSchedule().Tets)
  {
    for (int f = TriangleHead_[static_cast<std::size_t>(t)]; f >= 0;
         f = TriangleNext_[static_cast<std::size_t>(f)])
    {
      AddBoundaryLoad(rhs1, rhs2, coefficients[static_cast<std::size_t>(etaIndex[t])],
        triangles + 3 * static_cast<std::size_t>(f), triangleAreas[f], q);
    }
  }
}

void Sp3Solver::AddLoads(int numPoints, const std::vector<double>& sourceLoad,
  const std::vector<double>& imaginaryLoad)
{
  Blocks& b = *Blocks_;
  for (int k = 0; k < 2; ++k)
  {
    const std::vector<double>& extra = k == 0 ? AdditionalLoad1_ : AdditionalLoad2_;
    if (extra.empty())
    {
      continue;
    }
    if (extra.size() != 3 * static_cast<std::size_t>(numPoints))
    {
      std::ostringstream os;
      os << "sp3: the additional load of equation " << k + 1 << " has " << extra.size()
         << " values for " << numPoints << " points (3 per point expected)";
      throw Error(os.str());
    }
    DiffusionSystem& target = k == 0 ? b.A11 : b.A22;
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      for (int i = 0; i < numPoints; ++i)
      {
        target.RightHandSide[c][i] += extra[3 * static_cast<std::size_t>(i) + c];
      }
    }
  }
  // Interior sources: Q in the first equation, -(2/3) Q in the second
  // (the imaginary part of a modulated Q likewise).
  for (int part = 0; part < 2; ++part)
  {
    const std::vector<double>& load = part == 0 ? sourceLoad : imaginaryLoad;
    if (load.empty())
    {
      continue;
    }
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      double* rhs1 = part == 0 ? b.A11.RightHandSide[c].data() : b.ImaginaryRhs1[c].data();
      double* rhs2 = part == 0 ? b.A22.RightHandSide[c].data() : b.ImaginaryRhs2[c].data();
      for (int i = 0; i < numPoints; ++i)
      {
        const double value = load[3 * static_cast<std::size_t>(i) + c];
        rhs1[i] += value;
        rhs2[i] -= (2.0 / 3.0) * value;
      }
    }
  }
}

namespace
{

/// The values of a 2 x 2 block matrix on one CSR pattern, per channel.
struct BlockValues
{
  const double* V11[NumberOfChannels];
  const double* V12[NumberOfChannels];
  const double* V21[NumberOfChannels];
  const double* V22[NumberOfChannels];
};

/// y = A x for the block matrix A, 2 N x 3 interleaved ((b N + i) 3 + c).
/// The rows i with `ownA21[i]` == 0 read A12 in place of A21 (equal there:
/// the two coupling blocks differ only in the Fresnel boundary rows), so
/// an interior row reads three value arrays per channel, not four.
void BlockProduct(int n, const int* rows, const int* cols, const BlockValues& a,
  const unsigned char* ownA21, const double* x, double* y)
{
  const std::size_t shift = 3 * static_cast<std::size_t>(n);
#pragma omp for schedule(static)
  for (int i = 0; i < n; ++i)
  {
    double y1[3] = { 0, 0, 0 }, y2[3] = { 0, 0, 0 };
    if (ownA21[i])
    {
      for (int k = rows[i]; k < rows[i + 1]; ++k)
      {
        const std::size_t j = 3 * static_cast<std::size_t>(cols[k]);
        for (int c = 0; c < 3; ++c)
        {
          const double x1 = x[j + c], x2 = x[shift + j + c];
          y1[c] += a.V11[c][k] * x1 + a.V12[c][k] * x2;
          y2[c] += a.V21[c][k] * x1 + a.V22[c][k] * x2;
        }
      }
    }
    else
    {
      for (int k = rows[i]; k < rows[i + 1]; ++k)
      {
        const std::size_t j = 3 * static_cast<std::size_t>(cols[k]);
        for (int c = 0; c < 3; ++c)
        {
          const double x1 = x[j + c], x2 = x[shift + j + c], a12 = a.V12[c][k];
          y1[c] += a.V11[c][k] * x1 + a12 * x2;
          y2[c] += a12 * x1 + a.V22[c][k] * x2;
        }
      }
    }
    for (int c = 0; c < 3; ++c)
    {
      y[3 * static_cast<std::size_t>(i) + c] = y1[c];
      y[shift + 3 * static_cast<std::size_t>(i) + c] = y2[c];
    }
  }
}

/// The real form of (A + i B) x for the block matrices A and B: x = (x_r,
/// x_i), each 2 N x 3 interleaved; y_r = A x_r - B x_i, y_i = A x_i + B x_r.
/// One pass (one barrier: a loaded machine pays for every barrier).
void ComplexBlockProduct(int n, const int* rows, const int* cols, const BlockValues& a,
  const BlockValues& b, const double* x, double* y)
{
  const std::size_t shift = 3 * static_cast<std::size_t>(n), block = 2 * shift;
  const double* xr = x;
  const double* xi = x + block;
#pragma omp for schedule(static)
  for (int i = 0; i < n; ++i)
  {
    double r1[3] = { 0, 0, 0 }, r2[3] = { 0, 0, 0 }, i1[3] = { 0, 0, 0 }, i2[3] = { 0, 0, 0 };
    for (int k = rows[i]; k < rows[i + 1]; ++k)
    {
      const std::size_t j = 3 * static_cast<std::size_t>(cols[k]);
      for (int c = 0; c < 3; ++c)
      {
        const double p1 = xr[j + c], p2 = xr[shift + j + c];
        const double q1 = xi[j + c], q2 = xi[shift + j + c];
        r1[c] += a.V11[c][k] * p1 + a.V12[c][k] * p2 - b.V11[c][k] * q1 - b.V12[c][k] * q2;
        r2[c] += a.V21[c][k] * p1 + a.V22[c][k] * p2 - b.V21[c][k] * q1 - b.V22[c][k] * q2;
        i1[c] += a.V11[c][k] * q1 + a.V12[c][k] * q2 + b.V11[c][k] * p1 + b.V12[c][k] * p2;
        i2[c] += a.V21[c][k] * q1 + a.V22[c][k] * q2 + b.V21[c][k] * p1 + b.V22[c][k] * p2;
      }
    }
    for (int c = 0; c < 3; ++c)
    {
      const std::size_t m = 3 * static_cast<std::size_t>(i) + c;
      y[m] = r1[c];
      y[shift + m] = r2[c];
      y[block + m] = i1[c];
      y[block + shift + m] = i2[c];
    }
  }
}

/// Per-channel dot products of two vectors interleaved by 3 (serial order:
/// deterministic for any thread count).
std::array<double, 3> Dots(const std::vector<double>& a, const std::vector<double>& b)
{
  std::array<double, 3> d{ 0, 0, 0 };
  const std::size_t m = a.size() / 3;
  for (std::size_t i = 0; i < m; ++i)
  {
    for (int c = 0; c < 3; ++c)
    {
      d[c] += a[3 * i + c] * b[3 * i + c];
    }
  }
  return d;
}

/// The per-channel sums of per-chunk partial sums, in chunk order (the same
/// bits for any thread count).
std::array<double, 3> SumPartials(const std::vector<std::array<double, 3>>& partial)
{
  std::array<double, 3> sum{ 0.0, 0.0, 0.0 };
  for (const std::array<double, 3>& p : partial)
  {
    for (int c = 0; c < 3; ++c)
    {
      sum[c] += p[c];
    }
  }
  return sum;
}

/// Dots on `threads` OpenMP threads: partial sums over fixed chunks of
/// 4096 points added in chunk order, so the result does not depend on the
/// thread count.
std::array<double, 3> ChunkedDots(const double* a, const double* b, std::size_t size, int threads)
{
  constexpr std::size_t chunk = 3 * 4096;
  const std::size_t chunks = (size + chunk - 1) / chunk;
  std::vector<std::array<double, 3>> partial(chunks);
#pragma omp parallel for schedule(static) num_threads(threads)
  for (std::ptrdiff_t q = 0; q < static_cast<std::ptrdiff_t>(chunks); ++q)
  {
    double d0 = 0.0, d1 = 0.0, d2 = 0.0;
    const std::size_t end = std::min(size, (static_cast<std::size_t>(q) + 1) * chunk);
    for (std::size_t k = static_cast<std::size_t>(q) * chunk; k < end; k += 3)
    {
      d0 += a[k] * b[k];
      d1 += a[k + 1] * b[k + 1];
      d2 += a[k + 2] * b[k + 2];
    }
    partial[static_cast<std::size_t>(q)] = { d0, d1, d2 };
  }
  return SumPartials(partial);
}

/// y += s_c x per channel (interleaved by 3), on `threads` threads.
void ChannelAxpy(const std::array<double, 3>& s, const double* x, double* y, std::size_t size,
  int threads)
{
#pragma omp parallel for schedule(static) num_threads(threads)
  for (std::ptrdiff_t k = 0; k < static_cast<std::ptrdiff_t>(size); k += 3)
  {
    y[k] += s[0] * x[k];
    y[k + 1] += s[1] * x[k + 1];
    y[k + 2] += s[2] * x[k + 2];
  }
}

/**
 * BiCGSTAB (right-preconditioned) for the three channels in lockstep, each
 * with its own scalars, on vectors interleaved by 3 (entry k is channel
 * k % 3); restarted from the true residual when the recursive one says
 * converged but the true one does not (drift), at most 5 times.
 */
class LockstepBiCgStab
{
public:
  using Operator = std::function<void(const std::vector<double>&, std::vector<double>&)>;

  LockstepBiCgStab(Operator product, Operator precondition, double relTol, int maxIter,
    int threads, std::function<bool(int)> progress)
    : Product_(std::move(product))
    , Precondition_(std::move(precondition))
    , RelTol_(relTol)
    , MaxIter_(maxIter)
    , Threads_(threads)
    , Progress_(std::move(progress))
  {
  }

  /// Solves A x = rhs from x (sized as rhs); false if `progress` aborted.
  /// `zeroStart`: x is 0 (a cold start), so the first residual is rhs
  /// without a product.
  bool Solve(const std::vector<double>& rhs, std::vector<double>& x, SolverReport& report,
    bool zeroStart = false)
  {
    const std::size_t size = rhs.size();
    for (std::vector<double>* v : { &R_, &P_, &V_, &PHat_, &S_, &SHat_, &T_ })
    {
      v->assign(size, 0.0);
    }
    Bb_ = Dots(rhs, rhs);
    for (int c = 0; c < 3; ++c)
    {
      if (Bb_[c] == 0.0)
      {
        // No source in this channel: the solution is 0.
        for (std::size_t k = static_cast<std::size_t>(c); k < size; k += 3)
        {
          x[k] = 0.0;
        }
      }
    }
    if (zeroStart)
    {
      R_ = rhs;
      Rr_ = Bb_;
    }
    else
    {
      TrueResidual(rhs, x);
    }
    for (int restart = 0; restart < 5; ++restart)
    {
      for (int c = 0; c < 3; ++c)
      {
        Done_[c] = Failed_[c] || Converged(c);
      }
      if (AllDone())
      {
        break;
      }
      if (!Cycle(x))
      {
        return false;
      }
      TrueResidual(rhs, x);
      if (It_ >= MaxIter_)
      {
        break;
      }
    }
    for (int c = 0; c < 3; ++c)
    {
      report.Iterations[c] = Iterations_[c];
      report.Residual[c] = Bb_[c] > 0.0 ? std::sqrt(Rr_[c] / Bb_[c]) : std::sqrt(Rr_[c]);
      report.Converged[c] = !Failed_[c] && Converged(c);
    }
    return true;
  }

private:
  bool Converged(int c) const
  {
    return Bb_[c] == 0.0 ? Rr_[c] == 0.0 : std::sqrt(Rr_[c] / Bb_[c]) <= RelTol_;
  }
  bool AllDone() const { return Done_[0] && Done_[1] && Done_[2]; }

  void TrueResidual(const std::vector<double>& rhs, const std::vector<double>& x)
  {
    Product_(x, R_);
    const std::ptrdiff_t size = static_cast<std::ptrdiff_t>(R_.size());
    double* r = R_.data();
#pragma omp parallel for schedule(static) num_threads(Threads_)
    for (std::ptrdiff_t k = 0; k < size; ++k)
    {
      r[k] = rhs[static_cast<std::size_t>(k)] - r[k];
    }
    Rr_ = Dots(R_, R_);
  }

  /// Per-channel dot products on the solver's threads (ChunkedDots: the
  /// same bits for any thread count).
  std::array<double, 3> Dots(const std::vector<double>& a, const std::vector<double>& b) const
  {
    return ChunkedDots(a.data(), b.data(), a.size(), Threads_);
  }

  /// One BiCGSTAB cycle from the current residual until every channel is
  /// done (converged, failed or stagnated) or MaxIter; false if aborted.
  bool Cycle(std::vector<double>& x)
  {
    RHat_ = R_;
    std::fill(P_.begin(), P_.end(), 0.0);
    std::fill(V_.begin(), V_.end(), 0.0);
    Rho_ = { 1, 1, 1 };
    Alpha_ = { 1, 1, 1 };
    Omega_ = { 1, 1, 1 };
    for (; It_ < MaxIter_ && !AllDone(); ++It_)
    {
      if (Progress_ && !Progress_(It_))
      {
        return false;
      }
      Iterate(x);
    }
    return true;
  }

  /// Marks channel c failed (breakdown: reported as not converged) unless
  /// `value` is a usable finite non-zero divisor.
  bool Usable(int c, double value)
  {
    if (!(std::abs(value) > 0.0) || !std::isfinite(value))
    {
      Failed_[c] = Done_[c] = true;
      return false;
    }
    return true;
  }

  void Iterate(std::vector<double>& x)
  {
    const std::size_t size = x.size();
    const std::array<double, 3> rhoNew = Dots(RHat_, R_);
    std::array<double, 3> beta{};
    for (int c = 0; c < 3; ++c)
    {
      if (!Done_[c] && Usable(c, rhoNew[c]))
      {
        beta[c] = (rhoNew[c] / Rho_[c]) * (Alpha_[c] / Omega_[c]);
        Rho_[c] = rhoNew[c];
      }
    }
    const std::ptrdiff_t points = static_cast<std::ptrdiff_t>(size / 3);
    {
      const double* r = R_.data();
      const double* v = V_.data();
      double* p = P_.data();
      const std::array<bool, 3> done = Done_;
      const std::array<double, 3> omega = Omega_;
#pragma omp parallel for schedule(static) num_threads(Threads_)
      for (std::ptrdiff_t i = 0; i < points; ++i)
      {
        for (int c = 0; c < 3; ++c)
        {
          const std::size_t k = 3 * static_cast<std::size_t>(i) + c;
          p[k] = done[c] ? 0.0 : r[k] + beta[c] * (p[k] - omega[c] * v[k]);
        }
      }
    }
    Precondition_(P_, PHat_);
    Product_(PHat_, V_);
    const std::array<double, 3> rv = Dots(RHat_, V_);
    for (int c = 0; c < 3; ++c)
    {
      if (!Done_[c] && Usable(c, rv[c]))
      {
        Alpha_[c] = Rho_[c] / rv[c];
      }
    }
    {
      const double* r = R_.data();
      const double* v = V_.data();
      double* sv = S_.data();
      const std::array<bool, 3> done = Done_;
      const std::array<double, 3> alpha = Alpha_;
#pragma omp parallel for schedule(static) num_threads(Threads_)
      for (std::ptrdiff_t i = 0; i < points; ++i)
      {
        for (int c = 0; c < 3; ++c)
        {
          const std::size_t k = 3 * static_cast<std::size_t>(i) + c;
          sv[k] = done[c] ? 0.0 : r[k] - alpha[c] * v[k];
        }
      }
    }
    Precondition_(S_, SHat_);
    Product_(SHat_, T_);
    const std::array<double, 3> ts = Dots(T_, S_), tt = Dots(T_, T_);
    for (int c = 0; c < 3; ++c)
    {
      if (!Done_[c])
      {
        Omega_[c] = tt[c] > 0.0 ? ts[c] / tt[c] : 0.0;
      }
    }
    {
      const double* pHat = PHat_.data();
      const double* sHat = SHat_.data();
      const double* sv = S_.data();
      const double* tv = T_.data();
      double* xv = x.data();
      double* r = R_.data();
      const std::array<bool, 3> done = Done_;
      const std::array<double, 3> alpha = Alpha_, omega = Omega_;
#pragma omp parallel for schedule(static) num_threads(Threads_)
      for (std::ptrdiff_t i = 0; i < points; ++i)
      {
        for (int c = 0; c < 3; ++c)
        {
          const std::size_t k = 3 * static_cast<std::size_t>(i) + c;
          if (!done[c])
          {
            xv[k] += alpha[c] * pHat[k] + omega[c] * sHat[k];
            r[k] = sv[k] - omega[c] * tv[k];
          }
        }
      }
    }
    const std::array<double, 3> rrNew = Dots(R_, R_);
    for (int c = 0; c < 3; ++c)
    {
      if (Done_[c])
      {
        continue;
      }
      Rr_[c] = rrNew[c];
      ++Iterations_[c];
      if (!std::isfinite(Rr_[c]))
      {
        Failed_[c] = Done_[c] = true;
      }
      else if (Converged(c) || Omega_[c] == 0.0)
      {
        Done_[c] = true; // converged, or stagnation: restart from the true residual
      }
    }
  }

  Operator Product_, Precondition_;
  double RelTol_;
  int MaxIter_;
  int Threads_;
  std::function<bool(int)> Progress_;
  int It_ = 0;
  std::vector<double> R_, RHat_, P_, V_, PHat_, S_, SHat_, T_;
  std::array<double, 3> Bb_{}, Rr_{}, Rho_{}, Alpha_{}, Omega_{};
  std::array<bool, 3> Done_{}, Failed_{};
  std::array<int, 3> Iterations_{};
};

/**
 * Restarted GMRES(m), right-preconditioned and flexible (the preconditioned
 * vectors z_j = M^-1 v_j are kept, so x = x_0 + Z y is exact for any
 * preconditioner, e.g. a single-precision cycle; Saad, "A flexible
 * inner-outer preconditioned GMRES algorithm", SIAM J. Sci. Comput. 14(2),
 * 1993, Algorithm 2.2), for the three channels in lockstep on vectors
 * interleaved by 3: one product and one preconditioner application per
 * iteration (BiCGSTAB: two each), Gram-Schmidt (Orthogonalise below) and
 * Givens rotations per channel, each channel with its own Hessenberg matrix.
 * Not the default: its orthogonalisation reads the whole basis every
 * iteration, about one block product's memory traffic at 8 vectors, and
 * it needs as many products as BiCGSTAB here (Solvers.md, SP3 "Cost").
 * A channel stops when its least-squares residual |g_{j+1}| reaches RelTol
 * (or on a happy breakdown); every restart starts from the true residual
 * b - A x, which decides convergence. A cycle that does not reduce a
 * channel's true residual marks it failed (reported as not converged).
 */
class LockstepGmres
{
public:
  using Operator = std::function<void(const std::vector<double>&, std::vector<double>&)>;

  LockstepGmres(Operator product, Operator precondition, double relTol, int maxIter, int restart,
    int threads, std::function<bool(int)> progress)
    : Product_(std::move(product))
    , Precondition_(std::move(precondition))
    , RelTol_(relTol)
    , MaxIter_(maxIter)
    , Restart_(std::max(1, restart))
    , Threads_(std::max(1, threads))
    , Progress_(std::move(progress))
  {
  }

  /// Solves A x = rhs from x (sized as rhs); false if `progress` aborted.
  bool Solve(const std::vector<double>& rhs, std::vector<double>& x, SolverReport& report)
  {
    const std::size_t size = rhs.size();
    R_.assign(size, 0.0);
    W_.assign(size, 0.0);
    Bb_ = Dots(rhs, rhs);
    for (int c = 0; c < 3; ++c)
    {
      if (Bb_[c] == 0.0)
      {
        // No source in this channel: the solution is 0.
        for (std::size_t k = static_cast<std::size_t>(c); k < size; k += 3)
        {
          x[k] = 0.0;
        }
      }
    }
    TrueResidual(rhs, x);
    while (It_ < MaxIter_)
    {
      for (int c = 0; c < 3; ++c)
      {
        Done_[c] = Failed_[c] || Converged(c);
      }
      if (Done_[0] && Done_[1] && Done_[2])
      {
        break;
      }
      const std::array<double, 3> before = Rr_;
      if (!Cycle(x))
      {
        return false;
      }
      TrueResidual(rhs, x);
      for (int c = 0; c < 3; ++c)
      {
        // No progress over a whole cycle: stagnation (or a non-finite value).
        if (!Done_[c] && !Converged(c) && !(Rr_[c] < before[c]))
        {
          Failed_[c] = true;
        }
      }
    }
    for (int c = 0; c < 3; ++c)
    {
      report.Iterations[c] = Iterations_[c];
      report.Residual[c] = Bb_[c] > 0.0 ? std::sqrt(Rr_[c] / Bb_[c]) : std::sqrt(Rr_[c]);
      report.Converged[c] = !Failed_[c] && Converged(c);
    }
    return true;
  }

private:
  bool Converged(int c) const
  {
    return Bb_[c] == 0.0 ? Rr_[c] == 0.0 : std::sqrt(Rr_[c] / Bb_[c]) <= RelTol_;
  }

  void TrueResidual(const std::vector<double>& rhs, const std::vector<double>& x)
  {
    Product_(x, R_);
    for (std::size_t k = 0; k < R_.size(); ++k)
    {
      R_[k] = rhs[k] - R_[k];
    }
    Rr_ = Dots(R_, R_);
  }

  /// The basis vector v_j (allocated on first use: memory grows with the
  /// iterations a cycle needs, at most Restart_ + 1 vectors of V and
  /// Restart_ of Z).
  static std::vector<double>& Vector(std::vector<std::vector<double>>& set, int j, std::size_t size)
  {
    if (static_cast<int>(set.size()) <= j)
    {
      set.resize(static_cast<std::size_t>(j) + 1);
    }
    set[static_cast<std::size_t>(j)].resize(size);
    return set[static_cast<std::size_t>(j)];
  }

  /// The per-channel dots (v_i, w) for i < count, in one pass over the
  /// basis (fixed chunks summed in order: independent of the thread count).
  std::vector<std::array<double, 3>> Project(int count) const
  {
    const std::size_t size = W_.size();
    constexpr std::size_t chunk = 3 * 2048;
    const std::size_t chunks = (size + chunk - 1) / chunk;
    const std::size_t width = 3 * static_cast<std::size_t>(count);
    std::vector<double> partial(chunks * width, 0.0);
    const double* w = W_.data();
#pragma omp parallel for schedule(static) num_threads(Threads_)
    for (std::ptrdiff_t q = 0; q < static_cast<std::ptrdiff_t>(chunks); ++q)
    {
      const std::size_t begin = static_cast<std::size_t>(q) * chunk;
      const std::size_t end = std::min(size, begin + chunk);
      double* out = partial.data() + static_cast<std::size_t>(q) * width;
      for (int i = 0; i < count; ++i)
      {
        const double* v = V_[static_cast<std::size_t>(i)].data();
        double d0 = 0.0, d1 = 0.0, d2 = 0.0;
        for (std::size_t k = begin; k < end; k += 3)
        {
          d0 += v[k] * w[k];
          d1 += v[k + 1] * w[k + 1];
          d2 += v[k + 2] * w[k + 2];
        }
        out[3 * i] = d0;
        out[3 * i + 1] = d1;
        out[3 * i + 2] = d2;
      }
    }
    std::vector<std::array<double, 3>> d(static_cast<std::size_t>(count), { 0.0, 0.0, 0.0 });
    for (std::size_t q = 0; q < chunks; ++q)
    {
      for (int i = 0; i < count; ++i)
      {
        for (int c = 0; c < 3; ++c)
        {
          d[static_cast<std::size_t>(i)][c] += partial[q * width + 3 * static_cast<std::size_t>(i) + c];
        }
      }
    }
    return d;
  }

  /// w -= sum_i d_i v_i per channel, in one pass; returns |w|^2 per channel
  /// (chunked as Project).
  std::array<double, 3> Subtract(const std::vector<std::array<double, 3>>& d)
  {
    const std::size_t size = W_.size();
    constexpr std::size_t chunk = 3 * 2048;
    const std::size_t chunks = (size + chunk - 1) / chunk;
    const int count = static_cast<int>(d.size());
    std::vector<std::array<double, 3>> partial(chunks);
    double* w = W_.data();
#pragma omp parallel for schedule(static) num_threads(Threads_)
    for (std::ptrdiff_t q = 0; q < static_cast<std::ptrdiff_t>(chunks); ++q)
    {
      const std::size_t begin = static_cast<std::size_t>(q) * chunk;
      const std::size_t end = std::min(size, begin + chunk);
      for (int i = 0; i < count; ++i)
      {
        const double* v = V_[static_cast<std::size_t>(i)].data();
        const std::array<double, 3>& s = d[static_cast<std::size_t>(i)];
        for (std::size_t k = begin; k < end; k += 3)
        {
          w[k] -= s[0] * v[k];
          w[k + 1] -= s[1] * v[k + 1];
          w[k + 2] -= s[2] * v[k + 2];
        }
      }
      double n0 = 0.0, n1 = 0.0, n2 = 0.0;
      for (std::size_t k = begin; k < end; k += 3)
      {
        n0 += w[k] * w[k];
        n1 += w[k + 1] * w[k + 1];
        n2 += w[k + 2] * w[k + 2];
      }
      partial[static_cast<std::size_t>(q)] = { n0, n1, n2 };
    }
    return SumPartials(partial);
  }

  /// One GMRES(m) cycle from the current residual R_; x gets the
  /// correction Z y of every channel that took part. False if aborted.
  bool Cycle(std::vector<double>& x)
  {
    const std::size_t size = x.size();
    const int m = Restart_;
    std::array<bool, 3> active{};
    std::array<int, 3> steps{};
    for (int c = 0; c < 3; ++c)
    {
      active[c] = !Done_[c];
      H_[c].assign(static_cast<std::size_t>((m + 1) * m), 0.0);
      G_[c].assign(static_cast<std::size_t>(m + 1), 0.0);
      Cs_[c].assign(static_cast<std::size_t>(m), 0.0);
      Sn_[c].assign(static_cast<std::size_t>(m), 0.0);
      G_[c][0] = std::sqrt(Rr_[c]);
    }
    {
      std::vector<double>& v0 = Vector(V_, 0, size);
      for (std::size_t k = 0; k < size; ++k)
      {
        const int c = static_cast<int>(k % 3);
        v0[k] = active[c] ? R_[k] / G_[c][0] : 0.0;
      }
    }
    auto h = [m](std::vector<double>& hc, int i, int j) -> double& {
      return hc[static_cast<std::size_t>(i * m + j)];
    };
    for (int j = 0; j < m && It_ < MaxIter_ && (active[0] || active[1] || active[2]); ++j, ++It_)
    {
      if (Progress_ && !Progress_(It_))
      {
        return false;
      }
      std::vector<double>& z = Vector(Z_, j, size);
      Precondition_(V_[static_cast<std::size_t>(j)], z);
      Product_(z, W_);
      // Classical Gram-Schmidt against v_0..v_j, per channel, repeated
      // once when it cancelled more than 1 - 1/sqrt(2) of w's norm (the
      // DGKS criterion: Daniel, Gragg, Kaufman and Stewart, Math. Comp.
      // 30(136), 1976): two passes over the basis per round, so two
      // parallel regions where modified Gram-Schmidt needs 2 (j + 1)
      // (each costs a wait for both threads on a loaded machine).
      std::array<double, 3> ww = ChunkedDots(W_.data(), W_.data(), size, Threads_);
      for (int round = 0; round < 2; ++round)
      {
        const std::array<double, 3> before = ww;
        std::vector<std::array<double, 3>> d = Project(j + 1);
        ww = Subtract(d);
        bool again = false;
        for (int c = 0; c < 3; ++c)
        {
          for (int i = 0; i <= j; ++i)
          {
            h(H_[c], i, j) = (round == 0 ? 0.0 : h(H_[c], i, j)) + (active[c] ? d[i][c] : 0.0);
          }
          again = again || (active[c] && ww[c] < 0.5 * before[c]);
        }
        if (!again)
        {
          break;
        }
      }
      std::array<double, 3> norm{};
      for (int c = 0; c < 3; ++c)
      {
        if (!active[c])
        {
          continue;
        }
        norm[c] = std::sqrt(ww[c]);
        std::vector<double>& hc = H_[c];
        // The earlier rotations on the new column, then the one that zeroes
        // its subdiagonal entry.
        for (int i = 0; i < j; ++i)
        {
          const double a = h(hc, i, j), b = h(hc, i + 1, j);
          h(hc, i, j) = Cs_[c][i] * a + Sn_[c][i] * b;
          h(hc, i + 1, j) = -Sn_[c][i] * a + Cs_[c][i] * b;
        }
        const double a = h(hc, j, j), b = norm[c];
        const double r = std::hypot(a, b);
        steps[c] = j + 1;
        ++Iterations_[c];
        if (!std::isfinite(r) || !(r > 0.0))
        {
          // A singular or non-finite step: this channel fails.
          Failed_[c] = true;
          active[c] = false;
          steps[c] = j; // column j is not usable
          continue;
        }
        Cs_[c][j] = a / r;
        Sn_[c][j] = b / r;
        h(hc, j, j) = r;
        h(hc, j + 1, j) = 0.0;
        G_[c][j + 1] = -Sn_[c][j] * G_[c][j];
        G_[c][j] = Cs_[c][j] * G_[c][j];
        const double estimate = std::abs(G_[c][j + 1]);
        if (!(norm[c] > 0.0) || estimate <= RelTol_ * std::sqrt(Bb_[c]))
        {
          active[c] = false; // converged in the least-squares sense, or a happy breakdown
        }
      }
      if (j + 1 < m)
      {
        std::vector<double>& next = Vector(V_, j + 1, size);
        std::array<double, 3> scale{};
        for (int c = 0; c < 3; ++c)
        {
          scale[c] = active[c] ? 1.0 / norm[c] : 0.0;
        }
        const double* w = W_.data();
        double* out = next.data();
#pragma omp parallel for schedule(static) num_threads(Threads_)
        for (std::ptrdiff_t k = 0; k < static_cast<std::ptrdiff_t>(size); k += 3)
        {
          out[k] = scale[0] * w[k];
          out[k + 1] = scale[1] * w[k + 1];
          out[k + 2] = scale[2] * w[k + 2];
        }
      }
    }
    // x += Z y, y from the triangular system H y = g of each channel.
    std::array<std::vector<double>, 3> y;
    for (int c = 0; c < 3; ++c)
    {
      const int k = steps[c];
      y[c].assign(static_cast<std::size_t>(m), 0.0);
      for (int i = k - 1; i >= 0; --i)
      {
        double s = G_[c][i];
        for (int l = i + 1; l < k; ++l)
        {
          s -= h(H_[c], i, l) * y[c][l];
        }
        y[c][i] = s / h(H_[c], i, i);
      }
    }
    const int used = std::max({ steps[0], steps[1], steps[2] });
    for (int i = 0; i < used; ++i)
    {
      std::array<double, 3> s{};
      for (int c = 0; c < 3; ++c)
      {
        s[c] = i < steps[c] ? y[c][static_cast<std::size_t>(i)] : 0.0;
      }
      ChannelAxpy(s, Z_[static_cast<std::size_t>(i)].data(), x.data(), size, Threads_);
    }
    return true;
  }

  Operator Product_, Precondition_;
  double RelTol_;
  int MaxIter_;
  int Restart_;
  int Threads_;
  std::function<bool(int)> Progress_;
  int It_ = 0;
  std::vector<double> R_, W_;
  std::vector<std::vector<double>> V_, Z_;
  std::array<std::vector<double>, 3> H_, G_, Cs_, Sn_;
  std::array<double, 3> Bb_{}, Rr_{};
  std::array<bool, 3> Done_{}, Failed_{};
  std::array<int, 3> Iterations_{};
};

} // namespace

const char* Sp3Solver::SetUpPreconditioner(const TetMesh& mesh, const std::string& preconditioner)
{
  Blocks& b = *Blocks_;
  b.Multigrid = preconditioner == "multigrid-agg";
  if (b.Multigrid)
  {
    if (!b.Cycle1 || !b.Cycle2)
    {
      b.Cycle1 = std::make_unique<AggregationMultigridSolver>();
      b.Cycle2 = std::make_unique<AggregationMultigridSolver>();
      b.CyclesReady = false;
    }
    const bool setUp = b.CyclesSetUp;
    b.CyclesSetUp = false; // until the set-up below succeeds
    const char* done = "kept";
    if (!b.CyclesReady)
    {
      done = "rebuilt";
      // The first time on this mesh: one aggregation hierarchy for both
      // blocks (it reads only the pattern, which A11 and A22 share, and the
      // points), the values of each.
      b.Cycle1->Setup(b.A11, &mesh, true);
      b.Cycle2->SetupSharedHierarchy(*b.Cycle1, b.A22, &mesh);
    }
    else if (!setUp)
    {
      // New values (a full assembly), the same pattern: values only.
      b.Cycle1->Setup(b.A11, &mesh, false);
      b.Cycle2->Setup(b.A22, &mesh, false);
      done = "values";
    }
    // Otherwise the blocks did not change (only the right-hand sides:
    // Assemble): the set-up is kept.
    b.CyclesReady = true;
    b.CyclesSetUp = true;
    return done;
  }
  const int n = mesh.GetNumberOfPoints();
  const std::size_t half = 3 * static_cast<std::size_t>(n);
  b.InverseDiagonal.resize(2 * half);
  const int* diagonal = mesh.GetDiagonalPositions().data();
  for (int i = 0; i < n; ++i)
  {
    for (int c = 0; c < 3; ++c)
    {
      b.InverseDiagonal[3 * static_cast<std::size_t>(i) + c] = 1.0 / b.A11.Values[c][diagonal[i]];
      b.InverseDiagonal[half + 3 * static_cast<std::size_t>(i) + c] =
        1.0 / b.A22.Values[c][diagonal[i]];
    }
  }
  return "values";
}

bool Sp3Solver::SolveBlocks(
  const TetMesh& mesh, const std::string& preconditioner, std::vector<double>& x, SolverReport& report)
{
  Blocks& b = *Blocks_;
  const int n = mesh.GetNumberOfPoints();
  const std::size_t half = 3 * static_cast<std::size_t>(n), block = 2 * half;
  const bool complex = !b.B11[0].empty();
  // Complex: the real form [[A, -B], [B, A]] of (A + i B) on the unknowns
  // (Re phi_1, Re phi_2, Im phi_1, Im phi_2).
  const std::size_t size = complex ? 2 * block : block;
  const int numThreads = NumberOfThreads_ > 0 ? NumberOfThreads_ : omp_get_max_threads();
  report.LinearSetup = SetUpPreconditioner(mesh, preconditioner);

  BlockValues real{}, imaginary{};
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    real.V11[c] = b.A11.Values[c].data();
    real.V12[c] = b.A12[c].data();
    real.V21[c] = b.A21[c].data();
    real.V22[c] = b.A22.Values[c].data();
    if (complex)
    {
      imaginary.V11[c] = b.B11[c].data();
      imaginary.V12[c] = b.B12[c].data();
      imaginary.V21[c] = b.B21[c].data();
      imaginary.V22[c] = b.B22[c].data();
    }
  }
  const int* rows = b.A11.RowOffsets.data();
  const int* cols = b.A11.ColumnIndices.data();
  // The rows where A21 differs from A12: only boundary rows can (the
  // Fresnel coupling F21 != F12 of the boundary mass); the others share A12.
  b.OwnA21.assign(static_cast<std::size_t>(n), 0);
  for (const int i : mesh.GetBoundaryPoints())
  {
    for (int k = rows[i]; k < rows[i + 1] && !b.OwnA21[static_cast<std::size_t>(i)]; ++k)
    {
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        if (b.A21[c][k] != b.A12[c][k])
        {
          b.OwnA21[static_cast<std::size_t>(i)] = 1;
        }
      }
    }
  }
  auto product = [&](const std::vector<double>& in, std::vector<double>& out) {
#pragma omp parallel num_threads(numThreads)
    {
      if (complex)
      {
        ComplexBlockProduct(n, rows, cols, real, imaginary, in.data(), out.data());
      }
      else
      {
        BlockProduct(n, rows, cols, real, b.OwnA21.data(), in.data(), out.data());
      }
    }
  };
  auto precondition = [&](const std::vector<double>& r, std::vector<double>& z) {
    // The block diagonal of the real part, on the real and imaginary parts alike.
    for (std::size_t offset = 0; offset < size; offset += block)
    {
      if (b.Multigrid && numThreads == 2)
      {
        // Two threads: one cycle each, concurrently, in place of both
        // threads meeting at every loop of each cycle in turn. Each
        // cycle's loops then run on its one thread; multigrid-agg's
        // results do not depend on the number of threads, so the bits are
        // those of the cycles one after the other.
        std::exception_ptr error[2];
        AggregationMultigridSolver* cycles[2] = { b.Cycle1.get(), b.Cycle2.get() };
#pragma omp parallel for schedule(static, 1) num_threads(2)
        for (int k = 0; k < 2; ++k)
        {
          try
          {
            omp_set_num_threads(1);
            cycles[k]->ApplyPreconditioner(r.data() + offset + k * half, z.data() + offset + k * half);
          }
          catch (...)
          {
            error[k] = std::current_exception();
          }
        }
        for (const std::exception_ptr& e : error)
        {
          if (e)
          {
            std::rethrow_exception(e);
          }
        }
      }
      else if (b.Multigrid)
      {
        b.Cycle1->ApplyPreconditioner(r.data() + offset, z.data() + offset);
        b.Cycle2->ApplyPreconditioner(r.data() + offset + half, z.data() + offset + half);
      }
      else
      {
        for (std::size_t k = 0; k < block; ++k)
        {
          z[offset + k] = b.InverseDiagonal[k] * r[offset + k];
        }
      }
    }
  };

  std::vector<double> rhs(size, 0.0);
  for (int i = 0; i < n; ++i)
  {
    for (int c = 0; c < 3; ++c)
    {
      const std::size_t k = 3 * static_cast<std::size_t>(i) + c;
      rhs[k] = b.A11.RightHandSide[c][i];
      rhs[half + k] = b.A22.RightHandSide[c][i];
      if (complex)
      {
        rhs[block + k] = b.ImaginaryRhs1[c][i];
        rhs[block + half + k] = b.ImaginaryRhs2[c][i];
      }
    }
  }
  const bool zeroStart = x.size() != size;
  if (zeroStart)
  {
    x.assign(size, 0.0);
  }
  auto progress = [this](int it) {
    return ReportProgress(static_cast<double>(it) / std::max(1, MaxIter_));
  };
  if (ChooseKrylov(preconditioner) == "gmres")
  {
    LockstepGmres solver(
      product, precondition, RelTol_, MaxIter_, GmresRestart_, numThreads, progress);
    return solver.Solve(rhs, x, report);
  }
  LockstepBiCgStab solver(product, precondition, RelTol_, MaxIter_, numThreads, progress);
  return solver.Solve(rhs, x, report, zeroStart);
}

void Sp3Solver::ComputeExitance(const DiffusionProblem& problem,
  const std::vector<double>& imaginaryPhi1, const std::vector<double>& imaginaryPhi2)
{
  const TetMesh& mesh = *problem.Mesh;
  const OpticalProperties& material = *problem.Material;
  const std::vector<double>& q = *problem.Irradiance;
  const int n = mesh.GetNumberOfPoints();
  const bool complex = !imaginaryPhi1.empty();
  // Area-weighted mean eta of the boundary triangles at each point.
  std::vector<double> area(static_cast<std::size_t>(n), 0.0), etaSum(area.size(), 0.0);
  const std::vector<int>& triangles = mesh.GetBoundaryTriangles();
  const std::vector<int>& triangleTets = mesh.GetBoundaryTriangleTets();
  const std::vector<double>& areas = mesh.GetBoundaryTriangleAreas();
  for (std::size_t f = 0; f < triangleTets.size(); ++f)
  {
    const double eta = material.RefractiveIndex[static_cast<std::size_t>(triangleTets[f])];
    for (int i = 0; i < 3; ++i)
    {
      const std::size_t p = static_cast<std::size_t>(triangles[3 * f + i]);
      area[p] += areas[f];
      etaSum[p] += areas[f] * eta;
    }
  }
  Exitance_.assign(3 * static_cast<std::size_t>(n), 0.0);
  ComplexExitance_.assign(complex ? Exitance_.size() : 0, 0.0);
  double lastEta = -1.0;
  Sp3BoundaryCoefficients k;
  for (int i = 0; i < n; ++i)
  {
    if (!(area[static_cast<std::size_t>(i)] > 0.0))
    {
      continue;
    }
    const double eta = etaSum[static_cast<std::size_t>(i)] / area[static_cast<std::size_t>(i)];
    if (eta != lastEta)
    {
      k = Sp3BoundaryCoefficients::Compute(eta);
      lastEta = eta;
    }
    for (int c = 0; c < 3; ++c)
    {
      const std::size_t m = 3 * static_cast<std::size_t>(i) + c;
      const double re = k.E1 * Phi1_[m] + k.E2 * Phi2_[m] + k.E3 * q[m];
      if (complex)
      {
        // q is modulated at phase 0: it adds to the real part only.
        ComplexExitance_[m] = { re, k.E1 * imaginaryPhi1[m] + k.E2 * imaginaryPhi2[m] };
        Exitance_[m] = std::abs(ComplexExitance_[m]);
      }
      else
      {
        Exitance_[m] = re;
      }
    }
  }
}

namespace
{

/// A pencil beam's first-collision source as point sources along the
/// refracted beam (ComputeSp3SourceLoad), each with the optical path eta s
/// (mm) the beam travelled to it.
struct BeamSegment
{
  PointSource Source;
  double OpticalPath = 0.0;
};

std::vector<BeamSegment> PencilSegments(
  const TetMesh& mesh, const OpticalProperties& material, const Sources& sources)
{
  std::vector<BeamSegment> segments;
  const std::vector<PencilBeam>& beams = sources.GetPencilBeams();
  if (beams.empty())
  {
    return segments;
  }
  material.Validate(mesh.GetNumberOfTets());
  TetLocator locator;
  locator.Build(mesh);
  const double tolerance = SurfaceTolerance(mesh);
  for (std::size_t b = 0; b < beams.size(); ++b)
  {
    const PencilBeam& beam = beams[b];
    const std::string name =
      beam.Label.empty() ? "pencil beam " + std::to_string(b + 1) : beam.Label;
    const PencilEntry entry = LocatePencilEntry(mesh, material, beam, name, tolerance);
    const std::size_t t = static_cast<std::size_t>(entry.Tet);
    const double eta = material.RefractiveIndex[t];
    double muT[NumberOfChannels], albedo[NumberOfChannels];
    double muTMax = 0.0, muTMin = 1e300;
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      muT[c] = material.AbsorptionCoefficient[3 * t + c] +
        material.ReducedScatteringCoefficient[3 * t + c];
      albedo[c] = material.ReducedScatteringCoefficient[3 * t + c] / muT[c];
      muTMax = std::max(muTMax, muT[c]);
      muTMin = std::min(muTMin, muT[c]);
    }
    // Segments of a tenth of the shortest mean free path, to 12 of the
    // longest (the beam is down to exp(-12) there); each segment's exact
    // power at its midpoint.
    const double step = 0.1 / muTMax;
    const int count = static_cast<int>(std::min(20000.0, std::ceil(12.0 / muTMin / step)));
    for (int k = 0; k < count; ++k)
    {
      const double s0 = k * step, s1 = s0 + step, middle = 0.5 * (s0 + s1);
      BeamSegment segment;
      PointSource& point = segment.Source;
      for (int i = 0; i < 3; ++i)
      {
        point.Position[i] = entry.Surface.Position[i] + middle * entry.Refracted[i];
      }
      if (locator.Locate(point.Position.data()) < 0)
      {
        break; // the beam left the object (what is left of it is transmitted)
      }
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        point.Power[c] = entry.Transmitted * beam.Power[c] * albedo[c] *
          (std::exp(-muT[c] * s0) - std::exp(-muT[c] * s1));
      }
      point.Label = name;
      segment.OpticalPath = eta * middle;
      segments.push_back(segment);
    }
  }
  return segments;
}

} // namespace

std::vector<double> ComputeSp3SourceLoad(
  const TetMesh& mesh, const OpticalProperties& material, const Sources& sources)
{
  std::vector<double> imaginary;
  return ComputeSp3SourceLoad(mesh, material, sources, 0.0, imaginary);
}

std::vector<double> ComputeSp3SourceLoad(const TetMesh& mesh, const OpticalProperties& material,
  const Sources& sources, double wavenumber, std::vector<double>& imaginary)
{
  sources.Validate();
  imaginary.clear();
  Sources points;
  for (const PointSource& point : sources.GetPointSources())
  {
    points.AddPointSource(point);
  }
  const std::vector<BeamSegment> segments = PencilSegments(mesh, material, sources);
  if (wavenumber == 0.0)
  {
    for (const BeamSegment& segment : segments)
    {
      points.AddPointSource(segment.Source);
    }
    return points.ComputeLoad(mesh, material);
  }
  // Modulated: each segment carries the beam's delay, power P exp(-i k eta
  // s); the point sources' powers must be >= 0, so the real and imaginary
  // parts are placed by sign: Re = (+) - (-), Im likewise.
  Sources parts[4]; // Re+, Re-, Im+, Im-
  for (const BeamSegment& segment : segments)
  {
    const double phase = -wavenumber * segment.OpticalPath;
    const double factors[2] = { std::cos(phase), std::sin(phase) };
    for (int part = 0; part < 2; ++part)
    {
      PointSource plus = segment.Source, minus = segment.Source;
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        const double value = factors[part] * segment.Source.Power[c];
        plus.Power[c] = std::max(0.0, value);
        minus.Power[c] = std::max(0.0, -value);
      }
      parts[2 * part].AddPointSource(plus);
      parts[2 * part + 1].AddPointSource(minus);
    }
  }
  std::vector<double> real = points.ComputeLoad(mesh, material);
  imaginary.assign(real.size(), 0.0);
  for (int part = 0; part < 4; ++part)
  {
    if (parts[part].GetPointSources().empty())
    {
      continue;
    }
    const std::vector<double> load = parts[part].ComputeLoad(mesh, material);
    std::vector<double>& target = part < 2 ? real : imaginary;
    const double sign = part % 2 == 0 ? 1.0 : -1.0;
    for (std::size_t k = 0; k < load.size(); ++k)
    {
      target[k] += sign * load[k];
    }
  }
  return real;
}

DiffusionProblem Sp3Solver::PrepareProblem(
  const DiffusionProblem& given, OpticalProperties& withAnisotropy)
{
  if (!given.Mesh || !given.Material || !given.Irradiance)
  {
    throw Error("sp3: the problem needs a mesh, a material and an irradiance");
  }
  // The option's g on every tet when the material carries none.
  DiffusionProblem problem = given;
  if (Anisotropy_ != 0.0 && given.Material->Anisotropy.empty())
  {
    withAnisotropy = *given.Material;
    withAnisotropy.Anisotropy.assign(withAnisotropy.AbsorptionCoefficient.size(), Anisotropy_);
    problem.Material = &withAnisotropy;
  }
  const TetMesh& mesh = *problem.Mesh;
  if (mesh.GetNumberOfTets() == 0)
  {
    throw Error("sp3: the mesh has no tetrahedra");
  }
  CheckAssemblySizes(mesh, *problem.Material, *problem.Irradiance);
  problem.Material->Validate(mesh.GetNumberOfTets());
  const bool sameMesh = LastMesh_ == &mesh && LastPoints_ == mesh.GetNumberOfPoints() &&
    LastTets_ == mesh.GetNumberOfTets() && LastRevision_ == mesh.GetGeometryRevision();
  if (!sameMesh)
  {
    Reset();
  }
  return problem;
}

std::string Sp3Solver::ChoosePreconditioner(const TetMesh& mesh) const
{
  const std::string requested = ToLower(LinearSolver_);
  if (requested.empty())
  {
    return mesh.GetNumberOfPoints() < VertexDiffusionSolver::LargeSystemUnknowns
      ? "jacobi"
      : "multigrid-agg";
  }
  // The names it accepts are its registry entry's (DiffusionSolverTraits::
  // LinearSolvers: bicgstab, multigrid-agg), each mapped here by its traits
  // (LinearSolverTraits) to the block preconditioner of SP3's BiCGSTAB:
  // BiCGSTAB with the diagonal, or one aggregation multigrid cycle per block.
  // "jacobi" is the core's short name of the first.
  if (requested == "jacobi")
  {
    return "jacobi";
  }
  if (const auto* entry = GetLinearSolverRegistry().Find(ResolveLinearSolverName(requested)))
  {
    const LinearSolverTraits& traits = entry->Properties;
    if (traits.Krylov == "bicgstab" && traits.Preconditioner == "jacobi")
    {
      return "jacobi";
    }
    if (traits.Preconditioner == "aggregation")
    {
      return "multigrid-agg";
    }
  }
  throw Error("sp3: linear solver '" + LinearSolver_ +
    "' is not available for the SP3 block system: its BiCGSTAB takes the diagonal "
    "(\"bicgstab\") or an aggregation multigrid cycle (\"multigrid-agg\") as preconditioner; "
    "\"\" chooses by size");
}

void Sp3Solver::SetKrylovMethod(const std::string& name)
{
  const std::string lower = ToLower(name);
  if (!lower.empty() && lower != "gmres" && lower != "bicgstab")
  {
    throw Error("sp3: Krylov method '" + name +
      "' is not available for the SP3 block system: \"gmres\", \"bicgstab\", or \"\" "
      "(by preconditioner)");
  }
  Krylov_ = lower;
}

void Sp3Solver::SetGmresRestart(int m)
{
  if (m < 1 || m > 1000)
  {
    throw Error("sp3: GMRES restart length " + std::to_string(m) + " (expected 1 to 1000)");
  }
  GmresRestart_ = m;
}

std::string Sp3Solver::ChooseKrylov(const std::string& preconditioner) const
{
  if (!Krylov_.empty())
  {
    return Krylov_;
  }
  return "bicgstab";
}

void Sp3Solver::FillReport(const TetMesh& mesh, SolverReport& report) const
{
  const std::size_t half = 3 * static_cast<std::size_t>(mesh.GetNumberOfPoints());
  report.NumberOfUnknowns = 2LL * mesh.GetNumberOfPoints();
  report.NumberOfNonZeros = 4LL * static_cast<long long>(Blocks_->A11.ColumnIndices.size());
  report.MemoryBytes = Blocks_->A11.GetMemoryBytes() + Blocks_->A22.GetMemoryBytes() +
    2 * NumberOfChannels * Blocks_->A11.ColumnIndices.size() * sizeof(double) +
    9 * 2 * half * sizeof(double) +
    // the kept material (Blocks::AssembledMaterial)
    (Blocks_->AssembledMaterial.AbsorptionCoefficient.capacity() +
      Blocks_->AssembledMaterial.ReducedScatteringCoefficient.capacity() +
      Blocks_->AssembledMaterial.RefractiveIndex.capacity() +
      Blocks_->AssembledMaterial.Anisotropy.capacity()) *
      sizeof(double) +
    (Blocks_->Cycle1 ? Blocks_->Cycle1->GetMemoryBytes() + Blocks_->Cycle2->GetMemoryBytes() : 0);
}

bool Sp3Solver::Solve(
  const DiffusionProblem& given, std::vector<double>& fluence, SolverReport& report)
{
  OpticalProperties withAnisotropy;
  const DiffusionProblem problem = PrepareProblem(given, withAnisotropy);
  const TetMesh& mesh = *problem.Mesh;
  const bool sameMesh = LastMesh_ == &mesh;
  report = SolverReport();
  report.Solver = GetName();
  report.Assembly = "full";
  const std::string preconditioner = ChoosePreconditioner(mesh);
  report.LinearSolver = ChooseKrylov(preconditioner) + "-block-" + preconditioner;

  auto start = Clock::now();
  std::vector<double> sourceLoad;
  SourcePower_ = {};
  if (problem.HasInteriorSources())
  {
    sourceLoad = ComputeSp3SourceLoad(mesh, *problem.Material, *problem.InteriorSources);
    for (std::size_t k = 0; k < sourceLoad.size(); ++k)
    {
      SourcePower_[k % 3] += sourceLoad[k];
    }
  }
  // The extended collimated models: the reduced beam's isotropic volume
  // source mu_s' E_c (CollimatedSource.h) is Q; the SP3 boundary
  // conditions stay those of Sp3BoundaryCoefficients for either model.
  const bool extended = IsExtendedCollimatedModel(problem.Collimated);
  CollimatedSource collimated;
  if (extended)
  {
    collimated =
      ComputeCollimatedSource(mesh, *problem.Material, problem.Lights, problem.Shadows);
    sourceLoad.resize(collimated.Load.size(), 0.0);
    for (std::size_t k = 0; k < sourceLoad.size(); ++k)
    {
      sourceLoad[k] += collimated.Load[k];
    }
  }
  report.Assembly = Assemble(problem, sourceLoad, {}, 0.0) ? "full" : "right-hand side";
  report.SetupMilliseconds = MillisecondsSince(start);

  start = Clock::now();
  if (!(WarmStart_ && sameMesh))
  {
    X_.clear();
  }
  if (!SolveBlocks(mesh, preconditioner, X_, report))
  {
    Reset();
    return false;
  }
  report.SolveMilliseconds = MillisecondsSince(start);
  LastMesh_ = &mesh;
  LastPoints_ = mesh.GetNumberOfPoints();
  LastTets_ = mesh.GetNumberOfTets();
  LastRevision_ = mesh.GetGeometryRevision();
  FillReport(mesh, report);

  const std::size_t half = 3 * static_cast<std::size_t>(mesh.GetNumberOfPoints());
  Phi1_.assign(X_.begin(), X_.begin() + static_cast<std::ptrdiff_t>(half));
  Phi2_.assign(X_.begin() + static_cast<std::ptrdiff_t>(half), X_.end());
  fluence.resize(half);
  for (std::size_t k = 0; k < half; ++k)
  {
    // phi_0 = phi_1 - (2/3) phi_2 (Klose & Larsen 2006, the composite
    // moments phi_1 = phi_0 + 2 phi_2, phi_2 := 3 phi_2).
    fluence[k] = Phi1_[k] - (2.0 / 3.0) * Phi2_[k];
  }
  ComputeExitance(problem, {}, {});
  if (extended)
  {
    AddCollimatedFluence(collimated, fluence, report);
  }
  return true;
}

bool Sp3Solver::SolveFrequencyDomain(const DiffusionProblem& given, double frequency,
  std::vector<std::complex<double>>& fluence, SolverReport& report)
{
  if (!std::isfinite(frequency) || !(frequency > 0.0))
  {
    std::ostringstream out;
    out << "sp3: modulation frequency " << frequency
        << " Hz (expected a finite value > 0; 0 is the continuous-wave Solve())";
    throw Error(out.str());
  }
  OpticalProperties withAnisotropy;
  const DiffusionProblem problem = PrepareProblem(given, withAnisotropy);
  const TetMesh& mesh = *problem.Mesh;
  const double omega = 2.0 * 3.14159265358979323846 * frequency;
  CheckFrequencyResolution(GetName(), mesh, *problem.Material, frequency, omega);
  report = SolverReport();
  report.Solver = GetName();
  report.Assembly = "full";
  const std::string preconditioner = ChoosePreconditioner(mesh);
  report.LinearSolver = ChooseKrylov(preconditioner) + "-block-" + preconditioner;

  auto start = Clock::now();
  const double wavenumber = omega / SpeedOfLight; // rad per mm of optical path
  std::vector<double> sourceLoad, imaginaryLoad;
  SourcePower_ = {};
  if (problem.HasInteriorSources())
  {
    sourceLoad = ComputeSp3SourceLoad(
      mesh, *problem.Material, *problem.InteriorSources, wavenumber, imaginaryLoad);
    const std::vector<double> unmodulated =
      ComputeSp3SourceLoad(mesh, *problem.Material, *problem.InteriorSources);
    for (std::size_t k = 0; k < unmodulated.size(); ++k)
    {
      SourcePower_[k % 3] += unmodulated[k];
    }
  }
  // The extended collimated models: the beam's volume source carries its
  // own modulation exp(-i k eta s) (ComputeCollimatedFrequencyLoad).
  const bool extended = IsExtendedCollimatedModel(problem.Collimated);
  std::vector<std::complex<double>> collimatedFluence;
  CollimatedSource collimated;
  if (extended)
  {
    collimated =
      ComputeCollimatedSource(mesh, *problem.Material, problem.Lights, problem.Shadows);
    std::vector<std::complex<double>> load;
    ComputeCollimatedFrequencyLoad(
      mesh, *problem.Material, collimated, wavenumber, load, collimatedFluence);
    sourceLoad.resize(load.size(), 0.0);
    imaginaryLoad.resize(load.size(), 0.0);
    for (std::size_t k = 0; k < load.size(); ++k)
    {
      sourceLoad[k] += load[k].real();
      imaginaryLoad[k] += load[k].imag();
    }
  }
  Assemble(problem, sourceLoad, imaginaryLoad, omega);
  report.SetupMilliseconds = MillisecondsSince(start);

  start = Clock::now();
  std::vector<double> x; // no warm start: the continuous-wave solution is kept
  const bool solved = SolveBlocks(mesh, preconditioner, x, report);
  // The cycles now hold the modulated blocks' real parts: the next solve
  // sets their values up again (SetUpPreconditioner), the hierarchy stays.
  if (!solved)
  {
    Reset();
    return false;
  }
  report.SolveMilliseconds = MillisecondsSince(start);
  FillReport(mesh, report);

  const std::size_t half = 3 * static_cast<std::size_t>(mesh.GetNumberOfPoints());
  const std::size_t block = 2 * half;
  Phi1_.assign(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(half));
  Phi2_.assign(x.begin() + static_cast<std::ptrdiff_t>(half),
    x.begin() + static_cast<std::ptrdiff_t>(block));
  const std::vector<double> imaginaryPhi1(x.begin() + static_cast<std::ptrdiff_t>(block),
    x.begin() + static_cast<std::ptrdiff_t>(block + half));
  const std::vector<double> imaginaryPhi2(
    x.begin() + static_cast<std::ptrdiff_t>(block + half), x.end());
  fluence.resize(half);
  for (std::size_t k = 0; k < half; ++k)
  {
    // phi_0 = phi_1 - (2/3) phi_2, in real and imaginary parts.
    fluence[k] = { Phi1_[k] - (2.0 / 3.0) * Phi2_[k],
      imaginaryPhi1[k] - (2.0 / 3.0) * imaginaryPhi2[k] };
  }
  ComputeExitance(problem, imaginaryPhi1, imaginaryPhi2);
  // The CW-only members now describe the modulated solve: no warm start
  // from it (X_ untouched), and Phi1_/Phi2_ hold the real parts.
  if (extended)
  {
    AddCollimatedFluence(collimated, collimatedFluence, fluence, report);
  }
  return true;
}

} // namespace translucency
