#include "Sp3Solver.h"

#include "Error.h"
#include "Fresnel.h"
#include "Strings.h"
#include "TetMesh.h"
#include "TetLocator.h"
#include "Timer.h"
#include "VertexAssembly.h"
#include "VertexDiffusionSolver.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
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

/// The assembled blocks: A11 and A22 as systems (the multigrid cycles are
/// set up on them), A12 and A21 on the same pattern.
struct Sp3Solver::Blocks
{
  DiffusionSystem A11, A22;
  std::array<std::vector<double>, NumberOfChannels> A12, A21;
  std::unique_ptr<LinearSolver> Cycle1, Cycle2; ///< multigrid-agg on A11, A22
  std::string Preconditioner;
  bool CyclesReady = false;
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
}

namespace
{

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

} // namespace

void Sp3Solver::Assemble(const DiffusionProblem& problem, const std::vector<double>& sourceLoad)
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

  ResizeVertexSystem(mesh, b.A11);
  ResizeVertexSystem(mesh, b.A22);
  b.A22.ColumnIndices = mesh.GetColumnIndices();
  const std::size_t nnz = mesh.GetColumnIndices().size();
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    b.A12[c].resize(nnz);
    b.A21[c].resize(nnz);
  }
  double* v22[NumberOfChannels];
  double* v12[NumberOfChannels];
  double* v21[NumberOfChannels];
  double* rhs2[NumberOfChannels];
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    v22[c] = b.A22.Values[c].data();
    v12[c] = b.A12[c].data();
    v21[c] = b.A21[c].data();
    rhs2[c] = b.A22.RightHandSide[c].data();
  }
  const double* muA = material.AbsorptionCoefficient.data();
  const double* sigmaS = material.ReducedScatteringCoefficient.data();
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
  const long long numValues = static_cast<long long>(nnz);
  double* const* rhs1 = nullptr;
  ChannelPointers channels1(b.A11);
  double* const* v11 = channels1.Values;
  rhs1 = channels1.RightHandSide;
  const int numThreads = NumberOfThreads_ > 0 ? NumberOfThreads_ : omp_get_max_threads();

  auto prepare = [&]() {
#pragma omp for schedule(static)
    for (long long k = 0; k < numValues; ++k)
    {
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        v22[c][k] = 0.0;
        v12[c][k] = 0.0;
        v21[c][k] = 0.0;
      }
    }
#pragma omp for schedule(static)
    for (int i = 0; i < numPoints; ++i)
    {
      const bool orphan = pointTetOffsets[i + 1] == pointTetOffsets[i];
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        rhs2[c][i] = 0.0;
        if (orphan)
        {
          v22[c][diagonal[i]] = 1.0;
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
    const double(&g)[4][4] = geometry.Stiffness;
    const double volume = geometry.Volume;
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      const double a = muA[3 * t + c];
      const double s = sigmaS[3 * t + c]; // sigma_s' = mu_s (1 - g)
      const double aniso = material.GetAnisotropy(static_cast<int>(t), c);
      // mu_an = mu_a + mu_s (1 - g^n) with mu_s = sigma_s' / (1 - g)
      // (Klose & Larsen 2006, the SP_N absorption moments; equation number
      // unverified: the paper is not in shared/papers, see Solvers.md "SP3"):
      const double muA1 = a + s;
      const double muA2 = a + s * (1.0 + aniso);
      const double muA3 = a + s * (1.0 + aniso + aniso * aniso);
      // Klose & Larsen 2006, the SP3 equations in their composite moments
      // (equation number unverified, restated from the P3 derivation): diffusion coefficients 1/(3 mu_a1), 1/(7 mu_a3);
      // mass coefficients mu_a, (4/9) mu_a + (5/9) mu_a2 and the coupling
      // -(2/3) mu_a.
      const double d1 = 1.0 / (3.0 * muA1), d2 = 1.0 / (7.0 * muA3);
      const double m1 = a, m2 = (4.0 / 9.0) * a + (5.0 / 9.0) * muA2, m12 = -(2.0 / 3.0) * a;
      // Consistent mass (V_t / 20)(1 + delta_ab).
      const double mass = volume / 20.0;
      for (int i = 0; i < 4; ++i)
      {
        for (int j = 0; j < 4; ++j)
        {
          const int p = pos[4 * i + j];
          const double mij = i == j ? 2.0 * mass : mass;
          v11[c][p] += d1 * g[i][j] + m1 * mij;
          v22[c][p] += d2 * g[i][j] + m2 * mij;
          v12[c][p] += m12 * mij;
          v21[c][p] += m12 * mij;
        }
      }
    }
    // Boundary triangles of this tet: the currents J_1, J_2 of the boundary
    // conditions (Sp3BoundaryCoefficients) as consistent boundary mass
    // (S_f / 12)(1 + delta_ab) and load.
    for (int f = head[t]; f >= 0; f = next[f])
    {
      const Sp3BoundaryCoefficients& k =
        coefficients[static_cast<std::size_t>(etaIndex[t])];
      const int* tri = triangles + 3 * static_cast<std::size_t>(f);
      const int local[3] = { LocalIndex(tv, tri[0]), LocalIndex(tv, tri[1]),
        LocalIndex(tv, tri[2]) };
      const double m = triangleAreas[f] / 12.0;
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        double qSum = 0.0;
        for (int i = 0; i < 3; ++i)
        {
          qSum += q[3 * static_cast<std::size_t>(tri[i]) + c];
        }
        for (int i = 0; i < 3; ++i)
        {
          for (int j = 0; j < 3; ++j)
          {
            const int p = pos[4 * local[i] + local[j]];
            const double mij = i == j ? 2.0 * m : m;
            v11[c][p] += k.F11 * mij;
            v12[c][p] += k.F12 * mij;
            v21[c][p] += k.F21 * mij;
            v22[c][p] += k.F22 * mij;
          }
          // int q v = m (q_i + sum_j q_j); the S q part of J moves to the
          // right-hand side.
          const double load = m * (qSum + q[3 * static_cast<std::size_t>(tri[i]) + c]);
          rhs1[c][tri[i]] -= k.S1 * load;
          rhs2[c][tri[i]] -= k.S2 * load;
        }
      }
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
  // Interior sources: Q in the first equation, -(2/3) Q in the second.
  if (!sourceLoad.empty())
  {
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      for (int i = 0; i < numPoints; ++i)
      {
        const double load = sourceLoad[3 * static_cast<std::size_t>(i) + c];
        b.A11.RightHandSide[c][i] += load;
        b.A22.RightHandSide[c][i] -= (2.0 / 3.0) * load;
      }
    }
  }
}

namespace
{

/// y = A x for the block system, 2 N x 3 interleaved ((b N + i) 3 + c).
void BlockProduct(const DiffusionSystem& a11, const DiffusionSystem& a22,
  const std::array<std::vector<double>, NumberOfChannels>& a12,
  const std::array<std::vector<double>, NumberOfChannels>& a21, const double* x, double* y)
{
  const int n = a11.NumberOfUnknowns;
  const int* rows = a11.RowOffsets.data();
  const int* cols = a11.ColumnIndices.data();
  const std::size_t shift = 3 * static_cast<std::size_t>(n);
#pragma omp for schedule(static)
  for (int i = 0; i < n; ++i)
  {
    double y1[3] = { 0, 0, 0 }, y2[3] = { 0, 0, 0 };
    for (int k = rows[i]; k < rows[i + 1]; ++k)
    {
      const std::size_t j = 3 * static_cast<std::size_t>(cols[k]);
      for (int c = 0; c < 3; ++c)
      {
        const double x1 = x[j + c], x2 = x[shift + j + c];
        y1[c] += a11.Values[c][k] * x1 + a12[c][k] * x2;
        y2[c] += a21[c][k] * x1 + a22.Values[c][k] * x2;
      }
    }
    for (int c = 0; c < 3; ++c)
    {
      y[3 * static_cast<std::size_t>(i) + c] = y1[c];
      y[shift + 3 * static_cast<std::size_t>(i) + c] = y2[c];
    }
  }
}

/// Per-channel dot products of two 2 N x 3 interleaved vectors (serial
/// order: deterministic for any thread count).
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

} // namespace

bool Sp3Solver::SolveBlocks(
  const TetMesh& mesh, bool warm, const std::string& preconditioner, SolverReport& report)
{
  Blocks& b = *Blocks_;
  const int n = mesh.GetNumberOfPoints();
  const std::size_t half = 3 * static_cast<std::size_t>(n), size = 2 * half;
  const int numThreads = NumberOfThreads_ > 0 ? NumberOfThreads_ : omp_get_max_threads();

  // Preconditioner: block-diagonal Jacobi or a multigrid cycle per block.
  std::vector<double> inverseDiagonal;
  const bool multigrid = preconditioner == "multigrid-agg";
  if (multigrid)
  {
    if (!b.Cycle1 || !b.Cycle2)
    {
      b.Cycle1 = CreateLinearSolver("multigrid-agg");
      b.Cycle2 = CreateLinearSolver("multigrid-agg");
      b.CyclesReady = false;
    }
    const bool rebuild = !b.CyclesReady;
    b.Cycle1->Setup(b.A11, &mesh, rebuild);
    b.Cycle2->Setup(b.A22, &mesh, rebuild);
    b.CyclesReady = true;
  }
  else
  {
    inverseDiagonal.resize(size);
    const int* diagonal = mesh.GetDiagonalPositions().data();
    for (int i = 0; i < n; ++i)
    {
      for (int c = 0; c < 3; ++c)
      {
        inverseDiagonal[3 * static_cast<std::size_t>(i) + c] =
          1.0 / b.A11.Values[c][diagonal[i]];
        inverseDiagonal[half + 3 * static_cast<std::size_t>(i) + c] =
          1.0 / b.A22.Values[c][diagonal[i]];
      }
    }
  }
  auto precondition = [&](const std::vector<double>& r, std::vector<double>& z) {
    if (multigrid)
    {
      b.Cycle1->ApplyPreconditioner(r.data(), z.data());
      b.Cycle2->ApplyPreconditioner(r.data() + half, z.data() + half);
    }
    else
    {
      for (std::size_t k = 0; k < size; ++k)
      {
        z[k] = inverseDiagonal[k] * r[k];
      }
    }
  };
  auto product = [&](const std::vector<double>& x, std::vector<double>& y) {
#pragma omp parallel num_threads(numThreads)
    BlockProduct(b.A11, b.A22, b.A12, b.A21, x.data(), y.data());
  };

  std::vector<double> rhs(size);
  for (int i = 0; i < n; ++i)
  {
    for (int c = 0; c < 3; ++c)
    {
      rhs[3 * static_cast<std::size_t>(i) + c] = b.A11.RightHandSide[c][i];
      rhs[half + 3 * static_cast<std::size_t>(i) + c] = b.A22.RightHandSide[c][i];
    }
  }
  if (!warm || X_.size() != size)
  {
    X_.assign(size, 0.0);
  }
  std::vector<double>& x = X_;
  std::vector<double> r(size), rHat, p(size), v(size), pHat(size), s(size), sHat(size), t(size);
  const std::array<double, 3> bb = Dots(rhs, rhs);
  std::array<double, 3> rr{};
  std::array<bool, 3> done{}, failed{};
  std::array<int, 3> iterations{};
  auto converged = [&](int c) {
    return bb[c] == 0.0 ? rr[c] == 0.0 : std::sqrt(rr[c] / bb[c]) <= RelTol_;
  };
  auto trueResidual = [&]() {
    product(x, r);
    for (std::size_t k = 0; k < size; ++k)
    {
      r[k] = rhs[k] - r[k];
    }
    rr = Dots(r, r);
  };
  for (int c = 0; c < 3; ++c)
  {
    if (bb[c] == 0.0)
    {
      // No source in this channel: the solution is 0.
      for (std::size_t k = static_cast<std::size_t>(c); k < size; k += 3)
      {
        x[k] = 0.0;
      }
    }
  }
  trueResidual();
  int it = 0;
  // BiCGSTAB (right-preconditioned), the three channels in lockstep with
  // their own scalars; restarted from the true residual when the recursive
  // one says converged but the true one does not (drift).
  for (int restart = 0; restart < 5; ++restart)
  {
    for (int c = 0; c < 3; ++c)
    {
      done[c] = failed[c] || converged(c);
    }
    if (done[0] && done[1] && done[2])
    {
      break;
    }
    rHat = r;
    std::fill(p.begin(), p.end(), 0.0);
    std::fill(v.begin(), v.end(), 0.0);
    std::array<double, 3> rho{ 1, 1, 1 }, alpha{ 1, 1, 1 }, omega{ 1, 1, 1 };
    for (; it < MaxIter_ && !(done[0] && done[1] && done[2]); ++it)
    {
      if (!ReportProgress(static_cast<double>(it) / std::max(1, MaxIter_)))
      {
        return false;
      }
      const std::array<double, 3> rhoNew = Dots(rHat, r);
      std::array<double, 3> beta{};
      for (int c = 0; c < 3; ++c)
      {
        if (done[c])
        {
          continue;
        }
        if (!(std::abs(rhoNew[c]) > 0.0) || !std::isfinite(rhoNew[c]))
        {
          failed[c] = done[c] = true; // breakdown: reported as not converged
          continue;
        }
        beta[c] = (rhoNew[c] / rho[c]) * (alpha[c] / omega[c]);
        rho[c] = rhoNew[c];
      }
      for (std::size_t k = 0; k < size; ++k)
      {
        const int c = static_cast<int>(k % 3);
        p[k] = done[c] ? 0.0 : r[k] + beta[c] * (p[k] - omega[c] * v[k]);
      }
      precondition(p, pHat);
      product(pHat, v);
      const std::array<double, 3> rv = Dots(rHat, v);
      for (int c = 0; c < 3; ++c)
      {
        if (!done[c])
        {
          if (!(std::abs(rv[c]) > 0.0) || !std::isfinite(rv[c]))
          {
            failed[c] = done[c] = true;
            continue;
          }
          alpha[c] = rho[c] / rv[c];
        }
      }
      for (std::size_t k = 0; k < size; ++k)
      {
        const int c = static_cast<int>(k % 3);
        s[k] = done[c] ? 0.0 : r[k] - alpha[c] * v[k];
      }
      precondition(s, sHat);
      product(sHat, t);
      const std::array<double, 3> ts = Dots(t, s), tt = Dots(t, t);
      for (int c = 0; c < 3; ++c)
      {
        if (!done[c])
        {
          omega[c] = tt[c] > 0.0 ? ts[c] / tt[c] : 0.0;
        }
      }
      for (std::size_t k = 0; k < size; ++k)
      {
        const int c = static_cast<int>(k % 3);
        if (!done[c])
        {
          x[k] += alpha[c] * pHat[k] + omega[c] * sHat[k];
          r[k] = s[k] - omega[c] * t[k];
        }
      }
      const std::array<double, 3> rrNew = Dots(r, r);
      for (int c = 0; c < 3; ++c)
      {
        if (!done[c])
        {
          rr[c] = rrNew[c];
          ++iterations[c];
          if (!std::isfinite(rr[c]))
          {
            failed[c] = done[c] = true;
          }
          else if (converged(c))
          {
            done[c] = true;
          }
          else if (omega[c] == 0.0)
          {
            done[c] = true; // stagnation: restart from the true residual
          }
        }
      }
    }
    trueResidual();
    if (it >= MaxIter_)
    {
      break;
    }
  }
  for (int c = 0; c < 3; ++c)
  {
    report.Iterations[c] = iterations[c];
    report.Residual[c] = bb[c] > 0.0 ? std::sqrt(rr[c] / bb[c]) : std::sqrt(rr[c]);
    report.Converged[c] = !failed[c] && converged(c);
  }
  return true;
}

void Sp3Solver::ComputeExitance(const DiffusionProblem& problem)
{
  const TetMesh& mesh = *problem.Mesh;
  const OpticalProperties& material = *problem.Material;
  const std::vector<double>& q = *problem.Irradiance;
  const int n = mesh.GetNumberOfPoints();
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
      Exitance_[m] = k.E1 * Phi1_[m] + k.E2 * Phi2_[m] + k.E3 * q[m];
    }
  }
}

std::vector<double> ComputeSp3SourceLoad(
  const TetMesh& mesh, const OpticalProperties& material, const Sources& sources)
{
  sources.Validate();
  Sources points;
  for (const PointSource& point : sources.GetPointSources())
  {
    points.AddPointSource(point);
  }
  const std::vector<PencilBeam>& beams = sources.GetPencilBeams();
  if (!beams.empty())
  {
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
        PointSource point;
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
        points.AddPointSource(point);
      }
    }
  }
  return points.ComputeLoad(mesh, material);
}

bool Sp3Solver::Solve(
  const DiffusionProblem& given, std::vector<double>& fluence, SolverReport& report)
{
  if (!given.Mesh || !given.Material || !given.Irradiance)
  {
    throw Error("sp3: the problem needs a mesh, a material and an irradiance");
  }
  // The option's g on every tet when the material carries none.
  OpticalProperties withAnisotropy;
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
  report = SolverReport();
  report.Solver = GetName();
  report.Assembly = "full";

  const std::string requested = ToLower(LinearSolver_);
  std::string preconditioner;
  if (requested.empty())
  {
    preconditioner = mesh.GetNumberOfPoints() < VertexDiffusionSolver::LargeSystemUnknowns
      ? "jacobi"
      : "multigrid-agg";
  }
  else if (requested == "jacobi" || requested == "cg-jacobi" || requested == "bicgstab")
  {
    preconditioner = "jacobi";
  }
  else if (requested == "multigrid-agg")
  {
    preconditioner = "multigrid-agg";
  }
  else
  {
    throw Error("sp3: linear solver '" + LinearSolver_ +
      "' is not available for the SP3 block system (known: jacobi, multigrid-agg; \"\" chooses "
      "by size)");
  }
  report.LinearSolver = "bicgstab-block-" + preconditioner;

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
    if (sourceLoad.empty())
    {
      sourceLoad.swap(collimated.Load);
    }
    else
    {
      for (std::size_t k = 0; k < sourceLoad.size(); ++k)
      {
        sourceLoad[k] += collimated.Load[k];
      }
    }
  }
  const bool sameMesh = LastMesh_ == &mesh && LastPoints_ == mesh.GetNumberOfPoints() &&
    LastTets_ == mesh.GetNumberOfTets() && LastRevision_ == mesh.GetGeometryRevision();
  if (!sameMesh)
  {
    Reset();
  }
  Assemble(problem, sourceLoad);
  report.SetupMilliseconds = MillisecondsSince(start);

  start = Clock::now();
  if (!SolveBlocks(mesh, WarmStart_ && sameMesh, preconditioner, report))
  {
    Reset();
    return false;
  }
  report.SolveMilliseconds = MillisecondsSince(start);
  LastMesh_ = &mesh;
  LastPoints_ = mesh.GetNumberOfPoints();
  LastTets_ = mesh.GetNumberOfTets();
  LastRevision_ = mesh.GetGeometryRevision();

  const int n = mesh.GetNumberOfPoints();
  const std::size_t half = 3 * static_cast<std::size_t>(n);
  report.NumberOfUnknowns = 2LL * n;
  report.NumberOfNonZeros = 4LL * static_cast<long long>(Blocks_->A11.ColumnIndices.size());
  report.MemoryBytes = Blocks_->A11.GetMemoryBytes() + Blocks_->A22.GetMemoryBytes() +
    2 * NumberOfChannels * Blocks_->A11.ColumnIndices.size() * sizeof(double) +
    9 * 2 * half * sizeof(double) +
    (Blocks_->Cycle1 ? Blocks_->Cycle1->GetMemoryBytes() + Blocks_->Cycle2->GetMemoryBytes() : 0);
  Phi1_.assign(X_.begin(), X_.begin() + static_cast<std::ptrdiff_t>(half));
  Phi2_.assign(X_.begin() + static_cast<std::ptrdiff_t>(half), X_.end());
  fluence.resize(half);
  for (std::size_t k = 0; k < half; ++k)
  {
    // phi_0 = phi_1 - (2/3) phi_2 (Klose & Larsen 2006, the composite
    // moments phi_1 = phi_0 + 2 phi_2, phi_2 := 3 phi_2).
    fluence[k] = Phi1_[k] - (2.0 / 3.0) * Phi2_[k];
  }
  ComputeExitance(problem);
  if (extended)
  {
    // The total fluence rate: diffuse plus the unscattered beam.
    for (std::size_t k = 0; k < fluence.size(); ++k)
    {
      fluence[k] += collimated.Fluence[k];
    }
    report.CollimatedFluence = std::move(collimated.Fluence);
    report.CollimatedEntering = collimated.Entering;
    report.CollimatedScattered = collimated.Scattered;
    report.CollimatedAbsorbed = collimated.Absorbed;
  }
  return true;
}

} // namespace translucency
