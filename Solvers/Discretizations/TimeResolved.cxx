// Time-resolved diffusion: VertexDiffusionSolver::SolveTimeResolved and the
// time gates (TimeResolved.h has the equations and the scheme).
#include "TimeResolved.h"

#include "Error.h"
#include "TetMesh.h"
#include "Timer.h"
#include "VertexDiffusionSolver.h"

#include "AggregationMultigrid.h"
#include "SolutionRecycler.h"

#include "Strings.h"

#include <Eigen/IterativeLinearSolvers>

#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>

namespace translucency
{

long long TimeGates::GetStepsBeforeStart() const
{
  if (!(Start > 0.0))
  {
    return 0;
  }
  // A tolerance so that T0 = k x step (up to rounding) gives k steps.
  return static_cast<long long>(std::ceil(Start / GetTimeStep() * (1.0 - 1e-12)));
}

int TimeGates::ChooseStepsPerGate(double absorptionRate) const
{
  if (StepsPerGate > 0)
  {
    return StepsPerGate;
  }
  const double needed = std::ceil(GetWidth() * absorptionRate / MaximumDecayPerStep);
  return static_cast<int>(std::min<double>(
    std::max<double>(DefaultStepsPerGate, std::isfinite(needed) ? needed : 0.0),
    MaximumStepsPerGate + 1.0)); // beyond the limit: Check() says so
}

std::string TimeGates::Check() const
{
  if (StepsPerGate == 0)
  {
    TimeGates chosen = *this;
    chosen.StepsPerGate = DefaultStepsPerGate;
    return chosen.Check();
  }
  std::ostringstream out;
  out.precision(10);
  if (!std::isfinite(Start) || !std::isfinite(End))
  {
    out << "T0 = " << Start << " ns and T1 = " << End << " ns must be finite";
  }
  else if (Start < 0.0)
  {
    out << "T0 = " << Start << " ns is negative (the pulse is at t = 0; expected T0 >= 0)";
  }
  else if (!(End > Start))
  {
    out << "T1 = " << End << " ns is not after T0 = " << Start << " ns (expected T0 < T1)";
  }
  else if (Count < 1)
  {
    out << "N = " << Count << " gates (expected N >= 1)";
  }
  else if (Count > MaximumTimeGates)
  {
    out << "N = " << Count << " gates is more than the limit of " << MaximumTimeGates;
  }
  else if (StepsPerGate < 0 || StepsPerGate > MaximumStepsPerGate)
  {
    out << StepsPerGate << " steps per gate (expected 1.." << MaximumStepsPerGate
        << ", or 0 for automatic)";
  }
  else if (End > MaximumEnd)
  {
    out << "T1 = " << End << " ns is later than " << MaximumEnd
        << " ns (1 ms): light in a diffusing object is absorbed or has left it within "
           "microseconds, so the gates would hold nothing but zeros (or overflow)";
  }
  else if (!(GetTimeStep() >= MinimumTimeStep) || !std::isfinite(Start / GetTimeStep()))
  {
    out << "the gates are too narrow: the time step " << GetTimeStep() << " ns (gate width "
        << GetWidth() << " ns / " << StepsPerGate << " steps) is below " << MinimumTimeStep
        << " ns (1 fs), where light moves less than a micrometre and the diffusion model "
           "(valid after a few mean free times, picoseconds) says nothing";
  }
  else if (Start / GetTimeStep() + 1.0 * Count * StepsPerGate > MaximumTimeSteps)
  {
    out << "these gates need " << std::ceil(Start / GetTimeStep()) + 1.0 * Count * StepsPerGate
        << " time steps of " << GetTimeStep() << " ns (" << StepsPerGate
        << " per gate, from t = 0 to T1 = " << End << " ns); the limit is " << MaximumTimeSteps
        << ": use fewer or wider gates, or fewer steps per gate (the automatic choice takes "
        << DefaultStepsPerGate << ", more where mu_a c_m dt would exceed "
        << MaximumDecayPerStep << ")";
  }
  return out.str();
}

void TimeGates::Validate() const
{
  const std::string fault = Check();
  if (!fault.empty())
  {
    std::ostringstream out;
    out.precision(10);
    out << "time gates " << Start << "," << End << "," << Count << ": " << fault;
    throw Error(out.str());
  }
}

namespace
{

using Matrix = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;
using JacobiCG = Eigen::ConjugateGradient<Matrix, Eigen::Lower | Eigen::Upper,
  Eigen::DiagonalPreconditioner<double>>;

using Channels = std::array<Eigen::VectorXd, NumberOfChannels>;

/// Loops over fewer unknowns than this run on one thread (a parallel region
/// costs more than the work; blocked::ParallelThreshold's rule).
constexpr int StepParallelThreshold = 8192;

/**
 * The mass matrix M on the system's pattern, and its diagonal when every
 * off-diagonal value is 0 (the lumped mass of divergence): M x is then one
 * product per value instead of a pass over the pattern.
 */
struct MassMatrix
{
  const DiffusionSystem* System = nullptr;
  std::vector<double> Values;   ///< one per non-zero of System's pattern
  std::vector<double> Diagonal; ///< n values if M is diagonal, else empty

  void Set(const DiffusionSystem& system, std::vector<double> values)
  {
    System = &system;
    Values = std::move(values);
    Diagonal.assign(static_cast<std::size_t>(system.NumberOfUnknowns), 0.0);
    for (int i = 0; i < system.NumberOfUnknowns; ++i)
    {
      for (int k = system.RowOffsets[i]; k < system.RowOffsets[i + 1]; ++k)
      {
        if (system.ColumnIndices[k] == i)
        {
          Diagonal[i] += Values[k];
        }
        else if (Values[k] != 0.0)
        {
          Diagonal.clear();
          return;
        }
      }
    }
  }

  /// Row i of M x for the three channels.
  void Row(int i, const std::array<const double*, NumberOfChannels>& x, double* y) const
  {
    if (!Diagonal.empty())
    {
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        y[c] = Diagonal[i] * x[c][i];
      }
      return;
    }
    const int* rows = System->RowOffsets.data();
    const int* cols = System->ColumnIndices.data();
    double sum[NumberOfChannels] = {};
    for (int k = rows[i]; k < rows[i + 1]; ++k)
    {
      const double m = Values[k];
      const int j = cols[k];
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        sum[c] += m * x[c][j];
      }
    }
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      y[c] = sum[c];
    }
  }
};

/// Pointers to the channels' data.
std::array<const double*, NumberOfChannels> Data(const Channels& v)
{
  return { v[0].data(), v[1].data(), v[2].data() };
}

} // namespace

void VertexDiffusionSolver::SetTimeStepRecycledSolutions(int k)
{
  if (k < 0 || k > SolutionRecycler::MaxCapacity)
  {
    throw Error(GetName() + ": time-step recycled solutions " + std::to_string(k) +
      " (expected 0.." + std::to_string(SolutionRecycler::MaxCapacity) + ")");
  }
  TimeStepRecycled_ = k;
}

bool VertexDiffusionSolver::SolveTimeResolved(const DiffusionProblem& problem,
  const TimeGates& gates, const std::vector<Detector>& detectors,
  const std::vector<int>& snapshotGates, TimeResolvedResult& result, SolverReport& report)
{
  if (!problem.Mesh || !problem.Material || !problem.Irradiance)
  {
    throw Error(GetName() + ": the problem needs a mesh, a material and an irradiance");
  }
  gates.Validate();
  const OpticalProperties& material = *problem.Material;
  material.Validate(problem.Mesh->GetNumberOfTets());
  double absorptionRate = 0.0; // the largest mu_a c_m, 1/ns
  for (std::size_t t = 0; t < material.RefractiveIndex.size(); ++t)
  {
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      absorptionRate = std::max(absorptionRate, material.AbsorptionCoefficient[3 * t + c] *
          SpeedOfLightMillimetresPerNanosecond / material.RefractiveIndex[t]);
    }
  }
  TimeGates used = gates;
  used.StepsPerGate = gates.ChooseStepsPerGate(absorptionRate);
  used.Validate();
  for (int g : snapshotGates)
  {
    if (g < 0 || g >= gates.Count)
    {
      std::ostringstream out;
      out << GetName() << ": snapshot gate " << g << " (expected 0.." << gates.Count - 1
          << ", the gates are numbered from 0)";
      throw Error(out.str());
    }
  }
  const TetMesh& mesh = *problem.Mesh;
  const std::vector<double>& irradiance = *problem.Irradiance;
  report = SolverReport();
  report.Solver = GetName();
  report.Assembly = "full";
  result = TimeResolvedResult();
  result.Gates = used;
  result.TimeStep = used.GetTimeStep();
  result.SnapshotGates = snapshotGates;

  auto start = Clock::now();
  // The detectors' footprints, located once (not at every gate; a detector
  // off the surface is an error before the stepping).
  const std::vector<DetectorFootprint> footprints =
    detectors.empty() ? std::vector<DetectorFootprint>() : LocateDetectors(mesh, detectors);
  std::vector<double> sourceLoad;
  if (problem.HasInteriorSources())
  {
    sourceLoad = problem.InteriorSources->ComputeLoad(mesh, material);
  }
  DiffusionSystem system; // K and b of the continuous-wave solve
  // The Robin coefficients of the model (the Fresnel moments with
  // extended-moments; the detectors read with the same).
  const Fresnel::BoundaryRule rule = problem.Collimated == CollimatedModel::ExtendedMoments
    ? Fresnel::BoundaryRule::Moments
    : Fresnel::BoundaryRule::Fit;
  Discretization_->SetBoundaryRule(rule);
  Discretization_->Assemble(mesh, material, irradiance, system);
  if (!sourceLoad.empty())
  {
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      for (int i = 0; i < system.NumberOfUnknowns; ++i)
      {
        system.RightHandSide[c][i] += 4.0 * sourceLoad[3 * static_cast<std::size_t>(i) + c];
      }
    }
  }
  // The extended collimated model: the beam enters at t = 0 and reaches
  // the optical path eta s at tau = eta s / c, so its volume source is a
  // delayed pulse per point (CollimatedSource.h). Its load is split between
  // the two solve times around tau (ComputeCollimatedTimeLoad): the end
  // time of every linear solve of the run, sub-steps included, times[0] = 0
  // the pulse (DiffuseOptics.md, "Collimated beams in the frequency and time domain").
  const long long before = used.GetStepsBeforeStart();
  const bool extended = IsExtendedCollimatedModel(problem.Collimated);
  CollimatedSource collimated;
  std::vector<CollimatedDeposit> deposits;
  if (extended)
  {
    collimated = ComputeCollimatedSource(mesh, material, problem.Lights, problem.Shadows);
    std::vector<double> times(1, 0.0);
    const auto schedule = [&times](long long steps, double dt, bool fromPulse, double t0) {
      const long long eulerSteps = fromPulse ? TimeGates::PulseEulerSteps : 1;
      const int subSteps = fromPulse ? TimeGates::PulseEulerSubSteps : 1;
      const double h = dt / subSteps;
      for (long long s = 0; s < steps; ++s)
      {
        for (int j = 0; s < eulerSteps && j < subSteps; ++j)
        {
          times.push_back(t0 + static_cast<double>(s) * dt + (j + 1) * h);
        }
        if (s >= eulerSteps)
        {
          times.push_back(t0 + static_cast<double>(s + 1) * dt);
        }
      }
    };
    if (before > 0)
    {
      schedule(before, used.Start / static_cast<double>(before), true, 0.0);
    }
    schedule(static_cast<long long>(used.Count) * used.StepsPerGate, used.GetTimeStep(),
      before == 0, used.Start);
    deposits = ComputeCollimatedTimeLoad(mesh, material, collimated, times);
  }
  // M: the mass matrix times 1 / c_m = eta / c (ns/mm), the same for the
  // three channels (eta is per tet).
  const int numTets = mesh.GetNumberOfTets();
  const std::size_t nnz = system.ColumnIndices.size();
  std::vector<double> coefficient(3 * static_cast<std::size_t>(numTets));
  for (int t = 0; t < numTets; ++t)
  {
    const double value = material.RefractiveIndex[t] / SpeedOfLightMillimetresPerNanosecond;
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      coefficient[3 * static_cast<std::size_t>(t) + c] = value;
    }
  }
  MassMatrix mass;
  {
    std::array<std::vector<double>, NumberOfChannels> masses;
    for (auto& values : masses)
    {
      values.assign(nnz, 0.0);
    }
    if (!Discretization_->AddMass(mesh, coefficient, masses))
    {
      throw Error(GetName() + ": this discretisation has no time-resolved solve");
    }
    mass.Set(system, std::move(masses[0]));
  }
  // The step matrices a M / dt + K share K's pattern. They are solved, the
  // three channels together, by the linear solver a continuous-wave Solve()
  // would use (SetLinearSolver's name, or by size: multigrid-agg from
  // LargeSystemUnknowns on), set up once for the pattern (its hierarchy is
  // kept for the whole run) and again for the values when a / dt changes
  // (twice per run, three times with T0 > 0).
  DiffusionSystem step;
  step.NumberOfUnknowns = system.NumberOfUnknowns;
  step.RowOffsets = system.RowOffsets;
  step.ColumnIndices = system.ColumnIndices;
  std::unique_ptr<LinearSolver> linear = CreateLinearSolver(ToLower(LinearSolver_.empty()
      ? GetDefaultLinearSolverName(system.NumberOfUnknowns)
      : LinearSolver_)); // throws, listing the known names
  linear->SetRelTol(RelTol_);
  linear->SetMaxIter(MaxIter_);
  if (auto* agg = dynamic_cast<AggregationMultigridSolver*>(linear.get()))
  {
    // Each step starts from the A-norm-best combination of the extrapolated
    // guess and the last solutions of the same step matrix (forgotten when
    // the matrix changes: Setup); double precision, so exact at any RelTol.
    agg->SetRecycleInDoublePrecision(true);
    agg->SetRecycledSolutions(TimeStepRecycled_);
  }
  report.LinearSolver = linear->GetName();
  // cg-jacobi: Eigen's CG per channel with its diagonal kept per step matrix
  // (the registry's cg-jacobi rebuilds it at every Solve, one more pass over
  // the matrix per step).
  bool jacobi = linear->GetName() == "cg-jacobi";
  // The default (no name given) at multigrid-agg sizes starts with Jacobi:
  // when the mass term a M / dt dominates the steps, Jacobi-CG needs as few
  // iterations as the multigrid (5-6 per step on the time-resolved tests'
  // meshes) and the cycle is pure extra cost (4x slower there); when it does
  // not (18 per step on the 200k-tet bunny with 100 gates), the multigrid
  // is 3x faster. So the first AdaptiveSteps BDF2 steps decide:
  // a mean above AdaptiveIterations Jacobi iterations per channel switches
  // to the multigrid for the rest of the run (DiffuseOptics.md).
  constexpr int AdaptiveSteps = 4;
  constexpr double AdaptiveIterations = 10.0;
  const bool adaptive = !jacobi && LinearSolver_.empty();
  if (adaptive)
  {
    jacobi = true;
    report.LinearSolver = "cg-jacobi";
  }
  long long adaptiveSolves = 0, adaptiveIterations = 0;
  bool linearSetUp = false;
  bool bdf2Step = false; // the solve is a BDF2 step (set by runSegment)
  std::array<JacobiCG, NumberOfChannels> cg;
  double matrixFactor = -1.0; // a / dt of step.Values
  bool structure = true;      // the first set-up builds the structure
  const auto setMatrix = [&](double factor) {
    if (factor == matrixFactor)
    {
      return;
    }
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      step.Values[c].resize(nnz);
      for (std::size_t k = 0; k < nnz; ++k)
      {
        step.Values[c][k] = system.Values[c][k] + factor * mass.Values[k];
      }
      step.RightHandSide[c].setZero(system.NumberOfUnknowns);
    }
    for (int c = 0; c < NumberOfChannels && (jacobi || adaptive); ++c)
    {
      cg[c].setTolerance(RelTol_);
      cg[c].setMaxIterations(MaxIter_);
      cg[c].compute(step.Matrix(c));
      if (cg[c].info() != Eigen::Success)
      {
        throw Error(GetName() + ": the time-step matrix has a zero or non-finite diagonal");
      }
    }
    try
    {
      if (!jacobi)
      {
        linear->Setup(step, &mesh, structure || !linearSetUp);
        linearSetUp = true;
      }
    }
    catch (const Error& e)
    {
      throw Error(GetName() + ": the time-step matrix (a M / dt + K, a / dt = " +
        std::to_string(factor) + "/ns) is not SPD: " + e.what());
    }
    structure = false;
    matrixFactor = factor;
  };
  report.SetupMilliseconds = MillisecondsSince(start);

  start = Clock::now();
  const int n = system.NumberOfUnknowns;
  // Per channel: phi at the last two steps, M phi at the last two steps,
  // the integral over the current gate and over [T0, T1].
  std::array<Eigen::VectorXd, NumberOfChannels> phi, phiPrevious, massPhi, massPhiPrevious, gate,
    integral;
  // The collimated deposits: the next one to inject, the solve counter
  // (deposit Time j enters solve j; 0 is the pulse), and what the current
  // backward-Euler step injected (see runSegment).
  std::size_t nextDeposit = 0;
  long long solveIndex = 0;
  std::array<Eigen::VectorXd, NumberOfChannels> eulerInjected;
  // Adds 4 x the deposits of solve `j` (times `factor`) to `target` and,
  // if given, 4 x them to `injected` (the discretisations' systems are 4 x
  // the weak form, FiniteElement.h).
  const auto inject = [&](long long j, double factor,
                        std::array<Eigen::VectorXd, NumberOfChannels>& target,
                        std::array<Eigen::VectorXd, NumberOfChannels>* injected) {
    for (; nextDeposit < deposits.size() && deposits[nextDeposit].Time <= j; ++nextDeposit)
    {
      const CollimatedDeposit& d = deposits[nextDeposit];
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        target[c][d.Point] += 4.0 * factor * d.Load[c];
        if (injected)
        {
          (*injected)[c][d.Point] += 4.0 * d.Load[c];
        }
      }
    }
  };
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    phi[c].setZero(n);
    phiPrevious[c].setZero(n);
    massPhi[c] = system.RightHandSide[c]; // M phi(0+) = b: the pulse
    massPhiPrevious[c].setZero(n);
    eulerInjected[c].setZero(extended ? n : 0);
    gate[c].setZero(n);
    integral[c].setZero(n);
    report.Converged[c] = true;
  }
  inject(0, 1.0, massPhi, nullptr); // the beam at t = 0 (the entry points)
  const long long totalSteps = used.GetNumberOfSteps();
  long long stepsDone = 0;
  std::array<long long, NumberOfChannels> iterations{};
  bool pulse = true; // the next step starts from the pulse (phi is a delta)

  // One segment: `steps` steps of dt, the first backward Euler, the others
  // BDF2; `add` the step integrals to the current gate; `gateEnd(step)` after
  // every step (to close gates).
  // The integral of the last backward-Euler step, per channel: the first
  // BDF2 interval takes half of it in place of dt phi / 2, which keeps the
  // sum over the steps exactly K^-1 b (Documentation/DiffuseOptics.md).
  std::array<Eigen::VectorXd, NumberOfChannels> lastEuler;
  // One linear solve of the three channels (right-hand sides in
  // step.RightHandSide) from `next` (the guess), with the statistics.
  std::array<LinearSolveStats, NumberOfChannels> stats;
  const auto solve = [&](std::array<Eigen::VectorXd, NumberOfChannels>& next) {
    if (jacobi)
    {
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        stats[c] = LinearSolveStats();
        const Eigen::VectorXd& right = step.RightHandSide[c];
        if (right.squaredNorm() == 0.0)
        {
          next[c].setZero(n);
          stats[c].Converged = true;
          continue;
        }
        const Eigen::VectorXd guess = next[c];
        next[c] = cg[c].solveWithGuess(right, guess);
        stats[c].Iterations = static_cast<int>(cg[c].iterations());
        stats[c].RelativeResidual = cg[c].error();
        stats[c].Converged = cg[c].info() == Eigen::Success;
      }
    }
    else
    {
      linear->Solve(step, next, true, stats);
    }
    if (adaptive && jacobi && bdf2Step)
    {
      // The adaptive choice (above): after AdaptiveSteps BDF2 solves,
      // switch to the multigrid if Jacobi needed many.
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        adaptiveIterations += stats[c].Iterations;
      }
      if (++adaptiveSolves == AdaptiveSteps)
      {
        const double mean = static_cast<double>(adaptiveIterations) /
          (static_cast<double>(AdaptiveSteps) * NumberOfChannels);
        if (mean > AdaptiveIterations)
        {
          jacobi = false;
          linear->Setup(step, &mesh, true);
          linearSetUp = true;
          report.LinearSolver = "cg-jacobi, then " + linear->GetName();
        }
      }
    }
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      const int used = stats[c].Iterations;
      iterations[c] += used;
      result.MaximumStepIterations[c] = std::max(result.MaximumStepIterations[c], used);
      report.Residual[c] = std::max(report.Residual[c], stats[c].RelativeResidual);
      if (!stats[c].Converged || !next[c].allFinite())
      {
        report.Converged[c] = false;
      }
    }
  };
  std::array<Eigen::VectorXd, NumberOfChannels> next, massNext;
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    next[c].setZero(n);
    massNext[c].setZero(n);
    lastEuler[c].setZero(n);
  }
  // The per-step vector work in one pass over the unknowns each, the three
  // channels together (one OpenMP region instead of one per channel and
  // operation, no temporaries): `before(i)` before the solve, `after(i)`
  // after it.
  const auto forEachUnknown = [n](const auto& body) {
#pragma omp parallel for schedule(static) if (n > StepParallelThreshold)
    for (int i = 0; i < n; ++i)
    {
      body(i);
    }
  };
  const auto runSegment = [&](long long steps, double dt, bool add,
                            const std::function<void(long long)>& afterStep) -> bool {
    // From the pulse: TimeGates::PulseEulerSteps backward-Euler steps of
    // PulseEulerSubSteps sub-steps each (see there); a restart from a
    // smooth field: one step.
    const bool fromPulse = pulse;
    const long long eulerSteps = fromPulse ? TimeGates::PulseEulerSteps : 1;
    const int subSteps = fromPulse ? TimeGates::PulseEulerSubSteps : 1;
    const double h = dt / subSteps;
    const double halfDt = 0.5 * dt;
    for (long long s = 0; s < steps; ++s)
    {
      const bool euler = s < eulerSteps;
      setMatrix(euler ? 1.0 / h : 1.5 / dt);
      bdf2Step = !euler;
      if (euler)
      {
        // (M / h + K) x' = M x / h, subSteps times; the right rectangle.
        if (extended)
        {
          for (int c = 0; c < NumberOfChannels; ++c)
          {
            eulerInjected[c].setZero(n);
          }
        }
        for (int j = 0; j < subSteps; ++j)
        {
          const bool zeroGuess = pulse && j == 0;
          // The first sub-step starts from phi and M phi.
          const Channels& massFrom = j == 0 ? massPhi : massNext;
          forEachUnknown([&](int i) {
            for (int c = 0; c < NumberOfChannels; ++c)
            {
              step.RightHandSide[c][i] = massFrom[c][i] / h;
              if (j == 0)
              {
                next[c][i] = zeroGuess ? 0.0 : phi[c][i];
                lastEuler[c][i] = 0.0;
              }
            }
          });
          // (M / h + K) x' = (M x + w) / h: the beam's deposits w of this
          // sub-step.
          inject(++solveIndex, 1.0 / h, step.RightHandSide, &eulerInjected);
          solve(next);
          const auto x = Data(next);
          forEachUnknown([&](int i) {
            double m[NumberOfChannels];
            mass.Row(i, x, m);
            for (int c = 0; c < NumberOfChannels; ++c)
            {
              lastEuler[c][i] += h * next[c][i];
              massNext[c][i] = m[c];
              if (add && j + 1 == subSteps)
              {
                gate[c][i] += lastEuler[c][i];
              }
            }
          });
        }
      }
      else
      {
        // BDF2: (3/2 M / dt + K) phi' = M (2 phi - phi_prev / 2) / dt;
        // the trapezoid. The guess: the extrapolation 2 phi - phi_prev (the
        // multigrid step solver then combines it with its recycled
        // solutions).
        const bool first = s == eulerSteps;
        forEachUnknown([&](int i) {
          for (int c = 0; c < NumberOfChannels; ++c)
          {
            step.RightHandSide[c][i] = (2.0 * massPhi[c][i] - 0.5 * massPhiPrevious[c][i]) / dt;
            next[c][i] = first ? phi[c][i] : 2.0 * phi[c][i] - phiPrevious[c][i];
          }
        });
        inject(++solveIndex, 1.0 / dt, step.RightHandSide, nullptr); // + w / dt
        solve(next);
        const auto x = Data(next);
        forEachUnknown([&](int i) {
          double m[NumberOfChannels];
          mass.Row(i, x, m);
          for (int c = 0; c < NumberOfChannels; ++c)
          {
            massNext[c][i] = m[c];
            if (add)
            {
              gate[c][i] += first ? 0.5 * lastEuler[c][i] + halfDt * next[c][i]
                                  : halfDt * (phi[c][i] + next[c][i]);
            }
          }
        });
      }
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        phiPrevious[c].swap(phi[c]);
        phi[c].swap(next[c]);
        massPhiPrevious[c].swap(massPhi[c]);
        massPhi[c].swap(massNext[c]);
        if (euler && extended)
        {
          // BDF2's first history term takes the state at the start of the
          // last backward-Euler step with that step's deposits in it: then
          // the gate weights (half that step's integral for the first BDF2
          // interval) still sum to exactly K^-1 (b + all deposits), the
          // continuous-wave solution (DiffuseOptics.md).
          massPhiPrevious[c] += eulerInjected[c];
        }
      }
      pulse = false;
      ++stepsDone;
      afterStep(s);
      if (!ReportProgress(static_cast<double>(stepsDone) / static_cast<double>(totalSteps)))
      {
        return false;
      }
    }
    return true;
  };

  // [0, T0]: steps of at most the gate step, nothing recorded.
  if (before > 0 &&
    !runSegment(before, used.Start / static_cast<double>(before), false, [](long long) {}))
  {
    return false;
  }
  // The gates.
  const double width = used.GetWidth();
  std::vector<double> irradianceOverWidth;
  if (!detectors.empty() && before == 0)
  {
    // The q delta(t) term of the exitance, averaged over the first gate.
    irradianceOverWidth = irradiance;
    for (double& q : irradianceOverWidth)
    {
      q /= width;
    }
  }
  // The unscattered beam itself, E_c delta(t - tau) per point: its gate
  // (-1 outside [T0, T1]) per beam and point, for the snapshots and the
  // integral; the detectors read the diffuse field (as in continuous wave).
  std::vector<std::vector<int>> beamGate(collimated.Beams.size());
  if (extended)
  {
    report.CollimatedFluence.assign(3 * static_cast<std::size_t>(mesh.GetNumberOfPoints()), 0.0);
    for (std::size_t b = 0; b < collimated.Beams.size(); ++b)
    {
      const CollimatedSource::Beam& beam = collimated.Beams[b];
      beamGate[b].assign(beam.OpticalPath.size(), -1);
      for (std::size_t i = 0; i < beam.OpticalPath.size(); ++i)
      {
        const double tau = beam.OpticalPath[i] / SpeedOfLightMillimetresPerNanosecond;
        const double g = std::floor((tau - used.Start) / width);
        if (tau >= used.Start && g < used.Count)
        {
          beamGate[b][i] = static_cast<int>(g);
          for (int c = 0; c < NumberOfChannels; ++c)
          {
            report.CollimatedFluence[3 * i + c] += beam.Fluence[3 * i + c];
          }
        }
      }
    }
    report.CollimatedEntering = collimated.Entering;
    report.CollimatedScattered = collimated.Scattered;
    report.CollimatedAbsorbed = collimated.Absorbed;
  }
  std::vector<double> points;
  std::array<Eigen::VectorXd, NumberOfChannels> average;
  const auto closeGate = [&](long long s) {
    if ((s + 1) % used.StepsPerGate != 0)
    {
      return;
    }
    const int g = static_cast<int>(s / used.StepsPerGate);
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      integral[c] += gate[c];
      average[c] = gate[c] / width;
      gate[c].setZero();
    }
    const auto snapshot = std::find(snapshotGates.begin(), snapshotGates.end(), g);
    if (detectors.empty() && snapshot == snapshotGates.end())
    {
      return;
    }
    Discretization_->ToPointFluence(mesh, system, average, points);
    if (!detectors.empty())
    {
      result.Readings.push_back(ReadDetectorFootprints(mesh, material, footprints, points,
        g == 0 && !irradianceOverWidth.empty() ? &irradianceOverWidth : nullptr, rule));
    }
    if (snapshot != snapshotGates.end())
    {
      // The gate average of the unscattered pulses arriving in this gate.
      for (std::size_t b = 0; b < collimated.Beams.size(); ++b)
      {
        for (std::size_t i = 0; i < beamGate[b].size(); ++i)
        {
          for (int c = 0; c < NumberOfChannels && beamGate[b][i] == g; ++c)
          {
            points[3 * i + c] += collimated.Beams[b].Fluence[3 * i + c] / width;
          }
        }
      }
      result.Snapshots.resize(snapshotGates.size());
      for (std::size_t k = 0; k < snapshotGates.size(); ++k)
      {
        if (snapshotGates[k] == g)
        {
          result.Snapshots[k] = points;
        }
      }
    }
  };
  if (!runSegment(static_cast<long long>(used.Count) * used.StepsPerGate,
        used.GetTimeStep(), true, closeGate))
  {
    return false;
  }
  if (nextDeposit != deposits.size())
  {
    // The schedule above and runSegment disagree: a bug, not an input error.
    throw Error(GetName() + ": internal error: " +
      std::to_string(deposits.size() - nextDeposit) +
      " collimated deposits were not injected (time-step schedule mismatch)");
  }
  Discretization_->ToPointFluence(mesh, system, integral, result.IntegratedFluence);
  for (std::size_t k = 0; k < report.CollimatedFluence.size(); ++k)
  {
    result.IntegratedFluence[k] += report.CollimatedFluence[k]; // phi_d + E_c, as in CW
  }
  result.NumberOfSteps = stepsDone;
  report.SolveMilliseconds = MillisecondsSince(start);
  report.NumberOfUnknowns = n;
  report.NumberOfNonZeros = static_cast<long long>(nnz);
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    report.Iterations[c] = static_cast<int>(std::min<long long>(iterations[c], 2147483647LL));
  }
  // The system, the mass and step values, 10 vectors per channel, the
  // linear solver's own memory and the snapshots.
  report.MemoryBytes = system.GetMemoryBytes() + (1 + NumberOfChannels) * nnz * sizeof(double) +
    10 * NumberOfChannels * static_cast<std::size_t>(n) * sizeof(double) +
    linear->GetMemoryBytes() +
    result.Snapshots.size() * 3 * static_cast<std::size_t>(n) * sizeof(double);
  return true;
}

} // namespace translucency
