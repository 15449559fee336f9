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

namespace
{

using Progress = std::function<bool(double)>;

/// Schedule: the gates with their steps per gate chosen for the largest
/// absorption rate mu_a c_m (TimeGates::ChooseStepsPerGate), checked, and
/// the snapshot gates checked against them.
TimeGates ScheduleGates(const std::string& who, const OpticalProperties& material,
  const TimeGates& gates, const std::vector<int>& snapshotGates)
{
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
      out << who << ": snapshot gate " << g << " (expected 0.." << gates.Count - 1
          << ", the gates are numbered from 0)";
      throw Error(out.str());
    }
  }
  return used;
}

/// Schedule: the end time of every linear solve of the run (ns), sub-steps
/// included, times[0] = 0 the pulse: the time steps runSegment takes
/// (Stepper::RunSegment), for the extended collimated model's deposits.
std::vector<double> SolveTimes(const TimeGates& used)
{
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
  const long long before = used.GetStepsBeforeStart();
  if (before > 0)
  {
    schedule(before, used.Start / static_cast<double>(before), true, 0.0);
  }
  schedule(static_cast<long long>(used.Count) * used.StepsPerGate, used.GetTimeStep(),
    before == 0, used.Start);
  return times;
}

/// What the stepping solves with: K and b of the continuous-wave solve (with
/// the interior sources' load), the mass matrix, the Robin rule, and the
/// extended collimated model's source with its deposits per solve.
struct TimeResolvedSystem
{
  DiffusionSystem System;
  MassMatrix Mass;
  Fresnel::BoundaryRule Rule = Fresnel::BoundaryRule::Fit;
  bool Extended = false;
  CollimatedSource Collimated;
  std::vector<CollimatedDeposit> Deposits;
};

/// Step matrices (assembly): K and b, the deposits, and M = the mass matrix
/// times 1 / c_m = eta / c (ns/mm), the same for the three channels (eta
/// is per tet).
void AssembleTimeResolved(const std::string& who, Discretization& discretization,
  const DiffusionProblem& problem, const TimeGates& used, TimeResolvedSystem& out)
{
  const TetMesh& mesh = *problem.Mesh;
  const OpticalProperties& material = *problem.Material;
  std::vector<double> sourceLoad;
  if (problem.HasInteriorSources())
  {
    sourceLoad = problem.InteriorSources->ComputeLoad(mesh, material);
  }
  DiffusionSystem& system = out.System;
  // The Robin coefficients of the model (the Fresnel moments with
  // extended-moments; the detectors read with the same).
  out.Rule = problem.Collimated == CollimatedModel::ExtendedMoments
    ? Fresnel::BoundaryRule::Moments
    : Fresnel::BoundaryRule::Fit;
  discretization.SetBoundaryRule(out.Rule);
  discretization.Assemble(mesh, material, *problem.Irradiance, system);
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
  // time of every linear solve of the run (DiffuseOptics.md, "Collimated
  // beams in the frequency and time domain").
  out.Extended = IsExtendedCollimatedModel(problem.Collimated);
  if (out.Extended)
  {
    out.Collimated = ComputeCollimatedSource(mesh, material, problem.Lights, problem.Shadows);
    out.Deposits = ComputeCollimatedTimeLoad(mesh, material, out.Collimated, SolveTimes(used));
  }
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
  std::array<std::vector<double>, NumberOfChannels> masses;
  for (auto& values : masses)
  {
    values.assign(nnz, 0.0);
  }
  if (!discretization.AddMass(mesh, coefficient, masses))
  {
    throw Error(who + ": this discretisation has no time-resolved solve");
  }
  out.Mass.Set(system, std::move(masses[0]));
}

/**
 * Step matrices and their solver: a M / dt + K on K's pattern, solved, the
 * three channels together, by the linear solver a continuous-wave Solve()
 * would use (SetLinearSolver's name, or by size: multigrid-agg from
 * LargeSystemUnknowns on), set up once for the pattern (its hierarchy is
 * kept for the whole run) and again for the values when a / dt changes
 * (twice per run, three times with T0 > 0).
 *
 * The default (no name given) at sizes whose default is not Jacobi-CG
 * starts with Jacobi-CG (the registry's cg x jacobi entry): when the mass
 * term a M / dt dominates the steps, Jacobi-CG needs as few iterations as
 * the multigrid (5-6 per step on the time-resolved tests' meshes) and the
 * cycle is pure extra cost (4x slower there); when it does not (18 per
 * step on the 200k-tet bunny with 100 gates), the multigrid is 3x faster.
 * So the first AdaptiveSteps BDF2 steps decide: a mean above
 * AdaptiveIterations Jacobi iterations per channel switches to the
 * multigrid for the rest of the run (DiffuseOptics.md).
 */
class StepSolver
{
public:
  static constexpr int AdaptiveSteps = 4;
  static constexpr double AdaptiveIterations = 10.0;

  StepSolver(const std::string& who, const TimeResolvedSystem& base, const TetMesh& mesh,
    const std::string& linearName, bool defaultChoice, double relTol, int maxIter,
    int recycled, TimeResolvedResult& result, SolverReport& report)
    : Who_(who)
    , Base_(base)
    , Mesh_(mesh)
    , Result_(result)
    , Report_(report)
  {
    const DiffusionSystem& system = base.System;
    Step.NumberOfUnknowns = system.NumberOfUnknowns;
    Step.RowOffsets = system.RowOffsets;
    Step.ColumnIndices = system.ColumnIndices;
    Linear_ = CreateLinearSolver(linearName); // throws, listing the known names
    Linear_->SetRelTol(relTol);
    Linear_->SetMaxIter(maxIter);
    if (auto* agg = dynamic_cast<AggregationMultigridSolver*>(Linear_.get()))
    {
      // Each step starts from the A-norm-best combination of the
      // extrapolated guess and the last solutions of the same step matrix
      // (forgotten when the matrix changes: Setup); double precision, so
      // exact at any RelTol.
      agg->SetRecycleInDoublePrecision(true);
      agg->SetRecycledSolutions(recycled);
    }
    report.LinearSolver = Linear_->GetName();
    const LinearSolverRegistry::Entry& jacobi = FindLinearSolver("cg", "jacobi");
    const LinearSolverTraits& chosen =
      GetLinearSolverRegistry().Get(ResolveLinearSolverName(linearName)).Properties;
    Adaptive_ = defaultChoice &&
      !(chosen.Krylov == jacobi.Properties.Krylov &&
        chosen.Preconditioner == jacobi.Properties.Preconditioner);
    if (Adaptive_)
    {
      First_ = jacobi.Create();
      First_->SetRelTol(relTol);
      First_->SetMaxIter(maxIter);
      report.LinearSolver = First_->GetName();
    }
    Current_ = Adaptive_ ? First_.get() : Linear_.get();
  }

  /// The step matrix a M / dt + K for factor = a / dt (1/ns), with a zero
  /// right-hand side, and its solver set up (nothing when unchanged).
  void SetMatrix(double factor)
  {
    if (factor == MatrixFactor_)
    {
      return;
    }
    const DiffusionSystem& system = Base_.System;
    const std::size_t nnz = system.ColumnIndices.size();
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      Step.Values[c].resize(nnz);
      for (std::size_t k = 0; k < nnz; ++k)
      {
        Step.Values[c][k] = system.Values[c][k] + factor * Base_.Mass.Values[k];
      }
      Step.RightHandSide[c].setZero(system.NumberOfUnknowns);
    }
    try
    {
      Current_->Setup(Step, &Mesh_, Structure_);
    }
    catch (const Error& e)
    {
      throw Error(Who_ + ": the time-step matrix (a M / dt + K, a / dt = " +
        std::to_string(factor) + "/ns) is not SPD: " + e.what());
    }
    Structure_ = false;
    MatrixFactor_ = factor;
  }

  /// One linear solve of the three channels (right-hand sides in
  /// Step.RightHandSide) from `next` (the guess), with the statistics;
  /// `bdf2Step` says whether it is a BDF2 step (the adaptive choice counts
  /// those).
  void Solve(Channels& next, bool bdf2Step)
  {
    Current_->Solve(Step, next, true, Stats_);
    if (Adaptive_ && Current_ == First_.get() && bdf2Step)
    {
      // The adaptive choice (above): after AdaptiveSteps BDF2 solves,
      // switch to the multigrid if Jacobi needed many.
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        AdaptiveIterations_ += Stats_[c].Iterations;
      }
      if (++AdaptiveSolves_ == AdaptiveSteps)
      {
        const double mean = static_cast<double>(AdaptiveIterations_) /
          (static_cast<double>(AdaptiveSteps) * NumberOfChannels);
        if (mean > AdaptiveIterations)
        {
          Current_ = Linear_.get();
          Linear_->Setup(Step, &Mesh_, true);
          Report_.LinearSolver = First_->GetName() + ", then " + Linear_->GetName();
        }
      }
    }
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      const int used = Stats_[c].Iterations;
      Iterations[c] += used;
      Result_.MaximumStepIterations[c] = std::max(Result_.MaximumStepIterations[c], used);
      Report_.Residual[c] = std::max(Report_.Residual[c], Stats_[c].RelativeResidual);
      if (!Stats_[c].Converged || !next[c].allFinite())
      {
        Report_.Converged[c] = false;
      }
    }
  }

  /// The linear solvers' own memory (bytes).
  std::size_t GetMemoryBytes() const
  {
    return Linear_->GetMemoryBytes() + (First_ ? First_->GetMemoryBytes() : 0);
  }

  DiffusionSystem Step; ///< the step matrix and right-hand sides
  std::array<long long, NumberOfChannels> Iterations{};

private:
  std::string Who_;
  const TimeResolvedSystem& Base_;
  const TetMesh& Mesh_;
  TimeResolvedResult& Result_;
  SolverReport& Report_;
  std::unique_ptr<LinearSolver> Linear_; ///< the named (or default) solver
  std::unique_ptr<LinearSolver> First_;  ///< Jacobi-CG of the adaptive choice
  LinearSolver* Current_ = nullptr;
  bool Adaptive_ = false;
  long long AdaptiveSolves_ = 0, AdaptiveIterations_ = 0;
  double MatrixFactor_ = -1.0; ///< a / dt of Step.Values
  bool Structure_ = true;      ///< the first set-up builds the structure
  std::array<LinearSolveStats, NumberOfChannels> Stats_;
};

/**
 * Stepping: phi and M phi at the last two steps, the integral over the
 * current gate and over [T0, T1], per channel, advanced segment by segment
 * (RunSegment) by backward Euler from the pulse, then BDF2.
 */
class Stepper
{
public:
  Stepper(const TimeResolvedSystem& base, StepSolver& solver, long long totalSteps,
    Progress progress)
    : Base_(base)
    , Solver_(solver)
    , TotalSteps_(totalSteps)
    , Progress_(std::move(progress))
    , N_(base.System.NumberOfUnknowns)
  {
    const int n = N_;
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      Phi[c].setZero(n);
      PhiPrevious[c].setZero(n);
      MassPhi[c] = base.System.RightHandSide[c]; // M phi(0+) = b: the pulse
      MassPhiPrevious[c].setZero(n);
      EulerInjected[c].setZero(base.Extended ? n : 0);
      Gate[c].setZero(n);
      Integral[c].setZero(n);
    }
    Inject(0, 1.0, MassPhi, nullptr); // the beam at t = 0 (the entry points)
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      Next[c].setZero(n);
      MassNext[c].setZero(n);
      LastEuler[c].setZero(n);
    }
  }

  /**
   * One segment: `steps` steps of dt, the first backward Euler (from the
   * pulse: TimeGates::PulseEulerSteps steps of PulseEulerSubSteps
   * sub-steps each; a restart from a smooth field: one step), the others
   * BDF2; `add` the step integrals to the current gate; `afterStep(step)`
   * after every step (to close gates). False if the progress callback
   * asked to abort.
   */
  bool RunSegment(long long steps, double dt, bool add,
    const std::function<void(long long)>& afterStep)
  {
    const bool fromPulse = Pulse_;
    const long long eulerSteps = fromPulse ? TimeGates::PulseEulerSteps : 1;
    const int subSteps = fromPulse ? TimeGates::PulseEulerSubSteps : 1;
    const double h = dt / subSteps;
    for (long long s = 0; s < steps; ++s)
    {
      const bool euler = s < eulerSteps;
      Solver_.SetMatrix(euler ? 1.0 / h : 1.5 / dt);
      if (euler)
      {
        EulerStep(h, subSteps, add);
      }
      else
      {
        Bdf2Step(dt, s == eulerSteps, add);
      }
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        PhiPrevious[c].swap(Phi[c]);
        Phi[c].swap(Next[c]);
        MassPhiPrevious[c].swap(MassPhi[c]);
        MassPhi[c].swap(MassNext[c]);
        if (euler && Base_.Extended)
        {
          // BDF2's first history term takes the state at the start of the
          // last backward-Euler step with that step's deposits in it: then
          // the gate weights (half that step's integral for the first BDF2
          // interval) still sum to exactly K^-1 (b + all deposits), the
          // continuous-wave solution (DiffuseOptics.md).
          MassPhiPrevious[c] += EulerInjected[c];
        }
      }
      Pulse_ = false;
      ++StepsDone;
      afterStep(s);
      if (!Progress_(static_cast<double>(StepsDone) / static_cast<double>(TotalSteps_)))
      {
        return false;
      }
    }
    return true;
  }

  /// Moves the current gate's integral into the whole run's and returns
  /// the gate average (the integral / width) in `average`.
  void CloseGate(double width, Channels& average)
  {
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      Integral[c] += Gate[c];
      average[c] = Gate[c] / width;
      Gate[c].setZero();
    }
  }

  /// Deposits not injected by the end of the run (0 unless the schedule of
  /// SolveTimes and RunSegment disagree).
  std::size_t GetUninjectedDeposits() const { return Base_.Deposits.size() - NextDeposit_; }

  Channels Integral; ///< over [T0, T1]
  long long StepsDone = 0;

private:
  /// Adds 4 x the deposits of solve `j` (times `factor`) to `target` and,
  /// if given, 4 x them to `injected` (the discretisations' systems are 4 x
  /// the weak form, FiniteElement.h).
  void Inject(long long j, double factor, Channels& target, Channels* injected)
  {
    const std::vector<CollimatedDeposit>& deposits = Base_.Deposits;
    for (; NextDeposit_ < deposits.size() && deposits[NextDeposit_].Time <= j; ++NextDeposit_)
    {
      const CollimatedDeposit& d = deposits[NextDeposit_];
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        target[c][d.Point] += 4.0 * factor * d.Load[c];
        if (injected)
        {
          (*injected)[c][d.Point] += 4.0 * d.Load[c];
        }
      }
    }
  }

  /// The per-step vector work in one pass over the unknowns each, the
  /// three channels together (one OpenMP region instead of one per channel
  /// and operation, no temporaries).
  template <typename Body>
  void ForEachUnknown(const Body& body) const
  {
    const int n = N_;
#pragma omp parallel for schedule(static) if (n > StepParallelThreshold)
    for (int i = 0; i < n; ++i)
    {
      body(i);
    }
  }

  /// A backward-Euler step: (M / h + K) x' = M x / h, subSteps times; the
  /// right rectangle. The integral of the step is kept in LastEuler: the
  /// first BDF2 interval takes half of it in place of dt phi / 2, which
  /// keeps the sum over the steps exactly K^-1 b (DiffuseOptics.md).
  void EulerStep(double h, int subSteps, bool add)
  {
    DiffusionSystem& step = Solver_.Step;
    if (Base_.Extended)
    {
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        EulerInjected[c].setZero(N_);
      }
    }
    for (int j = 0; j < subSteps; ++j)
    {
      const bool zeroGuess = Pulse_ && j == 0;
      // The first sub-step starts from phi and M phi.
      const Channels& massFrom = j == 0 ? MassPhi : MassNext;
      ForEachUnknown([&](int i) {
        for (int c = 0; c < NumberOfChannels; ++c)
        {
          step.RightHandSide[c][i] = massFrom[c][i] / h;
          if (j == 0)
          {
            Next[c][i] = zeroGuess ? 0.0 : Phi[c][i];
            LastEuler[c][i] = 0.0;
          }
        }
      });
      // (M / h + K) x' = (M x + w) / h: the beam's deposits w of this
      // sub-step.
      Inject(++SolveIndex_, 1.0 / h, step.RightHandSide, &EulerInjected);
      Solver_.Solve(Next, false);
      const auto x = Data(Next);
      ForEachUnknown([&](int i) {
        double m[NumberOfChannels];
        Base_.Mass.Row(i, x, m);
        for (int c = 0; c < NumberOfChannels; ++c)
        {
          LastEuler[c][i] += h * Next[c][i];
          MassNext[c][i] = m[c];
          if (add && j + 1 == subSteps)
          {
            Gate[c][i] += LastEuler[c][i];
          }
        }
      });
    }
  }

  /// A BDF2 step: (3/2 M / dt + K) phi' = M (2 phi - phi_prev / 2) / dt;
  /// the trapezoid. The guess: the extrapolation 2 phi - phi_prev (the
  /// multigrid step solver then combines it with its recycled solutions).
  void Bdf2Step(double dt, bool first, bool add)
  {
    DiffusionSystem& step = Solver_.Step;
    const double halfDt = 0.5 * dt;
    ForEachUnknown([&](int i) {
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        step.RightHandSide[c][i] = (2.0 * MassPhi[c][i] - 0.5 * MassPhiPrevious[c][i]) / dt;
        Next[c][i] = first ? Phi[c][i] : 2.0 * Phi[c][i] - PhiPrevious[c][i];
      }
    });
    Inject(++SolveIndex_, 1.0 / dt, step.RightHandSide, nullptr); // + w / dt
    Solver_.Solve(Next, true);
    const auto x = Data(Next);
    ForEachUnknown([&](int i) {
      double m[NumberOfChannels];
      Base_.Mass.Row(i, x, m);
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        MassNext[c][i] = m[c];
        if (add)
        {
          Gate[c][i] += first ? 0.5 * LastEuler[c][i] + halfDt * Next[c][i]
                              : halfDt * (Phi[c][i] + Next[c][i]);
        }
      }
    });
  }

  const TimeResolvedSystem& Base_;
  StepSolver& Solver_;
  long long TotalSteps_;
  Progress Progress_;
  int N_;
  Channels Phi, PhiPrevious, MassPhi, MassPhiPrevious, Gate, Next, MassNext;
  /// What the current backward-Euler step injected, and its integral.
  Channels EulerInjected, LastEuler;
  /// The collimated deposits: the next one to inject and the solve counter
  /// (deposit Time j enters solve j; 0 is the pulse).
  std::size_t NextDeposit_ = 0;
  long long SolveIndex_ = 0;
  bool Pulse_ = true; ///< the next step starts from the pulse (phi is a delta)
};

/**
 * Read-outs: at the end of each gate, the gate average of the fluence at
 * the points for the detectors and the snapshots. The unscattered beam
 * itself, E_c delta(t - tau) per point, has its gate (-1 outside
 * [T0, T1]) per beam and point, for the snapshots and the integral; the
 * detectors read the diffuse field (as in continuous wave).
 */
class GateReadout
{
public:
  GateReadout(const DiffusionProblem& problem, const TimeResolvedSystem& base,
    Discretization& discretization, const TimeGates& used,
    const std::vector<Detector>& detectors, const std::vector<int>& snapshotGates,
    std::vector<DetectorFootprint> footprints, TimeResolvedResult& result, SolverReport& report)
    : Problem_(problem)
    , Base_(base)
    , Discretization_(discretization)
    , Used_(used)
    , Width_(used.GetWidth())
    , HasDetectors_(!detectors.empty())
    , SnapshotGates_(snapshotGates)
    , Footprints_(std::move(footprints))
    , Result_(result)
  {
    if (HasDetectors_ && used.GetStepsBeforeStart() == 0)
    {
      // The q delta(t) term of the exitance, averaged over the first gate.
      IrradianceOverWidth_ = *problem.Irradiance;
      for (double& q : IrradianceOverWidth_)
      {
        q /= Width_;
      }
    }
    if (base.Extended)
    {
      AssignBeamGates(report);
    }
  }

  /// After step s of the gates: closes the gate it ends, if any.
  void AfterStep(long long s, Stepper& stepper)
  {
    if ((s + 1) % Used_.StepsPerGate != 0)
    {
      return;
    }
    const int g = static_cast<int>(s / Used_.StepsPerGate);
    stepper.CloseGate(Width_, Average_);
    const auto snapshot = std::find(SnapshotGates_.begin(), SnapshotGates_.end(), g);
    if (!HasDetectors_ && snapshot == SnapshotGates_.end())
    {
      return;
    }
    const TetMesh& mesh = *Problem_.Mesh;
    Discretization_.ToPointFluence(mesh, Base_.System, Average_, Points_);
    if (HasDetectors_)
    {
      Result_.Readings.push_back(ReadDetectorFootprints(mesh, *Problem_.Material, Footprints_,
        Points_, g == 0 && !IrradianceOverWidth_.empty() ? &IrradianceOverWidth_ : nullptr,
        Base_.Rule));
    }
    if (snapshot != SnapshotGates_.end())
    {
      // The gate average of the unscattered pulses arriving in this gate.
      const CollimatedSource& collimated = Base_.Collimated;
      for (std::size_t b = 0; b < collimated.Beams.size(); ++b)
      {
        for (std::size_t i = 0; i < BeamGate_[b].size(); ++i)
        {
          for (int c = 0; c < NumberOfChannels && BeamGate_[b][i] == g; ++c)
          {
            Points_[3 * i + c] += collimated.Beams[b].Fluence[3 * i + c] / Width_;
          }
        }
      }
      Result_.Snapshots.resize(SnapshotGates_.size());
      for (std::size_t k = 0; k < SnapshotGates_.size(); ++k)
      {
        if (SnapshotGates_[k] == g)
        {
          Result_.Snapshots[k] = Points_;
        }
      }
    }
  }

private:
  /// Each beam's gate per point, and the unscattered fluence of the pulses
  /// arriving within [T0, T1] in the report (with the beam's power terms).
  void AssignBeamGates(SolverReport& report)
  {
    const CollimatedSource& collimated = Base_.Collimated;
    BeamGate_.resize(collimated.Beams.size());
    report.CollimatedFluence.assign(
      3 * static_cast<std::size_t>(Problem_.Mesh->GetNumberOfPoints()), 0.0);
    for (std::size_t b = 0; b < collimated.Beams.size(); ++b)
    {
      const CollimatedSource::Beam& beam = collimated.Beams[b];
      BeamGate_[b].assign(beam.OpticalPath.size(), -1);
      for (std::size_t i = 0; i < beam.OpticalPath.size(); ++i)
      {
        const double tau = beam.OpticalPath[i] / SpeedOfLightMillimetresPerNanosecond;
        const double g = std::floor((tau - Used_.Start) / Width_);
        if (tau >= Used_.Start && g < Used_.Count)
        {
          BeamGate_[b][i] = static_cast<int>(g);
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

  const DiffusionProblem& Problem_;
  const TimeResolvedSystem& Base_;
  Discretization& Discretization_;
  const TimeGates& Used_;
  double Width_;
  bool HasDetectors_;
  const std::vector<int>& SnapshotGates_;
  std::vector<DetectorFootprint> Footprints_;
  TimeResolvedResult& Result_;
  std::vector<double> IrradianceOverWidth_;
  std::vector<std::vector<int>> BeamGate_;
  std::vector<double> Points_;
  Channels Average_;
};

} // namespace

bool VertexDiffusionSolver::SolveTimeResolved(const DiffusionProblem& problem,
  const TimeGates& gates, const std::vector<Detector>& detectors,
  const std::vector<int>& snapshotGates, TimeResolvedResult& result, SolverReport& report)
{
  // ---- Schedule: checks, steps per gate.
  if (!problem.Mesh || !problem.Material || !problem.Irradiance)
  {
    throw Error(GetName() + ": the problem needs a mesh, a material and an irradiance");
  }
  gates.Validate();
  const OpticalProperties& material = *problem.Material;
  material.Validate(problem.Mesh->GetNumberOfTets());
  const TimeGates used = ScheduleGates(GetName(), material, gates, snapshotGates);
  const TetMesh& mesh = *problem.Mesh;
  report = SolverReport();
  report.Solver = GetName();
  report.Assembly = "full";
  result = TimeResolvedResult();
  result.Gates = used;
  result.TimeStep = used.GetTimeStep();
  result.SnapshotGates = snapshotGates;

  // ---- Step matrices: K, b, M and the step solver.
  auto start = Clock::now();
  // The detectors' footprints, located once (not at every gate; a detector
  // off the surface is an error before the stepping).
  std::vector<DetectorFootprint> footprints =
    detectors.empty() ? std::vector<DetectorFootprint>() : LocateDetectors(mesh, detectors);
  TimeResolvedSystem base;
  AssembleTimeResolved(GetName(), *Discretization_, problem, used, base);
  const DiffusionSystem& system = base.System;
  StepSolver solver(GetName(), base, mesh,
    ToLower(LinearSolver_.empty() ? GetDefaultLinearSolverName(system.NumberOfUnknowns)
                                  : LinearSolver_),
    LinearSolver_.empty(), RelTol_, MaxIter_, TimeStepRecycled_, result, report);
  report.SetupMilliseconds = MillisecondsSince(start);

  // ---- Stepping: [0, T0] (steps of at most the gate step, nothing
  // recorded), then the gates with their read-outs.
  start = Clock::now();
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    report.Converged[c] = true;
  }
  Stepper stepper(base, solver, used.GetNumberOfSteps(),
    [this](double fraction) { return ReportProgress(fraction); });
  const long long before = used.GetStepsBeforeStart();
  if (before > 0 &&
    !stepper.RunSegment(before, used.Start / static_cast<double>(before), false, [](long long) {}))
  {
    return false;
  }
  GateReadout readout(problem, base, *Discretization_, used, detectors, snapshotGates,
    std::move(footprints), result, report);
  if (!stepper.RunSegment(static_cast<long long>(used.Count) * used.StepsPerGate,
        used.GetTimeStep(), true, [&](long long s) { readout.AfterStep(s, stepper); }))
  {
    return false;
  }
  if (stepper.GetUninjectedDeposits() != 0)
  {
    // The schedule and RunSegment disagree: a bug, not an input error.
    throw Error(GetName() + ": internal error: " +
      std::to_string(stepper.GetUninjectedDeposits()) +
      " collimated deposits were not injected (time-step schedule mismatch)");
  }

  // ---- Read-outs of the whole run.
  Discretization_->ToPointFluence(mesh, system, stepper.Integral, result.IntegratedFluence);
  for (std::size_t k = 0; k < report.CollimatedFluence.size(); ++k)
  {
    result.IntegratedFluence[k] += report.CollimatedFluence[k]; // phi_d + E_c, as in CW
  }
  result.NumberOfSteps = stepper.StepsDone;
  report.SolveMilliseconds = MillisecondsSince(start);
  const int n = system.NumberOfUnknowns;
  const std::size_t nnz = system.ColumnIndices.size();
  report.NumberOfUnknowns = n;
  report.NumberOfNonZeros = static_cast<long long>(nnz);
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    report.Iterations[c] =
      static_cast<int>(std::min<long long>(solver.Iterations[c], 2147483647LL));
  }
  // The system, the mass and step values, 10 vectors per channel, the
  // linear solvers' own memory and the snapshots.
  report.MemoryBytes = system.GetMemoryBytes() + (1 + NumberOfChannels) * nnz * sizeof(double) +
    10 * NumberOfChannels * static_cast<std::size_t>(n) * sizeof(double) +
    solver.GetMemoryBytes() +
    result.Snapshots.size() * 3 * static_cast<std::size_t>(n) * sizeof(double);
  return true;
}

} // namespace translucency
