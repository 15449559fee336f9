#include "InverseDiffusion.h"

#include "Error.h"
#include "TetMesh.h"
#include "Timer.h"

#include <Eigen/Cholesky>
#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>

namespace translucency
{

namespace
{
const char* const ChannelNames[3] = { "R", "G", "B" };
constexpr double Infinity = std::numeric_limits<double>::infinity();

/**
 * Minimise's line search, the golden section (Press et al. 1992, as the
 * paper cites) of the bracket a < b < c (f(b) < f(a), f(b) <= f(c)) until
 * it is narrower than `tolerance` x the mean of the inner points (at most 40
 * steps). `f` keeps the best point itself.
 */
template <typename Objective>
void GoldenSection(Objective& f, double a, double b, double c, double fb, double tolerance)
{
  const double R = 0.618034, C = 1.0 - R;
  double x0 = a, x1, x2, x3 = c, f1, f2;
  if (std::abs(c - b) > std::abs(b - a))
  {
    x1 = b;
    f1 = fb;
    x2 = b + C * (c - b);
    f2 = f(x2);
  }
  else
  {
    x2 = b;
    f2 = fb;
    x1 = b - C * (b - a);
    f1 = f(x1);
  }
  for (int k = 0; k < 40 &&
       std::abs(x3 - x0) > tolerance * 0.5 * (std::abs(x1) + std::abs(x2));
       ++k)
  {
    if (f2 < f1)
    {
      x0 = x1;
      x1 = x2;
      f1 = f2;
      x2 = R * x2 + C * x3;
      f2 = f(x2);
    }
    else
    {
      x3 = x2;
      x2 = x1;
      f2 = f1;
      x1 = R * x1 + C * x0;
      f1 = f(x1);
    }
  }
}

} // namespace

/// The measurements of one colour channel, in solver form.
struct InverseDiffusion::Channel
{
  int Index = 0;
  Eigen::MatrixXd Source;                ///< column m: b_m (TransCut eq. 12)
  std::vector<std::vector<int>> Points;  ///< observed point ids of pattern m
  std::vector<Eigen::VectorXd> Offset;   ///< per observed point: L_meas + beta q
  double SumMeasuredSquared = 0.0;       ///< sum_m sum_i L_mi^2
  double DataScale = 1.0;                ///< 1 / SumMeasuredSquared
};

/// One forward pass: a factorisation and the M fluences.
struct InverseDiffusion::Workspace
{
  DiffusionForwardModel::Factor Factor;
  Eigen::MatrixXd Phi; ///< column m: the fluence of pattern m
  std::vector<double> Kappa, Mu;
  double Objective = Infinity;
  double Data = 0.0;
};

/// Polak-Ribiere CG with golden-section line search (paper Table I) on the
/// log-parameters of one channel, either per element or homogeneous.
class InverseDiffusion::Optimiser
{
public:
  Optimiser(const InverseDiffusion& owner, const Channel& channel)
    : Owner_(owner)
    , Model_(owner.Model_)
    , Channel_(channel)
    , NumElements_(owner.Model_.GetNumberOfElements())
  {
  }

  int Evaluations = 0;
  int Gradients = 0;
  int Tangents = 0;
  double EvaluationSeconds = 0.0;
  double GradientSeconds = 0.0;
  double TangentSeconds = 0.0;

  /// Forward pass at the given parameters into ws (F = inf if not finite).
  void Evaluate(const std::vector<double>& kappa, const std::vector<double>& mu, Workspace& ws)
  {
    const auto start = Clock::now();
    ++Evaluations;
    ws.Kappa = kappa;
    ws.Mu = mu;
    ws.Objective = Infinity;
    for (int e = 0; e < NumElements_; ++e)
    {
      if (!(std::isfinite(kappa[e]) && kappa[e] > 0.0 && std::isfinite(mu[e]) && mu[e] > 0.0))
      {
        EvaluationSeconds += SecondsSince(start);
        return; // outside the domain: the line search sees +inf
      }
    }
    Model_.Factorize(kappa.data(), mu.data(), ws.Factor);
    const Eigen::VectorXd& alpha = Model_.GetReadOutFluenceWeights();
    const int numPatterns = static_cast<int>(Channel_.Source.cols());
    // The M forward solves with one factorisation, as one blocked solve.
    ws.Factor.Solve(Channel_.Source, ws.Phi);
    double data = 0.0;
    for (int m = 0; m < numPatterns; ++m)
    {
      const std::vector<int>& pts = Channel_.Points[m];
      const Eigen::VectorXd& offset = Channel_.Offset[m];
      for (size_t k = 0; k < pts.size(); ++k)
      {
        // r = L_meas - L^R, L^R = alpha phi - beta q (TransCut eq. 3).
        const double r = offset[k] - alpha[pts[k]] * ws.Phi(pts[k], m);
        data += r * r; // paper Sec. 4.2, f_m
      }
    }
    ws.Data = data * Channel_.DataScale; // normalised by sum of measured L^2
    data = ws.Data;
    ws.Objective = data + Owner_.Lambda_ * Owner_.Roughness(kappa);
    if (!std::isfinite(ws.Objective))
    {
      ws.Objective = Infinity;
    }
    EvaluationSeconds += SecondsSince(start);
  }

  /// dF/dkappa and dF/dmu at ws (a finite forward pass) by the adjoint method.
  void Gradient(const Workspace& ws, std::vector<double>& gKappa, std::vector<double>& gMu)
  {
    const auto start = Clock::now();
    ++Gradients;
    gKappa.assign(NumElements_, 0.0);
    gMu.assign(NumElements_, 0.0);
    const Eigen::VectorXd& alpha = Model_.GetReadOutFluenceWeights();
    const int n = Model_.GetNumberOfPoints();
    const int numPatterns = static_cast<int>(Channel_.Source.cols());
    Eigen::MatrixXd source = Eigen::MatrixXd::Zero(n, numPatterns), adjoint;
    for (int m = 0; m < numPatterns; ++m)
    {
      // Adjoint source dF/dphi = -2 alpha r on the observed points: the
      // discrete form of the virtual illumination of paper eq. 6.
      const std::vector<int>& pts = Channel_.Points[m];
      const Eigen::VectorXd& offset = Channel_.Offset[m];
      for (size_t k = 0; k < pts.size(); ++k)
      {
        const int i = pts[k];
        const double r = offset[k] - alpha[i] * ws.Phi(i, m);
        source(i, m) = -2.0 * Channel_.DataScale * alpha[i] * r;
      }
    }
    // Adjoint equation (paper eq. 5-6): M lambda = dF/dphi, with the same
    // SPD matrix as the forward problem (M = M^T): M solves, one blocked solve.
    ws.Factor.Solve(source, adjoint);
    for (int m = 0; m < numPatterns; ++m)
    {
      // Paper eq. 7, discrete: dF/dp = -lambda^T (dM/dp) phi.
      Model_.AccumulateGradient(adjoint.col(m), ws.Phi.col(m), gKappa.data(), gMu.data());
    }
    // Regulariser: d/dkappa of lambda sum (k_e - k_f)^2 / d_ef^2 (the discrete
    // -2 lambda Laplacian(kappa) of Appendix A).
    const std::vector<int>& pairs = Model_.GetElementNeighbours();
    const std::vector<double>& weights = Model_.GetElementNeighbourWeights();
    const double lambda = Owner_.Lambda_;
    if (lambda != 0.0)
    {
      for (size_t p = 0; p < pairs.size(); p += 2)
      {
        const int e = pairs[p], f = pairs[p + 1];
        const double w = weights[p / 2];
        const double g = 2.0 * lambda * w * (ws.Kappa[e] - ws.Kappa[f]);
        gKappa[e] += g;
        gKappa[f] -= g;
      }
    }
    GradientSeconds += SecondsSince(start);
  }

  /// Parameters from the optimisation variables: x = (log kappa, log mu),
  /// per element or (homogeneous) one pair broadcast to every element.
  void Expand(const Eigen::VectorXd& x, bool homogeneous, std::vector<double>& kappa,
    std::vector<double>& mu) const
  {
    kappa.resize(NumElements_);
    mu.resize(NumElements_);
    for (int e = 0; e < NumElements_; ++e)
    {
      kappa[e] = std::exp(homogeneous ? x[0] : x[e]);
      mu[e] = std::exp(homogeneous ? x[1] : x[NumElements_ + e]);
    }
  }

  /// Gradient with respect to x (chain rule through exp and the broadcast).
  Eigen::VectorXd ReducedGradient(const Workspace& ws, bool homogeneous)
  {
    std::vector<double> gk, gm;
    Gradient(ws, gk, gm);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(homogeneous ? 2 : 2 * NumElements_);
    for (int e = 0; e < NumElements_; ++e)
    {
      const double a = gk[e] * ws.Kappa[e], b = gm[e] * ws.Mu[e];
      if (homogeneous)
      {
        g[0] += a;
        g[1] += b;
      }
      else
      {
        g[e] = a;
        g[NumElements_ + e] = b;
      }
    }
    return g;
  }

  /// Forward pass at the optimisation variables x; +inf where the
  /// factorisation fails (e.g. far out along a search direction).
  void EvaluateAt(const Eigen::VectorXd& x, bool homogeneous, Workspace& ws)
  {
    Expand(x, homogeneous, Scratch_[0], Scratch_[1]);
    try
    {
      Evaluate(Scratch_[0], Scratch_[1], ws);
    }
    catch (const Error&)
    {
      ws.Objective = Infinity;
    }
  }

  /// The checks at the top of each optimiser iteration: "" to go on, else
  /// the stop reason (objective below the threshold, or the progress
  /// callback `tick`, if given, asked to abort).
  static std::string CheckStop(const Workspace& ws, int it, double threshold,
    const std::function<bool(int)>& tick, bool& converged)
  {
    if (ws.Objective < threshold)
    {
      converged = true;
      return "objective below threshold";
    }
    if (tick && !tick(it))
    {
      return "aborted";
    }
    return "";
  }

  /**
   * Linearisation of the scaled residual e = sqrt(DataScale) (L_meas - L)
   * at ws (F_data = |e|^2) along parameter directions k (dKappa_k, dMu_k per
   * element, in parameter units): J_k = de/ds = sqrt(DataScale) alpha
   * M^-1 (dM_k phi), since M phi = b gives dphi/ds = -M^-1 (dM_k phi) and
   * L = alpha phi - beta q (TransCut eq. 3). One blocked back-solve with
   * the factor of ws for all directions and patterns (a tangent solve costs
   * what the adjoint pass costs, not a factorisation).
   */
  void Linearise(const Workspace& ws, const std::vector<std::vector<double>>& dKappa,
    const std::vector<std::vector<double>>& dMu, Eigen::VectorXd& e, Eigen::MatrixXd& J)
  {
    const auto start = Clock::now();
    const Eigen::VectorXd& alpha = Model_.GetReadOutFluenceWeights();
    const int numPatterns = static_cast<int>(Channel_.Source.cols());
    const int numDirections = static_cast<int>(dKappa.size());
    Eigen::MatrixXd rhs(ws.Phi.rows(), numDirections * numPatterns), tangent;
    for (int k = 0; k < numDirections; ++k)
    {
      const Eigen::SparseMatrix<double> dM = Model_.DerivativeMatrix(dKappa[k].data(), dMu[k].data());
      rhs.middleCols(k * numPatterns, numPatterns) = dM * ws.Phi;
    }
    ws.Factor.Solve(rhs, tangent);
    int rows = 0;
    for (int m = 0; m < numPatterns; ++m)
    {
      rows += static_cast<int>(Channel_.Points[m].size());
    }
    const double scale = std::sqrt(Channel_.DataScale);
    e.resize(rows);
    J.resize(rows, numDirections);
    int row = 0;
    for (int m = 0; m < numPatterns; ++m)
    {
      const std::vector<int>& pts = Channel_.Points[m];
      const Eigen::VectorXd& offset = Channel_.Offset[m];
      for (size_t k = 0; k < pts.size(); ++k, ++row)
      {
        const int i = pts[k];
        e[row] = scale * (offset[k] - alpha[i] * ws.Phi(i, m));
        for (int d = 0; d < numDirections; ++d)
        {
          J(row, d) = scale * alpha[i] * tangent(i, d * numPatterns + m);
        }
      }
    }
    ++Tangents;
    TangentSeconds += SecondsSince(start);
  }

  /**
   * Homogeneous fit of h = (log kappa, log mu) by Levenberg-Marquardt on the
   * linearised residual (our choice; the paper, Sec. 4.2, uses its CG
   * procedure for these two unknowns, available as
   * HomogeneousMethod::ConjugateGradient): per iteration one tangent solve
   * (J, two directions) and, per trial, one forward pass. `current` holds
   * the forward pass at h on entry and at the final h on return.
   */
  std::string FitHomogeneous(Eigen::VectorXd& h, int maxIter, double threshold,
    std::unique_ptr<Workspace>& current, std::vector<InverseDiffusionIteration>& history,
    const std::function<bool(int)>& tick, int& iterations, bool& converged)
  {
    auto trial = std::make_unique<Workspace>();
    std::vector<std::vector<double>> dKappa(2), dMu(2);
    Eigen::VectorXd e;
    Eigen::MatrixXd J;
    auto linearise = [&]() {
      // d/dlog kappa = kappa dM/dkappa, d/dlog mu = mu dM/dmu (every element).
      dKappa[0] = current->Kappa;
      dMu[0].assign(NumElements_, 0.0);
      dKappa[1].assign(NumElements_, 0.0);
      dMu[1] = current->Mu;
      Linearise(*current, dKappa, dMu, e, J);
    };
    iterations = 0;
    converged = false;
    linearise();
    // dF/dh = 2 J^T e (the regulariser is 0 and flat for a homogeneous kappa).
    Eigen::Vector2d g = 2.0 * J.transpose() * e;
    history.push_back(
      { Channel_.Index, "homogeneous", 0, current->Objective, current->Data, g.norm(), 0.0, 1 });
    double damping = 1e-3;
    for (int it = 1; it <= maxIter; ++it)
    {
      const std::string stop = CheckStop(*current, it, threshold, tick, converged);
      if (!stop.empty())
      {
        return stop;
      }
      const Eigen::Matrix2d A = J.transpose() * J;
      const Eigen::Vector2d b = -(J.transpose() * e);
      const double f0 = current->Objective;
      int evaluations = 0;
      bool accepted = false;
      Eigen::Vector2d step = Eigen::Vector2d::Zero();
      for (int attempt = 0; attempt < 12 && !accepted; ++attempt)
      {
        // (J^T J + nu diag(J^T J)) delta = -J^T e, at most a factor e per
        // scalar per step.
        Eigen::Matrix2d damped = A;
        damped.diagonal() *= 1.0 + damping;
        step = damped.ldlt().solve(b);
        const double largest = step.cwiseAbs().maxCoeff();
        if (!std::isfinite(largest))
        {
          break;
        }
        if (largest > 1.0)
        {
          step /= largest;
        }
        EvaluateAt(h + step, true, *trial);
        ++evaluations;
        if (trial->Objective < f0)
        {
          std::swap(current, trial);
          h += step;
          damping = std::max(1e-7, 0.1 * damping);
          accepted = true;
        }
        else
        {
          damping *= 10.0;
        }
      }
      if (!accepted)
      {
        return "homogeneous fit found no decrease";
      }
      iterations = it;
      linearise();
      g = 2.0 * J.transpose() * e;
      history.push_back({ Channel_.Index, "homogeneous", it, current->Objective, current->Data,
        g.norm(), step.norm(), evaluations });
      if ((f0 - current->Objective) <= Owner_.HomogeneousTolerance_ * f0)
      {
        return "homogeneous fit converged";
      }
    }
    const std::string stop = CheckStop(*current, 0, threshold, nullptr, converged);
    return stop.empty() ? "iteration limit" : stop;
  }

  /**
   * Gauss-Newton estimate of the minimiser of F(x + s d) (heterogeneous
   * stage): s = -F'(0) / F''(0), F'(0) = g.d exactly (adjoint gradient),
   * F''(0) ~ 2 |J_d|^2 (tangent solve along d) + the regulariser's
   * 2 lambda sum w (dkappa_e - dkappa_f)^2. 0 if not a usable estimate.
   */
  double GaussNewtonStep(const Workspace& ws, const Eigen::VectorXd& g, const Eigen::VectorXd& d)
  {
    std::vector<std::vector<double>> dKappa(1), dMu(1);
    dKappa[0].resize(NumElements_);
    dMu[0].resize(NumElements_);
    for (int e = 0; e < NumElements_; ++e)
    {
      dKappa[0][e] = ws.Kappa[e] * d[e]; // chain rule through exp
      dMu[0][e] = ws.Mu[e] * d[NumElements_ + e];
    }
    Eigen::VectorXd e;
    Eigen::MatrixXd J;
    Linearise(ws, dKappa, dMu, e, J);
    double curvature = 2.0 * J.col(0).squaredNorm();
    const std::vector<int>& pairs = Model_.GetElementNeighbours();
    const std::vector<double>& weights = Model_.GetElementNeighbourWeights();
    for (size_t p = 0; Owner_.Lambda_ != 0.0 && p < pairs.size(); p += 2)
    {
      const double diff = dKappa[0][pairs[p]] - dKappa[0][pairs[p + 1]];
      curvature += 2.0 * Owner_.Lambda_ * weights[p / 2] * diff * diff;
    }
    const double slope = g.dot(d);
    const double step = -slope / curvature;
    return std::isfinite(step) && step > 0.0 ? step : 0.0;
  }

  /**
   * Paper Table I from x. `current` holds the forward pass at x on entry and
   * the one at the final x on return. Rows go to history. Returns the stop
   * reason; `converged` says whether F < threshold.
   */
  std::string Minimise(Eigen::VectorXd& x, bool homogeneous, int maxIter, double threshold,
    std::unique_ptr<Workspace>& current, std::vector<InverseDiffusionIteration>& history,
    const std::function<bool(int)>& tick, int& iterations, bool& converged)
  {
    const char* stage = homogeneous ? "homogeneous" : "heterogeneous";
    auto trial = std::make_unique<Workspace>();
    iterations = 0;
    converged = false;
    Eigen::VectorXd g = ReducedGradient(*current, homogeneous);
    Eigen::VectorXd p = -g; // Table I: p_0 = d_0 = -z(kappa_0, mu_0)
    Eigen::VectorXd d = p;
    history.push_back({ Channel_.Index, stage, 0, current->Objective, current->Data, g.norm(), 0.0, 1 });
    double lastMove = 0.0;
    bool retried = false;
    for (int it = 1; it <= maxIter; ++it)
    {
      const std::string stop = CheckStop(*current, it, threshold, tick, converged);
      if (!stop.empty())
      {
        return stop;
      }
      if (g.norm() == 0.0)
      {
        return "zero gradient";
      }
      if (g.dot(d) >= 0.0)
      {
        d = p; // not a descent direction: restart with steepest descent
      }
      // Golden-section line search along d (Table I).
      const double f0 = current->Objective;
      double bestStep = 0.0;
      int evaluations = 0;
      auto f = [&](double s) -> double {
        EvaluateAt(x + s * d, homogeneous, *trial);
        ++evaluations;
        const double value = trial->Objective;
        if (value < current->Objective)
        {
          std::swap(current, trial);
          bestStep = s;
        }
        return value;
      };
      const double dMax = d.cwiseAbs().maxCoeff();
      double s0 = lastMove > 0.0 ? lastMove / d.norm() : 0.5 / dMax;
      // Our choice (not in Table I): start the bracket at the Gauss-Newton
      // minimiser along d (a tangent solve, ~ the cost of an adjoint pass).
      const double sGaussNewton =
        !homogeneous && Owner_.GaussNewtonLineSearch_ ? GaussNewtonStep(*current, g, d) : 0.0;
      if (sGaussNewton > 0.0)
      {
        s0 = sGaussNewton;
      }
      s0 = std::min(s0, 1.0 / dMax); // at most a factor e per parameter on the first try
      // Bracket a < b < c with f(b) < f(a), f(b) <= f(c). From a
      // Gauss-Newton b the first c is b / 0.618 (b at the golden point of
      // [0, c], the minimum expected near b); otherwise golden expansion.
      double a = 0.0, b = s0, c = 0.0, fa = f0, fb = f(s0), fc = 0.0;
      if (fb < fa)
      {
        c = b + (sGaussNewton > 0.0 ? 0.618034 : 1.618034) * (b - a);
        fc = f(c);
        for (int k = 0; k < 30 && fc < fb; ++k)
        {
          a = b;
          fa = fb;
          b = c;
          fb = fc;
          c = b + 1.618034 * (b - a);
          fc = f(c);
        }
      }
      else
      {
        c = b;
        fc = fb;
        b = 0.381966 * c;
        fb = f(b);
        for (int k = 0; k < 40 && !(fb < fa); ++k)
        {
          c = b;
          fc = fb;
          b = 0.381966 * c;
          fb = f(b);
        }
      }
      if (fb < fa)
      {
        GoldenSection(f, a, b, c, fb, Owner_.LineSearchTolerance_);
      }
      if (bestStep == 0.0)
      {
        if (!retried)
        {
          d = p; // no decrease along the CG direction: retry steepest descent
          retried = true;
          lastMove = 0.0;
          --it;
          continue;
        }
        return "line search found no decrease";
      }
      retried = false;
      x += bestStep * d;
      lastMove = bestStep * d.norm();
      iterations = it;
      // Table I: new gradient, p_t = -z, Polak-Ribiere beta = max(0, .).
      g = ReducedGradient(*current, homogeneous);
      const Eigen::VectorXd pNew = -g;
      const double beta = std::max(0.0, pNew.dot(pNew - p) / p.squaredNorm());
      d = pNew + beta * d;
      p = pNew;
      history.push_back({ Channel_.Index, stage, it, current->Objective, current->Data, g.norm(),
        bestStep, evaluations });
      if (homogeneous && (f0 - current->Objective) <= Owner_.HomogeneousTolerance_ * f0)
      {
        return "homogeneous fit converged";
      }
    }
    const std::string stop = CheckStop(*current, 0, threshold, nullptr, converged);
    return stop.empty() ? "iteration limit" : stop;
  }

  /**
   * Run, the starting point of channel c in x (log kappa, then log mu per
   * element): the per-element start if given, else the homogeneous start
   * kappa = 1 / (3 (mu_a + sigma_s')), refined by a homogeneous fit (paper
   * Sec. 4.2; `current` then holds its last forward pass). `tick` reports
   * the progress of the fit.
   */
  void StartingPoint(int c, bool perElementStart, double threshold, Eigen::VectorXd& x,
    std::unique_ptr<Workspace>& current, std::vector<InverseDiffusionIteration>& history,
    const std::function<bool(double)>& tick, bool& converged)
  {
    const int numElements = NumElements_;
    std::vector<double> kappa, mu;
    if (perElementStart)
    {
      for (int e = 0; e < numElements; ++e)
      {
        x[e] = std::log(Owner_.InitialKappa_[3 * e + c]);
        x[numElements + e] = std::log(Owner_.InitialMuPerElement_[3 * e + c]);
      }
    }
    else
    {
      // Homogeneous start: kappa = 1 / (3 (mu_a + sigma_s')).
      Eigen::VectorXd h(2);
      h[0] = std::log(1.0 / (3.0 * (Owner_.InitialMu_[c] + Owner_.InitialSigmaS_[c])));
      h[1] = std::log(Owner_.InitialMu_[c]);
      if (Owner_.HomogeneousFit_ && Owner_.HomogeneousMaxIter_ > 0)
      {
        // Paper Sec. 4.2: initialise by a homogeneous fit of the two scalars
        // with the same conjugate-gradient procedure.
        Expand(h, true, kappa, mu);
        Evaluate(kappa, mu, *current);
        if (!std::isfinite(current->Objective))
        {
          throw Error("the objective is not finite at the initial values");
        }
        int homogeneousIterations = 0;
        auto homogeneousTick = [&](int it) { return tick(0.1 * it / Owner_.HomogeneousMaxIter_); };
        if (Owner_.HomogeneousMethod_ == HomogeneousMethod::GaussNewton)
        {
          FitHomogeneous(h, Owner_.HomogeneousMaxIter_, threshold, current, history,
            homogeneousTick, homogeneousIterations, converged);
        }
        else
        {
          Minimise(h, true, Owner_.HomogeneousMaxIter_, threshold, current, history,
            homogeneousTick, homogeneousIterations, converged);
        }
      }
      x.head(numElements).setConstant(h[0]);
      x.tail(numElements).setConstant(h[1]);
    }
  }

private:
  const InverseDiffusion& Owner_;
  const DiffusionForwardModel& Model_;
  const Channel& Channel_;
  int NumElements_;
  std::vector<double> Scratch_[2]; ///< kappa, mu of EvaluateAt
};

InverseDiffusion::Channel InverseDiffusion::BuildChannel(int c) const
{
  Channel ch;
  ch.Index = c;
  const Eigen::VectorXd& beta = Model_.GetReadOutIrradianceWeights();
  const int n = Model_.GetNumberOfPoints();
  ch.Source.resize(n, static_cast<Eigen::Index>(Irradiance_.size()));
  for (size_t m = 0; m < Irradiance_.size(); ++m)
  {
    Eigen::VectorXd q(n);
    for (int i = 0; i < n; ++i)
    {
      q[i] = Irradiance_[m][3 * i + c];
    }
    ch.Source.col(m) = Model_.Source(q);
    ch.Points.push_back(Observed_[m]);
    Eigen::VectorXd offset(Observed_[m].size());
    for (size_t k = 0; k < Observed_[m].size(); ++k)
    {
      const int i = Observed_[m][k];
      const double l = Radiance_[m][3 * i + c];
      offset[k] = l + beta[i] * q[i];
      ch.SumMeasuredSquared += l * l;
    }
    ch.Offset.push_back(offset);
  }
  if (!(ch.SumMeasuredSquared > 0.0))
  {
    throw Error(std::string("InverseDiffusion: the measured radiance of channel ") +
      ChannelNames[c] + " is 0 at every observed point: nothing to fit");
  }
  ch.DataScale = 1.0 / ch.SumMeasuredSquared;
  return ch;
}

InverseDiffusion::InverseDiffusion(const DiffusionForwardModel& model)
  : Model_(model)
{
}

void InverseDiffusion::SetMeasurements(std::vector<std::vector<double>> irradiance,
  std::vector<std::vector<double>> radiance, std::vector<std::vector<unsigned char>> observed)
{
  const int n = Model_.GetNumberOfPoints();
  const size_t expected = 3 * static_cast<size_t>(n);
  if (irradiance.empty())
  {
    throw Error("InverseDiffusion: no illumination pattern given");
  }
  if (irradiance.size() != radiance.size())
  {
    std::ostringstream os;
    os << "InverseDiffusion: " << irradiance.size() << " illumination patterns but "
       << radiance.size() << " radiance measurements (one per pattern expected)";
    throw Error(os.str());
  }
  if (!observed.empty() && observed.size() != irradiance.size())
  {
    std::ostringstream os;
    os << "InverseDiffusion: " << observed.size() << " observation masks for "
       << irradiance.size() << " patterns (one per pattern, or none)";
    throw Error(os.str());
  }
  const TetMesh& mesh = Model_.GetMesh();
  std::vector<std::vector<int>> points(irradiance.size());
  for (size_t m = 0; m < irradiance.size(); ++m)
  {
    if (irradiance[m].size() != expected || radiance[m].size() != expected)
    {
      std::ostringstream os;
      os << "InverseDiffusion: pattern " << m << " has " << irradiance[m].size()
         << " irradiance and " << radiance[m].size() << " radiance values; " << expected
         << " expected (3 per point, " << n << " points)";
      throw Error(os.str());
    }
    const bool hasMask = !observed.empty() && !observed[m].empty();
    if (hasMask && observed[m].size() != static_cast<size_t>(n))
    {
      std::ostringstream os;
      os << "InverseDiffusion: the mask of pattern " << m << " has " << observed[m].size()
         << " values for " << n << " points";
      throw Error(os.str());
    }
    for (int i = 0; i < n; ++i)
    {
      for (int c = 0; c < 3; ++c)
      {
        const double q = irradiance[m][3 * i + c];
        if (!(std::isfinite(q) && q >= 0.0))
        {
          std::ostringstream os;
          os << "InverseDiffusion: irradiance of pattern " << m << ", point " << i << ", channel "
             << ChannelNames[c] << " is " << q << ": must be finite and >= 0";
          throw Error(os.str());
        }
      }
      const bool obs = hasMask ? observed[m][i] != 0 : mesh.IsBoundaryPoint(i);
      if (!obs)
      {
        continue;
      }
      if (!mesh.IsBoundaryPoint(i))
      {
        std::ostringstream os;
        os << "InverseDiffusion: the mask of pattern " << m << " marks point " << i
           << " as observed, but it is not on the boundary";
        throw Error(os.str());
      }
      for (int c = 0; c < 3; ++c)
      {
        const double l = radiance[m][3 * i + c];
        if (!std::isfinite(l))
        {
          std::ostringstream os;
          os << "InverseDiffusion: measured radiance of pattern " << m << ", point " << i
             << ", channel " << ChannelNames[c] << " is " << l << ": must be finite";
          throw Error(os.str());
        }
      }
      points[m].push_back(i);
    }
    if (points[m].empty())
    {
      std::ostringstream os;
      os << "InverseDiffusion: pattern " << m << " has no observed point (empty mask)";
      throw Error(os.str());
    }
  }
  Irradiance_ = std::move(irradiance);
  Radiance_ = std::move(radiance);
  Observed_ = std::move(points);
}

void InverseDiffusion::SetInitialParameters(std::vector<double> kappa, std::vector<double> mu)
{
  InitialKappa_ = std::move(kappa);
  InitialMuPerElement_ = std::move(mu);
}

double InverseDiffusion::Roughness(const std::vector<double>& kappa) const
{
  const std::vector<int>& pairs = Model_.GetElementNeighbours();
  const std::vector<double>& weights = Model_.GetElementNeighbourWeights();
  double r = 0.0;
  for (size_t p = 0; p < pairs.size(); p += 2)
  {
    const int e = pairs[p], f = pairs[p + 1];
    const double dk = kappa[e] - kappa[f];
    // paper Sec. 4.2: |grad kappa|^2 over the volume, finite-volume form
    // sum over element faces of (A_ef / d_ef) (kappa_e - kappa_f)^2.
    r += weights[p / 2] * dk * dk;
  }
  return r;
}

namespace
{
void CheckChannel(int channel)
{
  if (channel < 0 || channel > 2)
  {
    throw Error("InverseDiffusion: channel must be 0, 1 or 2");
  }
}
} // namespace

double InverseDiffusion::Objective(int channel, const std::vector<double>& kappa,
  const std::vector<double>& mu, std::vector<double>* gKappa, std::vector<double>* gMu) const
{
  CheckChannel(channel);
  if (Irradiance_.empty())
  {
    throw Error("InverseDiffusion: no measurements (call SetMeasurements)");
  }
  const int numElements = Model_.GetNumberOfElements();
  if (static_cast<int>(kappa.size()) != numElements || static_cast<int>(mu.size()) != numElements)
  {
    throw Error("InverseDiffusion::Objective: kappa and mu need one value per element");
  }
  const Channel ch = BuildChannel(channel);
  Optimiser opt(*this, ch);
  Workspace ws;
  // Validate the values here: Evaluate returns +inf for them silently.
  for (int e = 0; e < numElements; ++e)
  {
    if (!(std::isfinite(kappa[e]) && kappa[e] > 0.0 && std::isfinite(mu[e]) && mu[e] > 0.0))
    {
      std::ostringstream os;
      os << "InverseDiffusion::Objective: element " << e << " has kappa = " << kappa[e]
         << " mm and mu_a = " << mu[e] << " 1/mm: both must be finite and > 0";
      throw Error(os.str());
    }
  }
  opt.Evaluate(kappa, mu, ws);
  if (gKappa && gMu)
  {
    opt.Gradient(ws, *gKappa, *gMu);
  }
  return ws.Objective;
}

namespace
{
/// Run: the starting values, checked (per element: 3 values of kappa and
/// mu_a per element, all > 0; else per channel: mu_a and sigma_s' > 0).
void CheckInitialValues(int numElements, bool perElementStart,
  const std::vector<double>& initialKappa, const std::vector<double>& initialMuPerElement,
  const std::array<double, 3>& initialMu, const std::array<double, 3>& initialSigmaS)
{
  if (perElementStart)
  {
    if (initialKappa.size() != 3 * static_cast<size_t>(numElements) ||
      initialMuPerElement.size() != 3 * static_cast<size_t>(numElements))
    {
      std::ostringstream os;
      os << "InverseDiffusion: initial parameters need 3 values per element (" << numElements
         << " elements); got " << initialKappa.size() << " kappa and "
         << initialMuPerElement.size() << " mu_a values";
      throw Error(os.str());
    }
    for (size_t k = 0; k < initialKappa.size(); ++k)
    {
      if (!(std::isfinite(initialKappa[k]) && initialKappa[k] > 0.0 &&
            std::isfinite(initialMuPerElement[k]) && initialMuPerElement[k] > 0.0))
      {
        std::ostringstream os;
        os << "InverseDiffusion: initial value of element " << k / 3 << ", channel "
           << ChannelNames[k % 3] << ": kappa = " << initialKappa[k]
           << " mm, mu_a = " << initialMuPerElement[k] << " 1/mm; both must be > 0";
        throw Error(os.str());
      }
    }
  }
  else
  {
    for (int c = 0; c < 3; ++c)
    {
      if (!(std::isfinite(initialMu[c]) && initialMu[c] > 0.0 &&
            std::isfinite(initialSigmaS[c]) && initialSigmaS[c] > 0.0))
      {
        std::ostringstream os;
        os << "InverseDiffusion: initial value of channel " << ChannelNames[c]
           << ": mu_a = " << initialMu[c] << " 1/mm, sigma_s' = " << initialSigmaS[c]
           << " 1/mm; both must be finite and > 0";
        throw Error(os.str());
      }
    }
  }
}

} // namespace

InverseDiffusionResult InverseDiffusion::Run()
{
  if (Irradiance_.empty())
  {
    throw Error("InverseDiffusion: no measurements (call SetMeasurements)");
  }
  if (!(Lambda_ >= 0.0) || !std::isfinite(Lambda_))
  {
    std::ostringstream os;
    os << "InverseDiffusion: lambda = " << Lambda_ << " must be finite and >= 0";
    throw Error(os.str());
  }
  if (MaxIter_ < 0)
  {
    throw Error("InverseDiffusion: the iteration limit must be >= 0");
  }
  const int numElements = Model_.GetNumberOfElements();
  const bool perElementStart = !InitialKappa_.empty() || !InitialMuPerElement_.empty();
  CheckInitialValues(numElements, perElementStart, InitialKappa_, InitialMuPerElement_,
    InitialMu_, InitialSigmaS_);

  InverseDiffusionResult result;
  result.Kappa.assign(3 * static_cast<size_t>(numElements), 0.0);
  result.Absorption.assign(3 * static_cast<size_t>(numElements), 0.0);
  std::array<std::vector<InverseDiffusionIteration>, 3> history;
  std::array<int, 3> evaluations{}, gradients{};
  std::array<double, 3> evaluationSeconds{}, gradientSeconds{}, tangentSeconds{};
  std::array<int, 3> tangents{};
  std::array<std::atomic<double>, 3> fraction;
  for (auto& f : fraction)
  {
    f = 0.0;
  }
  std::atomic<bool> aborted(false);
  std::array<std::string, 3> errors;

  const int numThreads = NumberOfThreads_ > 0 ? NumberOfThreads_ : omp_get_max_threads();
  // One thread per channel as soon as there are 2 cores or more: the channels
  // need different numbers of forward passes, and 3 channels on 2 threads
  // leave one thread idle while the other runs its second channel; 3 threads
  // on 2 cores share the cores until the end. One BLAS thread per channel
  // thread while the channels run in parallel.
  const int channelThreads = numThreads > 1 ? 3 : 1;
  const int blasThreads = channelThreads > 1 ? DiffusionForwardModel::SetBlasThreads(1) : 0;
#pragma omp parallel for schedule(dynamic, 1) num_threads(channelThreads)
  for (int c = 0; c < 3; ++c)
  {
    try
    {
      const Channel ch = BuildChannel(c);
      // Paper Sec. 4.2: epsilon = 1e-4 x sum_x L_o(x)^2; our data term is
      // already divided by sum_x L_o(x)^2.
      const double threshold = RelativeThreshold_;

      Optimiser opt(*this, ch);
      auto tick = [&](double f) {
        fraction[c] = f;
        if (omp_get_thread_num() == 0 && Progress_)
        {
          const double total = (fraction[0] + fraction[1] + fraction[2]) / 3.0;
          if (!Progress_(total))
          {
            aborted = true;
          }
        }
        return !aborted.load();
      };

      auto current = std::make_unique<Workspace>();
      std::vector<double> kappa, mu;
      Eigen::VectorXd x(2 * numElements);
      int iterations = 0;
      bool converged = false;
      opt.StartingPoint(c, perElementStart, threshold, x, current, history[c], tick, converged);
      // After a homogeneous fit `current` already holds the forward pass at x
      // (the same parameters, broadcast): no second factorisation.
      const bool reused = std::isfinite(current->Objective) && !current->Kappa.empty();
      if (!reused)
      {
        opt.Expand(x, false, kappa, mu);
        opt.Evaluate(kappa, mu, *current);
      }
      const size_t firstHeterogeneousRow = history[c].size();
      if (!std::isfinite(current->Objective))
      {
        throw Error("the objective is not finite at the initial values");
      }
      result.StopReason[c] = opt.Minimise(x, false, MaxIter_, threshold, current, history[c],
        [&](int it) { return tick(0.1 + 0.9 * it / std::max(1, MaxIter_)); }, iterations,
        converged);
      if (reused && history[c].size() > firstHeterogeneousRow)
      {
        history[c][firstHeterogeneousRow].Evaluations = 0; // no new forward pass
      }
      tick(1.0);
      opt.Expand(x, false, kappa, mu);
      for (int e = 0; e < numElements; ++e)
      {
        result.Kappa[3 * e + c] = kappa[e];
        result.Absorption[3 * e + c] = mu[e];
      }
      result.Objective[c] = current->Objective;
      result.Threshold[c] = threshold;
      result.Iterations[c] = iterations;
      result.Converged[c] = converged;
      evaluations[c] = opt.Evaluations;
      gradients[c] = opt.Gradients;
      evaluationSeconds[c] = opt.EvaluationSeconds;
      gradientSeconds[c] = opt.GradientSeconds;
      tangents[c] = opt.Tangents;
      tangentSeconds[c] = opt.TangentSeconds;
    }
    catch (const std::exception& e)
    {
      errors[c] = e.what();
    }
  }
  if (blasThreads > 0)
  {
    DiffusionForwardModel::SetBlasThreads(blasThreads);
  }
  for (int c = 0; c < 3; ++c)
  {
    if (!errors[c].empty())
    {
      throw Error(std::string("InverseDiffusion, channel ") + ChannelNames[c] + ": " + errors[c]);
    }
    result.History.insert(result.History.end(), history[c].begin(), history[c].end());
    result.Evaluations += evaluations[c];
    result.Gradients += gradients[c];
    result.EvaluationSeconds += evaluationSeconds[c];
    result.GradientSeconds += gradientSeconds[c];
    result.Tangents += tangents[c];
    result.TangentSeconds += tangentSeconds[c];
  }
  result.Aborted = aborted;
  return result;
}

std::vector<std::vector<double>> InverseDiffusion::PredictRadiance(
  const DiffusionForwardModel& model, const std::vector<double>& kappa,
  const std::vector<double>& mu, const std::vector<std::vector<double>>& irradiance)
{
  const int numElements = model.GetNumberOfElements();
  const int n = model.GetNumberOfPoints();
  if (kappa.size() != 3 * static_cast<size_t>(numElements) ||
    mu.size() != 3 * static_cast<size_t>(numElements))
  {
    throw Error("InverseDiffusion::PredictRadiance: kappa and mu need 3 values per element");
  }
  for (size_t m = 0; m < irradiance.size(); ++m)
  {
    if (irradiance[m].size() != 3 * static_cast<size_t>(n))
    {
      std::ostringstream os;
      os << "InverseDiffusion::PredictRadiance: pattern " << m << " has " << irradiance[m].size()
         << " irradiance values for " << n << " points (3 per point expected)";
      throw Error(os.str());
    }
  }
  std::vector<std::vector<double>> radiance(irradiance.size(), std::vector<double>(3 * n, 0.0));
  const Eigen::VectorXd& alpha = model.GetReadOutFluenceWeights();
  const Eigen::VectorXd& beta = model.GetReadOutIrradianceWeights();
  std::string error;
#pragma omp parallel for schedule(dynamic, 1)
  for (int c = 0; c < 3; ++c)
  {
    try
    {
      std::vector<double> k(numElements), u(numElements);
      for (int e = 0; e < numElements; ++e)
      {
        k[e] = kappa[3 * e + c];
        u[e] = mu[3 * e + c];
      }
      DiffusionForwardModel::Factor factor;
      model.Factorize(k.data(), u.data(), factor);
      const int numPatterns = static_cast<int>(irradiance.size());
      Eigen::MatrixXd q(n, numPatterns), b(n, numPatterns), phi;
      for (int m = 0; m < numPatterns; ++m)
      {
        for (int i = 0; i < n; ++i)
        {
          q(i, m) = irradiance[m][3 * i + c];
        }
        b.col(m) = model.Source(q.col(m));
      }
      factor.Solve(b, phi); // all patterns in one blocked solve
      for (int m = 0; m < numPatterns; ++m)
      {
        for (int i = 0; i < n; ++i)
        {
          if (alpha[i] != 0.0)
          {
            radiance[m][3 * i + c] = alpha[i] * phi(i, m) - beta[i] * q(i, m); // TransCut eq. 3
          }
        }
      }
    }
    catch (const std::exception& e)
    {
#pragma omp critical
      error = e.what();
    }
  }
  if (!error.empty())
  {
    throw Error(error);
  }
  return radiance;
}

double EstimateGridBlockMemory(double nx, double ny, double nz)
{
  return 6.0 * nx * ny * nz * 500.0 + (nx + 1.0) * (ny + 1.0) * (nz + 1.0) * 200.0;
}

void BuildGridBlock(int nx, int ny, int nz, const double origin[3], const double size[3],
  std::vector<double>& points, std::vector<int>& tets, std::vector<int>& tetElement,
  std::size_t memoryLimit)
{
  if (nx < 1 || ny < 1 || nz < 1)
  {
    std::ostringstream os;
    os << "BuildGridBlock: grid " << nx << "x" << ny << "x" << nz << " must be at least 1x1x1";
    throw Error(os.str());
  }
  for (int d = 0; d < 3; ++d)
  {
    if (!(std::isfinite(size[d]) && size[d] > 0.0 && std::isfinite(origin[d])))
    {
      throw Error("BuildGridBlock: the block size must be finite and > 0");
    }
  }
  {
    const double voxels = static_cast<double>(nx) * ny * nz;
    std::ostringstream what;
    what << "BuildGridBlock: a grid of " << nx << "x" << ny << "x" << nz << " voxels ("
         << FormatNumber(6.0 * voxels) << " tets)";
    CheckMemory(what.str(), EstimateGridBlockMemory(nx, ny, nz), memoryLimit,
      "use fewer voxels");
    if (6.0 * voxels * 4.0 >= static_cast<double>(std::numeric_limits<int>::max()))
    {
      throw Error(what.str() + " has more tets than the 32-bit indices hold: use fewer voxels");
    }
  }
  const int px = nx + 1, py = ny + 1, pz = nz + 1;
  points.resize(3 * static_cast<size_t>(px) * py * pz);
  for (int k = 0; k < pz; ++k)
  {
    for (int j = 0; j < py; ++j)
    {
      for (int i = 0; i < px; ++i)
      {
        const size_t id = i + static_cast<size_t>(px) * (j + static_cast<size_t>(py) * k);
        points[3 * id] = origin[0] + size[0] * i / nx;
        points[3 * id + 1] = origin[1] + size[1] * j / ny;
        points[3 * id + 2] = origin[2] + size[2] * k / nz;
      }
    }
  }
  // Kuhn (Freudenthal) subdivision: 6 tets around the diagonal 0 -> 7, one
  // per order of the three axes; faces are split consistently between voxels.
  static const int Orders[6][3] = { { 0, 1, 2 }, { 0, 2, 1 }, { 1, 0, 2 }, { 1, 2, 0 },
    { 2, 0, 1 }, { 2, 1, 0 } };
  const size_t numVoxels = static_cast<size_t>(nx) * ny * nz;
  tets.clear();
  tets.reserve(24 * numVoxels);
  tetElement.clear();
  tetElement.reserve(6 * numVoxels);
  for (int k = 0; k < nz; ++k)
  {
    for (int j = 0; j < ny; ++j)
    {
      for (int i = 0; i < nx; ++i)
      {
        const int voxel = i + nx * (j + ny * k);
        for (const auto& order : Orders)
        {
          int c[3] = { i, j, k };
          int ids[4];
          ids[0] = c[0] + px * (c[1] + py * c[2]);
          for (int s = 0; s < 3; ++s)
          {
            ++c[order[s]];
            ids[s + 1] = c[0] + px * (c[1] + py * c[2]);
          }
          tets.insert(tets.end(), ids, ids + 4);
          tetElement.push_back(voxel);
        }
      }
    }
  }
}

void MakeBlockPatterns(const std::vector<double>& points, int rows, int cols,
  AcquisitionSetup setup, double irradiance, std::vector<std::vector<double>>& patterns,
  std::vector<std::vector<unsigned char>>& observed)
{
  if (rows < 1 || cols < 1)
  {
    throw Error("MakeBlockPatterns: the pattern grid must be at least 1x1");
  }
  if (!(std::isfinite(irradiance) && irradiance > 0.0))
  {
    throw Error("MakeBlockPatterns: the irradiance must be finite and > 0");
  }
  const size_t n = points.size() / 3;
  if (n == 0)
  {
    throw Error("MakeBlockPatterns: no points");
  }
  double lo[3] = { Infinity, Infinity, Infinity }, hi[3] = { -Infinity, -Infinity, -Infinity };
  for (size_t i = 0; i < n; ++i)
  {
    for (int d = 0; d < 3; ++d)
    {
      lo[d] = std::min(lo[d], points[3 * i + d]);
      hi[d] = std::max(hi[d], points[3 * i + d]);
    }
  }
  const double diag = std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) +
    (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
  const double tol = 1e-9 * diag;
  if (!(hi[0] - lo[0] > tol && hi[1] - lo[1] > tol && hi[2] - lo[2] > tol))
  {
    throw Error("MakeBlockPatterns: the points do not span a 3D block");
  }
  patterns.assign(static_cast<size_t>(rows) * cols, std::vector<double>(3 * n, 0.0));
  observed.assign(static_cast<size_t>(rows) * cols, std::vector<unsigned char>(n, 0));
  for (size_t i = 0; i < n; ++i)
  {
    const double* p = &points[3 * i];
    const bool litFace = std::abs(p[2] - lo[2]) <= tol;
    const bool backFace = std::abs(p[2] - hi[2]) <= tol;
    int region = -1;
    if (litFace)
    {
      const int a = std::min(cols - 1, static_cast<int>(cols * (p[0] - lo[0]) / (hi[0] - lo[0])));
      const int b = std::min(rows - 1, static_cast<int>(rows * (p[1] - lo[1]) / (hi[1] - lo[1])));
      region = a + cols * b;
    }
    for (int m = 0; m < rows * cols; ++m)
    {
      if (m == region)
      {
        for (int c = 0; c < 3; ++c)
        {
          patterns[m][3 * i + c] = irradiance;
        }
      }
      if (setup == AcquisitionSetup::Back)
      {
        observed[m][i] = backFace ? 1 : 0;
      }
      else
      {
        observed[m][i] = (litFace && m != region) ? 1 : 0;
      }
    }
  }
}

} // namespace translucency
