/**
 * @file DiffusionSolver.h
 * @brief Common interface of every solver the user can pick: the vertex
 * discretisations (discrete divergence, FEM), QuadGraph finite differences,
 * regular-grid finite differences and the Monte Carlo reference. Each takes
 * the same problem and returns fluence at the mesh vertices, so results can
 * be compared point by point.
 */
#pragma once

#include "CollimatedSource.h"
#include "Communicator.h"
#include "InteriorSources.h"
#include "LightSources.h"
#include "OpticalProperties.h"
#include "Error.h"
#include "SolverOptions.h"
#include "TimeResolved.h"

#include <array>
#include <complex>
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
  /// Sources inside the object (point sources, pencil beams), borrowed; null
  /// or empty = none. Every solver takes them in continuous wave: the vertex
  /// discretisations (divergence, fem: the consistent FEM load, also in the
  /// frequency and time domains), quadgraph (the P1 load carried to its
  /// nodes by the transpose of its vertex map), grid (trilinear weights over
  /// the grid cell's corners) and montecarlo (photons launched there).
  /// Documentation/DiffuseOptics.md.
  const Sources* InteriorSources = nullptr;

  /// How the directional lights enter (DiffuseOptics.md): Surface (the
  /// default) = as Irradiance, which then includes them; Extended = as the
  /// volume source of ComputeCollimatedSource() from Lights, and Irradiance
  /// must not include them (vtkSurfaceIrradiance's CollimatedModel). Only
  /// the vertex discretisations (divergence, fem, continuous wave)
  /// implement Extended and ExtendedMoments (which also switches their
  /// Robin condition to Fresnel::BoundaryRule::Moments); quadgraph and grid
  /// throw, Monte Carlo (transport, not diffusion) ignores it.
  CollimatedModel Collimated = CollimatedModel::Surface;
  /// A distributed solve (DiffusionSolver::SetCommunicator with an MPI
  /// communicator): the identity of each of Mesh's points across the ranks,
  /// one per point (borrowed). Mesh is then this rank's piece: its owned
  /// tets (no ghost copies) on its local points; null when the rank has no
  /// tets (its points are the keys). The in-process solvers ignore it.
  const std::vector<PointKey>* PointKeys = nullptr;

  bool HasInteriorSources() const { return InteriorSources && !InteriorSources->Empty(); }
};

/// Throws translucency::Error naming `solver` if the problem asks for the
/// extended collimated-source model (for the solvers without it).
inline void RequireSurfaceCollimatedModel(const DiffusionProblem& problem, const std::string& solver)
{
  if (IsExtendedCollimatedModel(problem.Collimated))
  {
    throw Error(solver +
      ": the extended collimated-source model is implemented for the \"divergence\" and "
      "\"fem\" solvers only (use the surface model)");
  }
}

/// What a solve cost and how it ended (valid after Solve()).
struct SolverReport
{
  std::string Solver;             ///< name, e.g. "divergence"
  std::string LinearSolver;       ///< e.g. "cg-jacobi", "bicgstab", "relaxation"
  /// Vertex discretisations: "full" (Assemble), "incremental" (only the
  /// rows of changed tets rebuilt, VertexDiffusionSolver::SetChangedTets)
  /// or "right-hand side" (a relight: only the load rebuilt); empty for the
  /// other solvers.
  std::string Assembly;
  /// Vertex discretisations: what the linear solver's set-up did, "rebuilt"
  /// (structure and values: a new mesh or solver), "values" (values only),
  /// "rows" (the rows of changed tets, LinearSolver::SetupChangedRows) or
  /// "kept" (the matrices did not change: a relight); empty for the others.
  std::string LinearSetup;
  /// Vertex discretisations with an extended collimated model: what the
  /// beam's volume source did (CollimatedSourceCache::GetLastUpdate()):
  /// "full" (rays and every tet), "loads" (the kept rays, the changed tets
  /// integrated again: a paint) or "kept"; empty otherwise.
  std::string Collimated;
  long long NumberOfUnknowns = 0; ///< per channel
  long long NumberOfNonZeros = 0; ///< per channel matrix (0 for Monte Carlo)
  std::size_t MemoryBytes = 0;    ///< system (matrix, vectors) or tallies
  double SetupMilliseconds = 0.0; ///< discretisation / assembly / set-up
  double SolveMilliseconds = 0.0;
  std::array<int, NumberOfChannels> Iterations{};
  std::array<double, NumberOfChannels> Residual{}; ///< relative residual
  std::array<bool, NumberOfChannels> Converged{};
  /// Converged by the change rule (DiffusionSolver::SetChangeTol: the
  /// boundary fluence stopped changing), not by RelTol
  /// (LinearSolveStats::StoppedByChange).
  std::array<bool, NumberOfChannels> StoppedByChange{};
  /// The first attempt did not converge and this report is of the re-solve
  /// after a full set-up (a new hierarchy, no warm start) in the same call
  /// (DiffusionFrontEnd::Solve, DistributedVertexSolver::Solve).
  bool Resolved = false;
  /// Monte Carlo only: standard error of Fluence (3 per mesh point) and the
  /// tallied exitant Radiance with its standard error (3 per mesh point,
  /// boundary points only; W/mm^2/sr). Empty for the diffusion solvers.
  std::vector<double> FluenceStandardError;
  /// Extended collimated model only (vertex solvers): the collimated fluence
  /// rate E_c (3 per mesh point, W/mm^2; included in the fluence, which is
  /// phi_d + E_c) and the beams' power balance (W per channel):
  /// transmitted into the object, scattered into the diffuse field (the
  /// volume source's injected power) and absorbed directly. Empty / zero
  /// otherwise. Frequency domain: CollimatedFluence is the amplitude of the
  /// modulated beam and CollimatedFluencePhase its phase (radians, 3 per
  /// mesh point; the beam lags by omega eta s / c), the powers those of
  /// continuous wave. Time domain: CollimatedFluence is E_c integrated over
  /// the gates (E_c where the beam arrives within [T0, T1]), the powers
  /// those of continuous wave (the integral over all time).
  std::vector<double> CollimatedFluence;
  std::vector<double> CollimatedFluencePhase;
  std::array<double, NumberOfChannels> CollimatedEntering{};
  std::array<double, NumberOfChannels> CollimatedScattered{};
  std::array<double, NumberOfChannels> CollimatedAbsorbed{};
  std::vector<double> Radiance;
  std::vector<double> RadianceStandardError;
};

/// The extended collimated model's read-out, shared by the vertex solvers
/// and SP3: adds the unscattered beam's fluence to the diffuse one (the
/// total fluence rate phi_d + E_c) and records the beam in the report
/// (SolverReport::CollimatedFluence and the beams' power balance).
void AddCollimatedFluence(CollimatedSource& collimated, std::vector<double>& fluence,
  SolverReport& report);
/// The frequency domain's: adds the modulated beam (complex, 3 per mesh
/// point) and records its amplitude and phase; the powers are those of
/// continuous wave, taken from `collimated`.
void AddCollimatedFluence(const CollimatedSource& collimated,
  const std::vector<std::complex<double>>& modulated,
  std::vector<std::complex<double>>& fluence, SolverReport& report);

/// The names of the solver-specific options (DiffusionSolver::SetOptions).
namespace DiffusionOption
{
constexpr const char* GridSpacing = "grid-spacing"; ///< GridSolver: h (mm), 0 = automatic
constexpr const char* MultiLevel = "multilevel";    ///< GridSolver, QuadGraphSolver: 0 or 1
constexpr const char* TwoPointFlux = "two-point-flux"; ///< QuadGraphSolver: 0 or 1 (not the paper's)
constexpr const char* Photons = "photons";          ///< MonteCarloSolver: photon budget
constexpr const char* Seed = "seed";                ///< MonteCarloSolver: random seed
constexpr const char* Anisotropy = "anisotropy";    ///< MonteCarloSolver: Henyey-Greenstein g
/// VertexDiffusionSolver: recycled step solutions of the time domain, 0..4
constexpr const char* TimeStepRecycled = "time-step-recycled";
}

/**
 * What a stochastic solver (registry trait IsStochastic) tallied during its
 * last solve, beside the fluence: its detector readings with standard
 * errors (continuous wave: all time), the time-of-flight readings per gate
 * ([gate][detector], with time gates) and its own power bookkeeping (W per
 * channel). The deterministic solvers have none: the front end reads their
 * detectors from the fluence (ReadDetectors) and computes their balance.
 */
struct TalliedReadouts
{
  std::vector<DetectorReading> Readings, ReadingErrors;
  std::vector<std::vector<DetectorReading>> GateReadings, GateErrors;
  std::array<double, NumberOfChannels> Injected{}, Absorbed{}, Escaped{};
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

  /**
   * Frequency domain (registry trait SupportsFrequency): the complex fluence
   * Phi (3 per mesh point) of sources and irradiance modulated at
   * `frequency` Hz (VertexDiffusionSolver.h has the equation). The default
   * refuses: throws translucency::Error("the <name> solver has no frequency
   * domain"). Returns false if the progress callback aborted.
   */
  virtual bool SolveFrequencyDomain(const DiffusionProblem& problem, double frequency,
    std::vector<std::complex<double>>& fluence, SolverReport& report);

  /**
   * Time domain (registry trait SupportsTime): the response to a pulse at
   * t = 0 averaged over `gates`, `detectors` read at every gate, the
   * gate-averaged fluence of `snapshotGates` kept (TimeResolved.h). The
   * default refuses: throws translucency::Error("the <name> solver has no
   * time gates"). Returns false if the progress callback aborted.
   */
  virtual bool SolveTimeResolved(const DiffusionProblem& problem, const TimeGates& gates,
    const std::vector<Detector>& detectors, const std::vector<int>& snapshotGates,
    TimeResolvedResult& result, SolverReport& report);

  /**
   * Painting (TransCut Sec. 5.2): the caller guarantees that, since the
   * last successful Solve() on the same mesh, only the material of
   * `changedTets` changed (same irradiance). Solvers with an incremental
   * update (registry trait UnknownsAtVertices: VertexDiffusionSolver) rebuild
   * only those rows at the next Solve(); the default ignores it (a full
   * solve, the same result). With `irradianceChanged` (a relight, possibly
   * with a paint) the irradiance may differ too (VertexDiffusionSolver then
   * rebuilds the right-hand side and keeps the matrices).
   */
  virtual void SetChangedTets(std::vector<int> changedTets, bool irradianceChanged = false)
  {
    (void)changedTets;
    (void)irradianceChanged;
  }

  /**
   * The communicator of the solve (model: PETSc, every object has one). The
   * in-process solvers take none (the default Communicator); the base
   * refuses an MPI communicator with translucency::Error naming the solver.
   * A solver with the registry trait Distributed (the variant the registry
   * gives for it, DiffusionFrontEnd::SetCommunicator) solves one system over
   * the communicator's ranks, each rank calling Solve with its own piece
   * (DiffusionProblem::PointKeys); a communicator of size one is the same
   * code on one rank.
   */
  virtual void SetCommunicator(const Communicator& comm)
  {
    if (comm.IsMPI())
    {
      throw Error("the " + GetName() +
        " solver runs in one process: it takes no MPI communicator (its registry entry has "
        "no distributed variant)");
    }
  }
  /// OpenMP threads of the solver's parallel loops (0, the default: OpenMP's
  /// default). Does not change the results. The base (no threads) ignores it.
  virtual void SetNumberOfThreads(int n) { (void)n; }

  /**
   * Detectors a stochastic solver tallies while it runs (photons crossing
   * the fibre); the others ignore them (their detectors are read from the
   * fluence by the caller). Default: ignored.
   */
  virtual void SetDetectors(const std::vector<Detector>& detectors) { (void)detectors; }

  /// The read-outs the last solve tallied (stochastic solvers); false (the
  /// default) when the solver tallies none.
  virtual bool GetTalliedReadouts(TalliedReadouts& readouts) const
  {
    (void)readouts;
    return false;
  }

  ///@{
  /// Iterative solvers: relative residual to reach (default 1e-6) and the
  /// iteration limit (default 2000). Others ignore them.
  void SetRelTol(double tol) { RelTol_ = tol; }
  double GetRelTol() const { return RelTol_; }
  void SetMaxIter(int n) { MaxIter_ = n; }
  int GetMaxIter() const { return MaxIter_; }
  ///@}

  ///@{
  /**
   * The interactive accuracy rule (Documentation/Solvers.md, "The
   * interactive stopping rule"): > 0 also stops a channel once the
   * estimated error of its boundary fluence (relative RMS over the boundary
   * points) is at most this (LinearSolver::SetChangeRule). Default 0: off,
   * RelTol alone. Honoured by the vertex solvers with multigrid-agg; the
   * others ignore it.
   */
  void SetChangeTol(double tol) { ChangeTol_ = tol > 0.0 ? tol : 0.0; }
  double GetChangeTol() const { return ChangeTol_; }
  ///@}

  /// Start from the previous solution when the unknowns are unchanged (default on).
  void SetWarmStart(bool on) { WarmStart_ = on; }
  bool GetWarmStart() const { return WarmStart_; }

  ///@{
  /// Linear solver by name; "" (the default) means the solver's own default.
  /// QuadGraph, grid (non-symmetric): "bicgstab" (default) or "relaxation"
  /// (the papers' Jacobi-style sweeps). Vertex discretisations (divergence,
  /// fem): a name of GetLinearSolverNames() (LinearSolver.h), default
  /// "cg-jacobi".
  void SetLinearSolver(const std::string& name) { LinearSolver_ = name; }
  const std::string& GetLinearSolver() const { return LinearSolver_; }
  ///@}

  /**
   * Solver-specific settings by name, the one hook for callers that only
   * hold a DiffusionSolver (model: PETSc's KSPSetFromOptions_<type>). Each
   * solver reads the options it knows, checks them and applies them; the
   * concrete classes also have typed setters. The options (defaults in the
   * solver's header):
   *  - "grid-spacing" (GridSolver): voxel spacing h in mm, > 0, or 0 =
   *    automatic;
   *  - "multilevel" (GridSolver, QuadGraphSolver): coarse-to-fine
   *    initialisation, 0 or 1;
   *  - "two-point-flux" (QuadGraphSolver): two-point finite-volume link
   *    weights instead of the paper's eq. 5, 0 or 1;
   *  - "photons", "seed" (MonteCarloSolver): photon budget >= 1, random seed
   *    >= 0 (integers); "anisotropy" (MonteCarloSolver): Henyey-Greenstein
   *    g in (-1, 1);
   *  - "time-step-recycled" (VertexDiffusionSolver): earlier step solutions
   *    that start each time step, integer 0..4 (SetTimeStepRecycledSolutions).
   *
   * Decision: a value this solver reads but refuses throws
   * translucency::Error naming the solver, the option and the value (the
   * options read before it are applied). An option this solver does not
   * read is NOT an error here: it stays unused in `options`
   * (SolverOptions::GetUnused()), for the caller to report, because a
   * front end such as vtkSolveDiffusion forwards every setting to
   * whichever solver is selected (the grid spacing of a divergence solve
   * is ignored, as it always was). A name that no solver reads is refused
   * by CheckDiffusionSolverOptions() (DiffusionSolverFactory.h), which
   * knows them all. The base reads none.
   */
  virtual void SetOptions(const SolverOptions& options) { (void)options; }

  /// Called with the fraction done in [0, 1]; returning false aborts.
  void SetProgressCallback(std::function<bool(double)> callback) { Progress_ = std::move(callback); }

protected:
  bool ReportProgress(double fraction) const { return !Progress_ || Progress_(fraction); }

  double RelTol_ = 1e-6;
  int MaxIter_ = 2000;
  double ChangeTol_ = 0.0;
  bool WarmStart_ = true;
  std::string LinearSolver_;
  std::function<bool(double)> Progress_;
};

} // namespace translucency
