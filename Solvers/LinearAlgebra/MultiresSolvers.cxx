#include "MultiresSolvers.h"

#include "BlockedKernels.h"
#include "Error.h"
#include "TetMesh.h"
#include "Timer.h"

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCholesky>

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace translucency
{

namespace
{

using RowMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;
using namespace blocked;

/// x_fine += P x_coarse (eq. 16), three channels.
void Prolongate(const MultiresHierarchy::Level& level, const double* xc, double* xf)
{
  const int n = static_cast<int>(level.InterpolationOffsets.size()) - 1;
  const int* po = level.InterpolationOffsets.data();
  const int* pc = level.InterpolationColumns.data();
  const double* pw = level.InterpolationWeights.data();
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i)
  {
    double a0 = 0.0, a1 = 0.0, a2 = 0.0;
    for (int p = po[i]; p < po[i + 1]; ++p)
    {
      const double* c = xc + 3 * static_cast<std::size_t>(pc[p]);
      a0 += pw[p] * c[0];
      a1 += pw[p] * c[1];
      a2 += pw[p] * c[2];
    }
    xf[3 * static_cast<std::size_t>(i)] += a0;
    xf[3 * static_cast<std::size_t>(i) + 1] += a1;
    xf[3 * static_cast<std::size_t>(i) + 2] += a2;
  }
}

/// Inverse diagonals of the three channels (interleaved), checking positivity.
void InverseDiagonal(const CsrPattern& p, const std::array<const double*, NC>& values, int stride,
  Eigen::VectorXd& inv, const std::string& who, int level)
{
  const int n = p.Size;
  inv.setZero(3 * static_cast<long long>(n));
  for (int i = 0; i < n; ++i)
  {
    const int* begin = p.Columns.data() + p.Offsets[i];
    const int* end = p.Columns.data() + p.Offsets[i + 1];
    const int* d = std::lower_bound(begin, end, i);
    for (int c = 0; c < NC; ++c)
    {
      const double v = (d != end && *d == i)
        ? values[c][static_cast<std::size_t>(d - p.Columns.data()) * stride]
        : 0.0;
      if (!(v > 0.0) || !std::isfinite(v))
      {
        std::ostringstream os;
        os << who << ": diagonal entry of row " << i << " (level " << level << ", channel " << c
           << ") is " << v << ", not positive: the matrix is not SPD";
        throw Error(os.str());
      }
      inv[3 * static_cast<long long>(i) + c] = 1.0 / v;
    }
  }
}


} // namespace

// ---------------------------------------------------------------------------
// Common set-up

void MultiresLinearSolverBase::CheckSetup(const DiffusionSystem& system, const TetMesh* mesh) const
{
  blocked::CheckSystemOnMesh(GetName(), system, mesh);
}

void MultiresLinearSolverBase::SetupStructure(const DiffusionSystem& system, const TetMesh* mesh)
{
  const auto start = Clock::now();
  if (system.RowOffsets == mesh->GetRowOffsets() &&
    system.ColumnIndices == mesh->GetColumnIndices())
  {
    Hierarchy_.Build(*mesh);
  }
  else
  {
    Hierarchy_.Build(mesh->GetPoints(), system.RowOffsets, system.ColumnIndices);
  }
  BuildOperators();
  HierarchyMs_ = MillisecondsSince(start);
  ++Builds_;
}

void MultiresLinearSolverBase::SetupValues(const DiffusionSystem& system, const TetMesh*)
{
  const auto start = Clock::now();
  ComputeValues(system);
  ValuesMs_ = MillisecondsSince(start);
  ++Setups_;
}

void MultiresLinearSolverBase::CheckSystem(const DiffusionSystem& system) const
{
  blocked::CheckSolveMatchesSetup(GetName(), system, Ready_, Unknowns_, NonZeros_);
}

double MultiresLinearSolverBase::GetOperatorComplexity() const
{
  double total = static_cast<double>(Hierarchy_.GetLevel(0).Graph.GetNumberOfNonZeros());
  for (const auto& op : Operators_)
  {
    total += op.GetPattern().GetNumberOfNonZeros();
  }
  return total / std::max(1, Hierarchy_.GetLevel(0).Graph.GetNumberOfNonZeros());
}

// ---------------------------------------------------------------------------
// multigrid-cg

struct MultigridConjugateGradient::Internals
{
  struct Level
  {
    const CsrPattern* Pattern = nullptr;
    std::vector<double> Values; ///< double, interleaved (levels >= 1)
    std::vector<float> Single;  ///< single precision, interleaved (smoothing)
    Eigen::VectorXd InverseDiagonal;
    std::array<double, NC> LambdaMax{};
    // P^T as CSR for the restriction (levels with a coarser one).
    std::vector<int> TOffsets, TRows;
    std::vector<double> TWeights;
    mutable Eigen::VectorXd B, X, R, D, T;
  };
  std::vector<Level> Levels;
  std::array<Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>, NC> Coarsest;
  std::size_t CoarsestFactorNonZeros = 0;
  double VCycleFlops = 0.0; ///< multiply-adds per channel of one V-cycle
};

MultigridConjugateGradient::MultigridConjugateGradient()
  : Internal_(new Internals)
{
}

MultigridConjugateGradient::~MultigridConjugateGradient() = default;

void MultigridConjugateGradient::BuildOperators()
{
  const int L = Hierarchy_.GetNumberOfLevels();
  Operators_.assign(std::max(0, L - 1), CoarseOperator());
  Internal_->Levels.assign(L, Internals::Level());
  Internal_->Levels[0].Pattern = &Hierarchy_.GetLevel(0).Graph;
  for (int l = 0; l + 1 < L; ++l)
  {
    // Galerkin coarse operators P^T A P (beyond the paper, Sec. 4.2 remark).
    Operators_[l].Build(Hierarchy_.GetLevel(l), *Internal_->Levels[l].Pattern,
      Hierarchy_.GetLevel(l + 1).Graph,
      ExactGalerkinLevels_ >= 0 && l >= ExactGalerkinLevels_ ? CoarseOperator::Kind::SparseGalerkin
                                                       : CoarseOperator::Kind::Galerkin,
      Threads_);
    Internal_->Levels[l + 1].Pattern = &Operators_[l].GetPattern();
    // P^T for the restriction.
    const auto& h = Hierarchy_.GetLevel(l);
    auto& lev = Internal_->Levels[l];
    const int nc = Hierarchy_.GetLevel(l + 1).Graph.Size;
    lev.TOffsets.assign(nc + 1, 0);
    for (int c : h.InterpolationColumns)
    {
      ++lev.TOffsets[c + 1];
    }
    for (int a = 0; a < nc; ++a)
    {
      lev.TOffsets[a + 1] += lev.TOffsets[a];
    }
    lev.TRows.resize(h.InterpolationColumns.size());
    lev.TWeights.resize(h.InterpolationColumns.size());
    std::vector<int> fill(lev.TOffsets.begin(), lev.TOffsets.end() - 1);
    const int n = static_cast<int>(h.InterpolationOffsets.size()) - 1;
    for (int i = 0; i < n; ++i)
    {
      for (int p = h.InterpolationOffsets[i]; p < h.InterpolationOffsets[i + 1]; ++p)
      {
        const int slot = fill[h.InterpolationColumns[p]]++;
        lev.TRows[slot] = i;
        lev.TWeights[slot] = h.InterpolationWeights[p];
      }
    }
  }
}

void MultigridConjugateGradient::ComputeValues(const DiffusionSystem& system)
{
  auto& levels = Internal_->Levels;
  const int L = static_cast<int>(levels.size());
  Internal_->VCycleFlops = 0.0;
  for (int l = 0; l < L; ++l)
  {
    auto& lev = levels[l];
    const CsrPattern& p = *lev.Pattern;
    const std::size_t nnz = p.Columns.size();
    std::array<const double*, NC> values;
    int stride = 1;
    if (l == 0)
    {
      values = { system.Values[0].data(), system.Values[1].data(), system.Values[2].data() };
    }
    else
    {
      lev.Values.resize(3 * nnz);
      const auto& fine = levels[l - 1];
      std::array<const double*, NC> fineValues;
      int fineStride = 1;
      if (l == 1)
      {
        fineValues = { system.Values[0].data(), system.Values[1].data(),
          system.Values[2].data() };
      }
      else
      {
        fineValues = { fine.Values.data(), fine.Values.data() + 1, fine.Values.data() + 2 };
        fineStride = 3;
      }
      Operators_[l - 1].Compute(fineValues, fineStride, lev.Values.data(), Threads_);
      values = { lev.Values.data(), lev.Values.data() + 1, lev.Values.data() + 2 };
      stride = 3;
    }
    InverseDiagonal(p, values, stride, lev.InverseDiagonal, GetName(), l);
    const int n = p.Size;
    for (auto* v : { &lev.B, &lev.X, &lev.R, &lev.D, &lev.T })
    {
      v->setZero(3 * static_cast<long long>(n));
    }
    if (l == L - 1)
    {
      // Coarsest level: sparse LDL^T per channel (double precision).
      Internal_->CoarsestFactorNonZeros = 0;
      for (int c = 0; c < NC; ++c)
      {
        std::vector<double> vc(nnz);
        for (std::size_t k = 0; k < nnz; ++k)
        {
          vc[k] = values[c][k * stride];
        }
        const RowMatrix a = Eigen::Map<const RowMatrix>(
          n, n, static_cast<int>(nnz), p.Offsets.data(), p.Columns.data(), vc.data());
        auto& ldlt = Internal_->Coarsest[c];
        ldlt.compute(Eigen::SparseMatrix<double>(a));
        if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0))
        {
          std::ostringstream os;
          os << GetName() << ": the coarsest-level matrix (level " << l << ", " << n
             << " vertices, channel " << c << ") is not positive definite";
          throw Error(os.str());
        }
        Internal_->CoarsestFactorNonZeros =
          static_cast<std::size_t>(ldlt.matrixL().nestedExpression().nonZeros());
      }
      Internal_->VCycleFlops += 2.0 * Internal_->CoarsestFactorNonZeros + 2.0 * n;
      continue;
    }
    // Single-precision copy for the smoother and residuals.
    lev.Single.resize(3 * nnz);
#pragma omp parallel for schedule(static)
    for (long long k = 0; k < static_cast<long long>(nnz); ++k)
    {
      for (int c = 0; c < NC; ++c)
      {
        lev.Single[3 * k + c] = static_cast<float>(values[c][k * stride]);
      }
    }
    // Chebyshev interval: largest eigenvalue of D^-1 A by 15 power steps
    // (x 1.1), capped by the Gershgorin bound max_i sum_j |A_ij| / A_ii.
    std::array<double, NC> gershgorin{};
    {
      double g0 = 0.0, g1 = 0.0, g2 = 0.0;
#pragma omp parallel for schedule(static) reduction(max : g0, g1, g2)
      for (int i = 0; i < n; ++i)
      {
        double s[NC] = { 0.0, 0.0, 0.0 };
        for (int k = p.Offsets[i]; k < p.Offsets[i + 1]; ++k)
        {
          for (int c = 0; c < NC; ++c)
          {
            s[c] += std::abs(values[c][static_cast<std::size_t>(k) * stride]);
          }
        }
        g0 = std::max(g0, s[0] * lev.InverseDiagonal[3 * static_cast<long long>(i)]);
        g1 = std::max(g1, s[1] * lev.InverseDiagonal[3 * static_cast<long long>(i) + 1]);
        g2 = std::max(g2, s[2] * lev.InverseDiagonal[3 * static_cast<long long>(i) + 2]);
      }
      gershgorin = { g0, g1, g2 };
    }
    Eigen::VectorXd v(3 * static_cast<long long>(n)), w(v.size());
    for (long long i = 0; i < v.size(); ++i)
    {
      v[i] = 0.5 + (MultiresHierarchy::Code(static_cast<int>(i), 77) >> 32) / 4294967296.0;
    }
    std::array<double, NC> lambda{};
    for (int it = 0; it < 15; ++it)
    {
      MultiplyFloat(p, lev.Single.data(), v.data(), w.data());
      w = w.cwiseProduct(lev.InverseDiagonal);
      const auto ww = Dot3(w, w), vv = Dot3(v, v);
      std::array<double, NC> scale{};
      for (int c = 0; c < NC; ++c)
      {
        lambda[c] = vv[c] > 0.0 ? std::sqrt(ww[c] / vv[c]) : 0.0;
        scale[c] = ww[c] > 0.0 ? 1.0 / std::sqrt(ww[c]) : 0.0;
      }
      for (long long i = 0; i < static_cast<long long>(n); ++i)
      {
        for (int c = 0; c < NC; ++c)
        {
          v[3 * i + c] = w[3 * i + c] * scale[c];
        }
      }
    }
    for (int c = 0; c < NC; ++c)
    {
      lev.LambdaMax[c] = std::min(1.1 * lambda[c], gershgorin[c]);
    }
    // Flops per channel of one visit: 2 * degree SpMVs, P and P^T, and
    // about 4 vector operations per Chebyshev step.
    Internal_->VCycleFlops += 2.0 * Degree_ * static_cast<double>(nnz) +
      2.0 * lev.TRows.size() + 2.0 * Degree_ * 4.0 * n + 2.0 * n;
  }
}

void MultigridConjugateGradient::ApplyPreconditioner(
  const Eigen::VectorXd& rhs, Eigen::VectorXd& out) const
{
  auto& levels = Internal_->Levels;
  const int L = static_cast<int>(levels.size());
  const int degree = std::max(1, Degree_);
  const double fraction = std::min(std::max(Fraction_, 1e-3), 0.99);

  // Chebyshev smoothing of A x = b on level l (paper-independent; the
  // standard three-term recurrence on D^-1 A over [fraction, 1] * lambda_max).
  auto smooth = [&](const Internals::Level& lev, bool zeroStart)
  {
    const int n = lev.Pattern->Size;
    const long long m = 3 * static_cast<long long>(n);
    if (zeroStart)
    {
      lev.X.setZero();
      lev.R = lev.B;
    }
    else
    {
      MultiplyFloat(*lev.Pattern, lev.Single.data(), lev.X.data(), lev.T.data());
      lev.R = lev.B - lev.T;
    }
    std::array<double, NC> theta, delta, sigma, rho;
    for (int c = 0; c < NC; ++c)
    {
      const double upper = lev.LambdaMax[c], lower = fraction * upper;
      theta[c] = 0.5 * (upper + lower);
      delta[c] = 0.5 * (upper - lower);
      sigma[c] = theta[c] / delta[c];
      rho[c] = 1.0 / sigma[c];
    }
#pragma omp parallel for schedule(static)
    for (long long k = 0; k < m; ++k)
    {
      lev.D[k] = lev.InverseDiagonal[k] * lev.R[k] / theta[k % 3];
    }
    for (int step = 1; step <= degree; ++step)
    {
      lev.X += lev.D;
      if (step == degree)
      {
        break;
      }
      MultiplyFloat(*lev.Pattern, lev.Single.data(), lev.D.data(), lev.T.data());
      std::array<double, NC> a, b;
      for (int c = 0; c < NC; ++c)
      {
        const double rhoNew = 1.0 / (2.0 * sigma[c] - rho[c]);
        a[c] = rhoNew * rho[c];
        b[c] = 2.0 * rhoNew / delta[c];
        rho[c] = rhoNew;
      }
#pragma omp parallel for schedule(static)
      for (long long k = 0; k < m; ++k)
      {
        lev.R[k] -= lev.T[k];
        lev.D[k] = a[k % 3] * lev.D[k] + b[k % 3] * lev.InverseDiagonal[k] * lev.R[k];
      }
    }
  };

  levels[0].B = rhs;
  for (int l = 0; l < L; ++l)
  {
    const auto& lev = levels[l];
    if (l == L - 1)
    {
      SolveInterleaved(Internal_->Coarsest.data(), lev.Pattern->Size, lev.B.data(), lev.X.data());
      break;
    }
    // Pre-smoothing from zero, residual, restriction r_c = P^T r.
    smooth(lev, true);
    MultiplyFloat(*lev.Pattern, lev.Single.data(), lev.X.data(), lev.T.data());
    lev.R = lev.B - lev.T;
    const auto& coarse = levels[l + 1];
    const int nc = coarse.Pattern->Size;
#pragma omp parallel for schedule(static)
    for (int a = 0; a < nc; ++a)
    {
      double s0 = 0.0, s1 = 0.0, s2 = 0.0;
      for (int t = lev.TOffsets[a]; t < lev.TOffsets[a + 1]; ++t)
      {
        const double* r = lev.R.data() + 3 * static_cast<std::size_t>(lev.TRows[t]);
        s0 += lev.TWeights[t] * r[0];
        s1 += lev.TWeights[t] * r[1];
        s2 += lev.TWeights[t] * r[2];
      }
      coarse.B[3 * static_cast<long long>(a)] = s0;
      coarse.B[3 * static_cast<long long>(a) + 1] = s1;
      coarse.B[3 * static_cast<long long>(a) + 2] = s2;
    }
  }
  for (int l = L - 2; l >= 0; --l)
  {
    // Coarse correction x += P x_c (eq. 16), post-smoothing.
    const auto& lev = levels[l];
    Prolongate(Hierarchy_.GetLevel(l), levels[l + 1].X.data(), lev.X.data());
    smooth(lev, false);
  }
  out = levels[0].X;
}

bool MultigridConjugateGradient::Solve(const DiffusionSystem& system,
  std::array<Eigen::VectorXd, NumberOfChannels>& x, bool warmStart,
  std::array<LinearSolveStats, NumberOfChannels>& stats)
{
  CheckSystem(system);
  const int n = system.NumberOfUnknowns;
  Eigen::VectorXd xi = Eigen::VectorXd::Zero(3 * static_cast<long long>(n));
  if (warmStart && x[0].size() == n && x[1].size() == n && x[2].size() == n)
  {
    Interleave(x, xi);
  }
  const double flops = static_cast<double>(system.ColumnIndices.size()) + 5.0 * n +
    Internal_->VCycleFlops;
  const bool done = BlockedPCG(
    system, [this](const Eigen::VectorXd& r, Eigen::VectorXd& z) { ApplyPreconditioner(r, z); },
    xi, RelTol_, MaxIter_, stats, flops, Progress_, MinIter_);
  Deinterleave(xi, x);
  return done;
}

Eigen::SparseMatrix<double, Eigen::RowMajor, int> MultigridConjugateGradient::GetCoarseMatrix(
  int l, int c) const
{
  const auto& lev = Internal_->Levels.at(l);
  const CsrPattern& p = *lev.Pattern;
  std::vector<double> v(p.Columns.size());
  for (std::size_t k = 0; k < v.size(); ++k)
  {
    v[k] = lev.Values.at(3 * k + c);
  }
  return Eigen::Map<const RowMatrix>(
    p.Size, p.Size, static_cast<int>(v.size()), p.Offsets.data(), p.Columns.data(), v.data());
}

std::size_t MultigridConjugateGradient::GetMemoryBytes() const
{
  std::size_t bytes = Hierarchy_.GetMemoryBytes();
  for (const auto& op : Operators_)
  {
    bytes += op.GetMemoryBytes();
  }
  for (const auto& lev : Internal_->Levels)
  {
    bytes += lev.Values.size() * sizeof(double) + lev.Single.size() * sizeof(float) +
      6 * lev.InverseDiagonal.size() * sizeof(double) +
      (lev.TOffsets.size() + lev.TRows.size()) * sizeof(int) + lev.TWeights.size() * sizeof(double);
  }
  bytes += NC * Internal_->CoarsestFactorNonZeros * (sizeof(double) + sizeof(int));
  return bytes;
}

// ---------------------------------------------------------------------------
// transcut-multires

struct TransCutMultiresSolver::Internals
{
  /// Level l >= 1: eq. 17 values per channel (index l - 1).
  std::vector<std::array<std::vector<double>, NC>> Values;
  Eigen::VectorXd InverseDiagonal0;
};

TransCutMultiresSolver::TransCutMultiresSolver()
  : Internal_(new Internals)
{
}

TransCutMultiresSolver::~TransCutMultiresSolver() = default;

void TransCutMultiresSolver::BuildOperators()
{
  const int L = Hierarchy_.GetNumberOfLevels();
  Operators_.assign(std::max(0, L - 1), CoarseOperator());
  for (int l = 0; l + 1 < L; ++l)
  {
    const CsrPattern& fine = l == 0 ? Hierarchy_.GetLevel(0).Graph : Operators_[l - 1].GetPattern();
    // Eq. 17: substitute eq. 16 into eq. 15 for the retained rows.
    Operators_[l].Build(Hierarchy_.GetLevel(l), fine, Hierarchy_.GetLevel(l + 1).Graph,
      CoarseOperator::Kind::Injection, Threads_);
  }
  Internal_->Values.assign(Operators_.size(), {});
}

void TransCutMultiresSolver::ComputeValues(const DiffusionSystem& system)
{
  InverseDiagonal(Hierarchy_.GetLevel(0).Graph,
    { system.Values[0].data(), system.Values[1].data(), system.Values[2].data() }, 1,
    Internal_->InverseDiagonal0, GetName(), 0);
  std::vector<double> interleaved;
  for (std::size_t l = 0; l < Operators_.size(); ++l)
  {
    const std::size_t nnz = Operators_[l].GetPattern().Columns.size();
    interleaved.resize(3 * nnz);
    std::array<const double*, NC> fine;
    if (l == 0)
    {
      fine = { system.Values[0].data(), system.Values[1].data(), system.Values[2].data() };
    }
    else
    {
      fine = { Internal_->Values[l - 1][0].data(), Internal_->Values[l - 1][1].data(),
        Internal_->Values[l - 1][2].data() };
    }
    Operators_[l].Compute(fine, 1, interleaved.data(), Threads_);
    for (int c = 0; c < NC; ++c)
    {
      auto& v = Internal_->Values[l][c];
      v.resize(nnz);
      for (std::size_t k = 0; k < nnz; ++k)
      {
        v[k] = interleaved[3 * k + c];
      }
    }
  }
}

Eigen::SparseMatrix<double, Eigen::RowMajor, int> TransCutMultiresSolver::GetCoarseMatrix(
  int l, int c) const
{
  const CsrPattern& p = Operators_.at(l - 1).GetPattern();
  const auto& v = Internal_->Values.at(l - 1)[c];
  return Eigen::Map<const RowMatrix>(
    p.Size, p.Size, static_cast<int>(v.size()), p.Offsets.data(), p.Columns.data(), v.data());
}

bool TransCutMultiresSolver::Solve(const DiffusionSystem& system,
  std::array<Eigen::VectorXd, NumberOfChannels>& x, bool warmStart,
  std::array<LinearSolveStats, NumberOfChannels>& stats)
{
  CheckSystem(system);
  const int n = system.NumberOfUnknowns;
  const double nnz0 = std::max<double>(1.0, static_cast<double>(system.ColumnIndices.size()));
  const int L = Hierarchy_.GetNumberOfLevels();
  Eigen::VectorXd xi = Eigen::VectorXd::Zero(3 * static_cast<long long>(n));
  std::array<double, NC> coarseWork{};
  const bool warm = warmStart && x[0].size() == n && x[1].size() == n && x[2].size() == n;
  if (warm)
  {
    // Relight / paint: the previous solution is the initial guess (paper,
    // Sec. 6.1); the coarse levels are skipped.
    Interleave(x, xi);
  }
  else if (L > 1)
  {
    // Sec. 4.2: b^{l+1}_i = b^l_i on the retained vertices.
    std::vector<std::array<Eigen::VectorXd, NC>> b(L);
    b[0] = system.RightHandSide;
    for (int l = 0; l + 1 < L; ++l)
    {
      const auto& ids = Hierarchy_.GetLevel(l).CoarseIds;
      const int nc = Hierarchy_.GetLevel(l + 1).Graph.Size;
      for (int c = 0; c < NC; ++c)
      {
        b[l + 1][c].resize(nc);
        for (std::size_t i = 0; i < ids.size(); ++i)
        {
          if (ids[i] >= 0)
          {
            b[l + 1][c][ids[i]] = b[l][c][i];
          }
        }
      }
    }
    // Coarsest to finest: BiCGSTAB on the non-symmetric coarse systems,
    // each initialised by eq. 16 from the next coarser solution.
    Eigen::VectorXd coarse; // interleaved solution of level l + 1
    for (int l = L - 1; l >= 1; --l)
    {
      if (Progress_ && !Progress_(0.1 * (L - l) / L))
      {
        return false;
      }
      const int nl = Hierarchy_.GetLevel(l).Graph.Size;
      Eigen::VectorXd guess = Eigen::VectorXd::Zero(3 * static_cast<long long>(nl));
      if (l < L - 1)
      {
        Prolongate(Hierarchy_.GetLevel(l), coarse.data(), guess.data());
      }
      const CsrPattern& p = Operators_[l - 1].GetPattern();
      Eigen::VectorXd solution(guess.size());
      for (int c = 0; c < NC; ++c)
      {
        const auto& v = Internal_->Values[l - 1][c];
        Eigen::Map<const RowMatrix> a(
          nl, nl, static_cast<int>(v.size()), p.Offsets.data(), p.Columns.data(), v.data());
        Eigen::BiCGSTAB<RowMatrix, Eigen::DiagonalPreconditioner<double>> bicg;
        bicg.setTolerance(CoarseTol_);
        bicg.setMaxIterations(CoarseMaxIter_);
        bicg.compute(a);
        Eigen::VectorXd g(nl);
        for (int i = 0; i < nl; ++i)
        {
          g[i] = guess[3 * static_cast<long long>(i) + c];
        }
        Eigen::VectorXd s = b[l][c].squaredNorm() > 0.0 ? Eigen::VectorXd(bicg.solveWithGuess(b[l][c], g))
                                                        : Eigen::VectorXd::Zero(nl);
        coarseWork[c] +=
          static_cast<double>(bicg.iterations()) * (2.0 * v.size() + 10.0 * nl) + 2.0 * nl;
        // The paper notes the coarse systems may be singular: a failed
        // solve (non-finite) falls back to the interpolated guess.
        if (!s.allFinite())
        {
          s = g;
        }
        for (int i = 0; i < nl; ++i)
        {
          solution[3 * static_cast<long long>(i) + c] = s[i];
        }
      }
      coarse.swap(solution);
    }
    Prolongate(Hierarchy_.GetLevel(0), coarse.data(), xi.data());
    for (int l = 0; l + 1 < L; ++l)
    {
      for (int c = 0; c < NC; ++c)
      {
        coarseWork[c] += Hierarchy_.GetLevel(l).InterpolationColumns.size();
      }
    }
  }
  // Level 0: Jacobi-preconditioned CG (the matrix is SPD).
  const double flops = nnz0 + 6.0 * n;
  JacobiApply jacobi{ &Internal_->InverseDiagonal0 };
  const bool done = BlockedPCG(system, jacobi, xi, RelTol_, MaxIter_, stats, flops,
    Progress_ ? std::function<bool(double)>([this](double f) { return Progress_(0.1 + 0.9 * f); })
              : std::function<bool(double)>(),
    MinIter_);
  for (int c = 0; c < NC; ++c)
  {
    stats[c].SpMVEquivalents += coarseWork[c] / nnz0;
  }
  Deinterleave(xi, x);
  return done;
}

std::size_t TransCutMultiresSolver::GetMemoryBytes() const
{
  std::size_t bytes = Hierarchy_.GetMemoryBytes();
  for (const auto& op : Operators_)
  {
    bytes += op.GetMemoryBytes();
  }
  for (const auto& level : Internal_->Values)
  {
    for (const auto& v : level)
    {
      bytes += v.size() * sizeof(double);
    }
  }
  return bytes;
}

} // namespace translucency
