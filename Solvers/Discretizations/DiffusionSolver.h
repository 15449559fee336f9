/**
 * @file DiffusionSolver.h
 * @brief Common interface of every solver the user can pick: the vertex
 * discretisations (discrete divergence, FEM), QuadGraph finite differences,
 * regular-grid finite differences and the Monte Carlo reference. Each takes
 * the same problem and returns fluence at the mesh vertices, so results can
 * be compared point by point.
 */
#pragma once

#include "LightSources.h"
#include "OpticalProperties.h"

#include <array>
#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace translucency
{

class TetMesh;

/// The problem every solver receives. Pointers are borrowed (not owned).
struct DiffusionProblem
{
  const TetMesh* Mesh = nullptr;
  const OpticalProperties* Material = nullptr;
  /// q, 3 values per mesh point (W/mm^2), 0 at interior points. The
  /// diffusion solvers read only this.
  const std::vector<double>* Irradiance = nullptr;
  /// The lights q came from (the Monte Carlo reference launches photons
  /// from them; the diffusion solvers ignore them).
  std::vector<LightSource> Lights;
  double UniformIrradiance = 0.0; ///< W/mm^2, see LightSource
  bool Shadows = true;
};

/// What a solve cost and how it ended (valid after Solve()).
struct SolverReport
{
  std::string Solver;             ///< name, e.g. "divergence"
  std::string LinearSolver;       ///< e.g. "cg-jacobi", "bicgstab", "relaxation"
  /// Vertex discretisations: "full" (Assemble) or "incremental" (only the
  /// rows of changed tets rebuilt, VertexDiffusionSolver::SetChangedTets);
  /// empty for the other solvers.
  std::string Assembly;
  long long NumberOfUnknowns = 0; ///< per channel
  long long NumberOfNonZeros = 0; ///< per channel matrix (0 for Monte Carlo)
  std::size_t MemoryBytes = 0;    ///< system (matrix, vectors) or tallies
  double SetupMilliseconds = 0.0; ///< discretisation / assembly / set-up
  double SolveMilliseconds = 0.0;
  std::array<int, NumberOfChannels> Iterations{};
  std::array<double, NumberOfChannels> Residual{}; ///< relative residual
  std::array<bool, NumberOfChannels> Converged{};
  /// Monte Carlo only: standard error of Fluence (3 per mesh point) and the
  /// tallied exitant Radiance with its standard error (3 per mesh point,
  /// boundary points only; W/mm^2/sr). Empty for the diffusion solvers.
  std::vector<double> FluenceStandardError;
  std::vector<double> Radiance;
  std::vector<double> RadianceStandardError;
};

class DiffusionSolver
{
public:
  virtual ~DiffusionSolver() = default;

  /// The name scripts use ("divergence", "fem", "quadgraph", "grid", "montecarlo").
  virtual std::string GetName() const = 0;

  /**
   * Solve the three channels and write fluence phi, 3 values per mesh point
   * (W/mm^2). Throws translucency::Error on invalid input; returns false if
   * the progress callback asked to abort. Not converging is not an error
   * (see the report).
   */
  virtual bool Solve(const DiffusionProblem& problem, std::vector<double>& fluence,
    SolverReport& report) = 0;

  /// Forget any state kept for a warm start (call when the mesh changes).
  virtual void Reset() {}

  ///@{
  /// Iterative solvers: relative residual to reach (default 1e-6) and the
  /// iteration limit (default 2000). Others ignore them.
  void SetRelTol(double tol) { RelTol_ = tol; }
  double GetRelTol() const { return RelTol_; }
  void SetMaxIter(int n) { MaxIter_ = n; }
  int GetMaxIter() const { return MaxIter_; }
  ///@}

  /// Start from the previous solution when the unknowns are unchanged (default on).
  void SetWarmStart(bool on) { WarmStart_ = on; }
  bool GetWarmStart() const { return WarmStart_; }

  ///@{
  /// Regular-grid solver: voxel spacing h (mm, > 0). Default 0 = automatic
  /// (the solver picks it from the mesh). Others ignore it.
  void SetGridSpacing(double h) { GridSpacing_ = h; }
  double GetGridSpacing() const { return GridSpacing_; }
  ///@}

  ///@{
  /// Monte Carlo: photon budget (> 0, default 1e6) and seed (default 1).
  void SetNumberOfPhotons(long long n) { NumberOfPhotons_ = n; }
  long long GetNumberOfPhotons() const { return NumberOfPhotons_; }
  void SetSeed(unsigned long long seed) { Seed_ = seed; }
  unsigned long long GetSeed() const { return Seed_; }
  ///@}

  ///@{
  /// Linear solver by name; "" (the default) means the solver's own default.
  /// QuadGraph, grid (non-symmetric): "bicgstab" (default) or "relaxation"
  /// (the papers' Jacobi-style sweeps). Vertex discretisations (divergence,
  /// fem): a name of GetLinearSolverNames() (LinearSolver.h), default
  /// "cg-jacobi".
  void SetLinearSolver(const std::string& name) { LinearSolver_ = name; }
  const std::string& GetLinearSolver() const { return LinearSolver_; }
  ///@}

  ///@{
  /// Coarse-to-fine initialisation where the solver has one (QuadGraph
  /// eq. 10, grid 8-children averaging). Default off.
  void SetMultiLevel(bool on) { MultiLevel_ = on; }
  bool GetMultiLevel() const { return MultiLevel_; }
  ///@}

  /// Called with the fraction done in [0, 1]; returning false aborts.
  void SetProgressCallback(std::function<bool(double)> callback) { Progress_ = std::move(callback); }

protected:
  bool ReportProgress(double fraction) const { return !Progress_ || Progress_(fraction); }

  double RelTol_ = 1e-6;
  int MaxIter_ = 2000;
  bool WarmStart_ = true;
  double GridSpacing_ = 0.0;
  long long NumberOfPhotons_ = 1000000;
  unsigned long long Seed_ = 1;
  std::string LinearSolver_;
  bool MultiLevel_ = false;
  std::function<bool(double)> Progress_;
};

} // namespace translucency
