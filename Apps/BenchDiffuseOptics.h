/**
 * @file BenchDiffuseOptics.h
 * @brief `translucency bench --diffuse-optics`: the frequency-domain and
 * time-resolved solves of issue 19 against the continuous-wave solve, in one
 * run on the same mesh (Documentation/DiffuseOptics.md, Performance.md):
 *
 * - at each --tets: the CW cold 3-channel solve (divergence, the default
 *   linear solver: multigrid-agg at these sizes) as the baseline; the
 *   frequency-domain solve with COCG-Jacobi and with COCG preconditioned by
 *   the multigrid cycle of the real part; each one's ratio to the CW solve;
 * - at --gate-tets: --gates time gates over 0-5 ns (--steps-per-gate) with
 *   the cg-jacobi step solver, the multigrid-agg one from the extrapolated
 *   guess alone (before session 21) and with the recycled step solutions
 *   (the default, VertexDiffusionSolver::SetTimeStepRecycledSolutions); the
 *   ratios are to the extrapolated multigrid row.
 *
 * Medians of --runs; every figure of a table comes from the same run, so the
 * ratios hold on a loaded machine (the load average is printed).
 */
#pragma once

#include <string>
#include <vector>

namespace translucency_app
{

/// The options of `translucency bench --diffuse-optics` (declared in BenchCommand.cxx).
struct DiffuseOpticsBenchOptions
{
  std::string MeshPath = "Data/bunny.ply";
  std::vector<double> Tets = { 1000000 }; ///< sizes of the frequency-domain table
  int Runs = 3;
  std::string JsonPath;
  double Frequency = 100e6; ///< Hz
  double GateTets = 200000; ///< size of the time-gate table; 0: skip it
  int Gates = 100;          ///< gates over 0-5 ns
  int StepsPerGate = 0;     ///< time steps per gate (0: automatic, TimeGates)
};

/// Runs the bench and prints its tables; 0 on success.
int BenchDiffuseOptics(const DiffuseOpticsBenchOptions& options);

} // namespace translucency_app
