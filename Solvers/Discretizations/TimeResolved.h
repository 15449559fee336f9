/**
 * @file TimeResolved.h
 * @brief Time-resolved diffusion (issue 19): the response to a light pulse
 * delta(t) at t = 0, averaged over time gates, for the vertex
 * discretisations (VertexDiffusionSolver::SolveTimeResolved).
 *
 * Equation (per channel; lengths mm, times ns, c = 299.792458 mm/ns, eta
 * the tet's refractive index, c_m = c / eta):
 *
 *   (1 / c_m) dphi/dt - div(kappa grad phi) + mu_a phi = S(x) delta(t),
 *
 * with the boundary condition of the continuous-wave solve, the boundary
 * irradiance q also a pulse q delta(t). In matrix form M dphi/dt + K phi =
 * b delta(t), K and b the discretisation's continuous-wave matrix and
 * right-hand side, M its mass matrix times eta / c (Discretization::AddMass:
 * lumped for divergence, consistent for fem). The pulse sets M phi(0+) = b.
 *
 * Time stepping: TimeGates::PulseEulerSteps (4) backward-Euler steps of
 * PulseEulerSubSteps (4) sub-steps each, then BDF2 with a constant step
 * (second order, A-stable and strongly damping, so the delta start does not
 * ring as Crank-Nicolson would); when T0 > 0 the interval [0, T0] is
 * stepped first (steps of at most the gate step) and the gates restart with
 * one backward-Euler step. Each step solves the SPD system
 * (a M / dt + K) phi = rhs (a = 1 or 3/2) from the extrapolated previous
 * values, the three channels by the linear solver a continuous-wave solve
 * would use (multigrid-agg from VertexDiffusionSolver::LargeSystemUnknowns
 * unknowns on, its hierarchy built once per run, each step starting from the
 * A-norm-best combination of the extrapolation and the last step solutions:
 * VertexDiffusionSolver::SetTimeStepRecycledSolutions; cg-jacobi below).
 * Gate averages: the backward-Euler steps
 * contribute h phi (right rectangle), the BDF2 steps the trapezoid rule (the
 * first one with half the last Euler step's integral for dt phi / 2).
 * With these weights the sum over all steps of the step integrals equals
 * K^-1 b, the continuous-wave solution, exactly (up to the CG tolerance and
 * the tail after the last step): the power identity the tests check.
 *
 * Units: a source of power P (W) in the continuous-wave solve is here a
 * pulse of energy P (J); the gate-averaged fluence rate is in J/(mm^2 ns)
 * (= 1e9 W/mm^2), so that its integral over time in ns is numerically the
 * continuous-wave fluence rate (W/mm^2) for P W.
 * Documentation/DiffuseOptics.md has the derivation and the validation.
 */
#pragma once

#include "Detectors.h"

#include <string>
#include <vector>

namespace translucency
{

/// The time gates: Count equal gates covering [Start, End] (ns).
struct TimeGates
{
  double Start = 0.0; ///< T0, ns, finite, >= 0
  double End = 0.0;   ///< T1, ns, finite, > Start, <= MaximumEnd
  int Count = 0;      ///< N, 1..MaximumTimeGates
  /**
   * Time steps per gate: 1..MaximumStepsPerGate, or 0 (the default) for
   * automatic: ChooseStepsPerGate(). The step is (End - Start) / (Count
   * StepsPerGate). Halving the step divides the time-discretisation error
   * by about 4 (BDF2).
   */
  int StepsPerGate = 0;

  /**
   * Backward-Euler steps from the pulse before BDF2 (each of
   * PulseEulerSubSteps sub-steps). BDF2's history term 2 phi^n - phi^(n-1) / 2
   * is negative where the field falls by more than 4x in a step, as it does
   * next to the source just after the pulse: with one start step the
   * fluence there went negative (-18 % of the largest value one gate later,
   * 20k-tet box, pencil beam). Four steps of four sub-steps damp the fast
   * modes by (1 + lambda dt / 4)^-16 before BDF2 takes over; their first-
   * order error is small (measured time error at 4 steps per gate 0.10 %,
   * against 0.11 % with one plain start step and 0.22 % with four).
   */
  static constexpr int PulseEulerSteps = 4;
  /// Sub-steps of each of those backward-Euler steps (dt / 4 each: stronger
  /// damping of the fast modes, a quarter of the first-order error).
  static constexpr int PulseEulerSubSteps = 4;
  /// The automatic choice's least number of steps per gate.
  static constexpr int DefaultStepsPerGate = 4;
  /**
   * The automatic choice's largest mu_a c_m dt. BDF2 multiplies a mode that
   * decays at the rate lambda (1/ns) by exp(-lambda dt) (1 - (lambda dt)^3
   * / 3 + ...) per step: a relative error (lambda dt)^2 (lambda t) / 3 at
   * time t, 0.4 % at lambda t = 5 for lambda dt = 0.05 (absorption sets
   * the slowest decay; Documentation/DiffuseOptics.md).
   */
  static constexpr double MaximumDecayPerStep = 0.05;
  /// Latest End (ns, 1 ms): light in a diffusing object is gone within
  /// microseconds; later gates hold only zeros (T1 = 1e308 overflowed).
  static constexpr double MaximumEnd = 1e6;
  /// Shortest time step (ns, 1 fs): a step of 1e-321 ns (gates 0,1e-320,10)
  /// made 1/dt overflow; the diffusion model is meaningless far above it.
  static constexpr double MinimumTimeStep = 1e-6;
  /// Largest Count.
  static constexpr int MaximumTimeGates = 10000;
  /// Largest StepsPerGate.
  static constexpr int MaximumStepsPerGate = 1000;
  /// Largest number of time steps of one solve (those before Start included):
  /// each step is a linear solve per channel.
  static constexpr long long MaximumTimeSteps = 100000;

  double GetWidth() const { return (End - Start) / Count; }                   ///< ns
  double GetGateStart(int gate) const { return Start + gate * GetWidth(); }   ///< ns
  double GetGateCentre(int gate) const { return Start + (gate + 0.5) * GetWidth(); } ///< ns
  /// The step inside the gates (ns), for StepsPerGate > 0.
  double GetTimeStep() const { return GetWidth() / StepsPerGate; }
  /**
   * StepsPerGate if > 0; else max(DefaultStepsPerGate,
   * ceil(width absorptionRate / MaximumDecayPerStep)), absorptionRate the
   * largest mu_a c_m (1/ns) of the material.
   */
  int ChooseStepsPerGate(double absorptionRate) const;
  /// Steps before Start: ceil(Start / GetTimeStep()), 0 when Start is 0.
  long long GetStepsBeforeStart() const;
  /// Every step of a solve: GetStepsBeforeStart() + Count StepsPerGate.
  long long GetNumberOfSteps() const { return GetStepsBeforeStart() + 1LL * Count * StepsPerGate; }

  /// "" if valid, else what is wrong with the values (e.g. "T1 = 1 ns is not
  /// after T0 = 2 ns"), without a prefix: callers name their option. With
  /// StepsPerGate 0 the step limit is checked for DefaultStepsPerGate (the
  /// solve checks again with the steps it chose).
  std::string Check() const;
  /// Throws translucency::Error("time gates T0,T1,N: " + Check()) unless valid.
  void Validate() const;
};

/// What SolveTimeResolved returns.
struct TimeResolvedResult
{
  TimeGates Gates; ///< as solved: StepsPerGate is the number used
  double TimeStep = 0.0;       ///< ns, inside the gates
  long long NumberOfSteps = 0; ///< time steps done (those before T0 included)
  /**
   * Readings[g][k]: detector k averaged over gate g (Detectors.h, per
   * channel): Fluence the gate-averaged fluence rate and Exitance the
   * gate-averaged exitance J = (phi - 2 q delta(t)) / (2 A), both in
   * J/(mm^2 ns) per pulse of P J (the q delta(t) term falls in the first
   * gate when T0 = 0).
   */
  std::vector<std::vector<DetectorReading>> Readings;
  /// The integral of phi over [T0, T1], 3 values per mesh point, J/mm^2 for
  /// pulses of P J: the continuous-wave fluence rate for P W when the gates
  /// start at 0 and last until the pulse has died out.
  std::vector<double> IntegratedFluence;
  /// The gates asked for as snapshots, and their gate-averaged fluence rate
  /// (3 values per mesh point, J/(mm^2 ns)), in the same order.
  std::vector<int> SnapshotGates;
  std::vector<std::vector<double>> Snapshots;
  /// Linear-solver iterations of the most expensive step, per channel.
  std::array<int, NumberOfChannels> MaximumStepIterations{};
};

} // namespace translucency
