/**
 * @file DiffusionFrontEnd.h
 * @brief One diffusion solver kept across the solves of a changing scene
 * (relight, paint, cut), with the bookkeeping an interactive front end
 * needs: the solver by name (GetDiffusionSolverRegistry()), a new solver
 * or a new mesh forgets the warm start, and after a paint only the changed
 * tets are re-assembled (TransCut Sec. 5.2). vtkSolveDiffusion converts its
 * input and calls this.
 *
 * Incremental assembly (vertex solvers, IncrementalAssembly on): the front
 * end keeps the material and the irradiance of its last successful solve
 * (7 doubles per tet and 3 per point, moved in, not copied). When the next
 * solve has the same mesh object (same topology and points: a TetMesh
 * shared by the pipeline is keyed by both), the same irradiance (bit for
 * bit) and at most MaximumChangedFraction of the tets have another mu_a,
 * sigma_s' or eta (compared bit for bit, so any change is seen, whoever
 * made it), it hands those tets to VertexDiffusionSolver::SetChangedTets:
 * only their vertices' rows are rebuilt (the system equals a full
 * assembly) and the solve warm-starts from the previous fluence. Beyond the
 * fraction a parallel full assembly is faster than the serial row update.
 *
 * One front end for every domain and read-out: Solve(..., request, result)
 * takes the domain (continuous wave, frequency f, time gates) and the
 * read-outs (detectors, snapshots; the power balance by
 * ComputePowerBalance) and decides by the registry traits of the solver
 * (SupportsFrequency, SupportsTime, IsStochastic), never by its name or
 * type: a domain the solver lacks is refused with the solvers that have it.
 *
 * Never a non-converged result: a solve that does not converge is done
 * again in the same call after a full set-up (DiffusionSolver::Reset: a new
 * hierarchy or factor, a full assembly, no warm start); if that does not
 * converge either, Solve throws translucency::Error naming every channel's
 * residual and iterations (SolveRequest::AcceptUnconverged is the one
 * exception, for convergence studies).
 *
 * Why here and not in VertexDiffusionSolver: the cache is a policy of
 * interactive use (memory for a copy of the material, a comparison per
 * solve) that the other users of the solver (inverse diffusion, tests,
 * benchmarks) do not want; VertexDiffusionSolver keeps its explicit
 * SetChangedTets contract, and this class also owns the choice of solver
 * by name, which only this layer (above every solver) can make.
 */
#pragma once

#include "DiffusionSolver.h"
#include "Fresnel.h"

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace translucency
{

/// The domain of a solve.
enum class SolveDomain
{
  ContinuousWave, ///< DiffusionSolver::Solve
  Frequency,      ///< DiffusionSolver::SolveFrequencyDomain (trait SupportsFrequency)
  Time            ///< DiffusionSolver::SolveTimeResolved (trait SupportsTime)
};

/// What DiffusionFrontEnd::Solve solves and reads out.
struct SolveRequest
{
  SolveDomain Domain = SolveDomain::ContinuousWave;
  double Frequency = 0.0;          ///< Hz, finite and > 0 for SolveDomain::Frequency
  TimeGates Gates;                 ///< SolveDomain::Time (validated by the solver)
  std::vector<int> Snapshots;      ///< SolveDomain::Time: gates whose fluence is kept
  std::vector<Detector> Detectors; ///< read after the solve, any domain (may be empty)
  /**
   * Hand on a solve that did not converge (after the re-solve) instead of
   * throwing: for convergence studies only (translucency compare's error
   * against time stops solves early on purpose). Default false.
   */
  bool AcceptUnconverged = false;
};

/// What DiffusionFrontEnd::Solve returns (valid after a successful Solve).
struct SolveResult
{
  SolverReport Report;
  /**
   * 3 per mesh point (W/mm^2). Continuous wave: phi. Frequency: |Phi_d| +
   * E_c (the diffuse amplitude plus the beam's, so that Fluence -
   * CollimatedFluence is the diffuse amplitude downstream). Time: the
   * integral of phi over the gates (J/mm^2 per J).
   */
  std::vector<double> Fluence;
  /// Frequency domain: amplitude |Phi| and phase arg(Phi) (radians) of the
  /// total fluence, 3 per point; empty otherwise.
  std::vector<double> Amplitude, Phase;
  /// One per detector: continuous wave the readings; frequency their
  /// amplitudes (phases in FluencePhase / ExitancePhase, radians, 0 in the
  /// other domains); time the integrals of the gate readings.
  std::vector<DetectorReading> Readings;
  std::vector<std::array<double, 3>> FluencePhase, ExitancePhase;
  /// Time domain: gates, gate readings, snapshots (TimeResolved.h).
  TimeResolvedResult Time;
  /// Stochastic solvers (trait IsStochastic): the standard errors of
  /// Readings (continuous wave) and of Time.Readings ([gate][detector]),
  /// and the photons' own power bookkeeping (HasTalliedBalance).
  std::vector<DetectorReading> ReadingErrors;
  std::vector<std::vector<DetectorReading>> GateErrors;
  bool HasTalliedBalance = false;
  std::array<double, NumberOfChannels> TalliedInjected{}, TalliedAbsorbed{}, TalliedEscaped{};
  /// The Robin rule of the solve (Moments for the extended-moments
  /// collimated model), for the power balance and the radiance.
  Fresnel::BoundaryRule Rule = Fresnel::BoundaryRule::Fit;
};

class DiffusionFrontEnd
{
public:
  DiffusionFrontEnd();
  ~DiffusionFrontEnd();

  /**
   * The solver by name (case-insensitive, GetDiffusionSolverNames();
   * default "divergence"). Another name creates a new solver (its settings
   * are the defaults again) and forgets the warm start; the same name keeps
   * the solver. Throws translucency::Error for an unknown name (the solver
   * is then unchanged).
   */
  void SetSolver(const std::string& name);
  /**
   * The communicator of the next solves (model: PETSc, where every object
   * has one and serial is a communicator of size one). None (the default):
   * the in-process solvers. An MPI communicator, of any size (one
   * included): the registry's distributed variant of the named solver
   * (trait Distributed; SetSolver keeps choosing variants while it is set),
   * in continuous wave; every rank of the communicator then calls Solve
   * together with its own piece: the mesh of its owned tets (null for a rank
   * without tets) and DiffusionProblem::PointKeys. A new communicator
   * creates a new solver (default settings) and forgets the warm start.
   * Throws translucency::Error for a solver without a distributed variant,
   * naming those with one (the front end is then unchanged).
   */
  void SetCommunicator(const Communicator& comm);
  const Communicator& GetCommunicator() const { return Comm_; }
  /// The registry name of the current solver.
  const std::string& GetSolverName() const { return SolverName_; }
  /// The current solver, to set its parameters (RelTol, options, ...).
  DiffusionSolver& GetSolver() { return *Solver_; }

  ///@{
  /// Re-assemble only the changed tets after a paint (see the file
  /// comment). Default on. Off also drops the cached material.
  void SetIncrementalAssembly(bool on);
  bool GetIncrementalAssembly() const { return IncrementalAssembly_; }
  ///@}

  ///@{
  /// Largest fraction of changed tets (in [0, 1]) for which the update is
  /// incremental. Default 0.05.
  void SetMaximumChangedFraction(double fraction) { MaximumChangedFraction_ = fraction; }
  double GetMaximumChangedFraction() const { return MaximumChangedFraction_; }
  ///@}

  /**
   * Solve on `mesh` with this material and irradiance (q, 3 per point,
   * W/mm^2); `light` gives the lights, UniformIrradiance and Shadows (its
   * Mesh, Material and Irradiance are ignored). Material and irradiance are
   * taken by value: move them in, the front end keeps them for the next
   * comparison. Another mesh object than the last one resets the solver
   * (no warm start). Returns false if the solver's progress callback
   * aborted (the cache is then forgotten); throws translucency::Error as
   * the solver does (the cache is then forgotten and the solver reset).
   */
  bool Solve(std::shared_ptr<const TetMesh> mesh, OpticalProperties material,
    std::vector<double> irradiance, const DiffusionProblem& light, std::vector<double>& fluence,
    SolverReport& report);

  /**
   * The one solve of every caller (the filter, the CLI, the benches): as the
   * Solve above, in the domain of `request`, with its read-outs, decided by
   * the solver's registry traits. Throws translucency::Error for a domain
   * the solver lacks ("the grid solver has no frequency domain (...):
   * solvers with one: divergence, fem"), for invalid input (the solver's
   * messages) and for a solve that did not converge also after a full
   * set-up (see the file comment). Only continuous-wave solves feed the
   * incremental assembly of the next paint.
   */
  bool Solve(std::shared_ptr<const TetMesh> mesh, OpticalProperties material,
    std::vector<double> irradiance, const DiffusionProblem& light, const SolveRequest& request,
    SolveResult& result);

  /**
   * True when the front end keeps the material of its last successful solve
   * on `mesh` (a vertex solve in continuous wave with IncrementalAssembly
   * on, for the changed-tet detection in process; the distributed solve's
   * piece too, for a relight):
   * SolveKeptMaterial may then be called. GetKeptMaterial() is that material
   * (null when there is none).
   */
  bool HasKeptMaterial(const std::shared_ptr<const TetMesh>& mesh) const;
  const OpticalProperties* GetKeptMaterial() const { return HaveLast_ ? &LastMaterial_ : nullptr; }

  /**
   * Solve as above with the material of the last successful solve, which the
   * caller knows did not change (e.g. the filter's input carries the same
   * coefficient arrays, not modified since): it is not copied, compared tet
   * by tet or validated again (a relight). Throws translucency::Error unless
   * HasKeptMaterial(mesh).
   */
  bool SolveKeptMaterial(std::shared_ptr<const TetMesh> mesh, std::vector<double> irradiance,
    const DiffusionProblem& light, const SolveRequest& request, SolveResult& result);

  /**
   * A paint stroke without a copy of the material: the next solve's
   * coefficients as the caller's contiguous per-tet arrays (3, 3 and 1
   * values per tet, `mesh`'s tets in order) compared bit for bit with the
   * kept material in one parallel pass; the changed tets' values are written
   * into it and SolveKeptMaterial then solves with them, re-assembling only
   * the changed tets' rows (as Solve would after FindChangedTets). Returns
   * false, with nothing changed, unless HasKeptMaterial(mesh). Throws
   * translucency::Error, with OpticalProperties::Validate's message (the
   * lowest invalid tet), when a changed value is invalid; the kept material
   * is then unchanged. The unchanged tets were validated by the solve that
   * kept them.
   */
  bool UpdateKeptMaterial(const std::shared_ptr<const TetMesh>& mesh, const double* absorption,
    const double* scattering, const double* refractiveIndex);

  /// How many times a solve compared its material tet by tet with the kept
  /// one (FindChangedTets, UpdateKeptMaterial) since construction:
  /// SolveKeptMaterial does not.
  long long GetNumberOfMaterialComparisons() const { return MaterialComparisons_; }

  /**
   * Throws translucency::Error unless the current solver has the domain of
   * `request` (its registry traits), naming the solvers that have it. Solve
   * calls it first; callers may call it before converting their input.
   */
  void CheckDomain(const SolveRequest& request) const;

  /**
   * The power balance of `result` (a continuous-wave or time solve, its
   * Fluence passed as `fluence`; W per channel): the photons' own bookkeeping for a stochastic solver, else
   * ComputePowerBalance of the diffuse fluence with the solve's Robin rule
   * plus the interior sources' power and the extended model's beam
   * (DiffuseOptics.md, "Power balance"). Throws translucency::Error for a
   * frequency-domain result (the fluence is complex).
   */
  static void ComputePowerBalance(const TetMesh& mesh, const OpticalProperties& material,
    const std::vector<double>& fluence, const std::vector<double>& irradiance,
    const Sources* sources, const SolveResult& result,
    SolveDomain domain, std::array<double, NumberOfChannels>& injected,
    std::array<double, NumberOfChannels>& absorbed, std::array<double, NumberOfChannels>& escaped);

  /// Tets found changed for the last solve's incremental update; -1 if it
  /// did not look (not a vertex solver, IncrementalAssembly off, no cached
  /// solve, another mesh, another irradiance, or more changed tets than
  /// MaximumChangedFraction allows).
  long long GetNumberOfChangedTets() const { return ChangedTets_; }

  /// Forget the mesh, the cache and the warm start (keeps the solver and
  /// its settings).
  void Reset();

  /**
   * Ids of the tets whose mu_a, sigma_s' or eta differ between `a` and `b`
   * (same sizes), compared as bits (a NaN that stays a NaN is no change),
   * stopping once more than `limit` are found.
   */
  static std::vector<int> FindChangedTets(
    const OpticalProperties& a, const OpticalProperties& b, std::size_t limit);

private:
  void ForgetLast();
  void DetectChangedTets(
    const OpticalProperties& material, const std::vector<double>& irradiance, bool kept);
  bool SolveMaterial(std::shared_ptr<const TetMesh> mesh, OpticalProperties material,
    std::vector<double> irradiance, const DiffusionProblem& light, const SolveRequest& request,
    SolveResult& result, bool kept);
  bool SolveOnce(const DiffusionProblem& problem, const SolveRequest& request, SolveResult& result);
  bool SolveFrequency(const DiffusionProblem& problem, const SolveRequest& request,
    SolveResult& result);
  void ReadOut(const DiffusionProblem& problem, const SolveRequest& request, SolveResult& result);

  /// A new solver of the registry entry `name` for communicator `comm`.
  static std::unique_ptr<DiffusionSolver> MakeSolver(
    const std::string& name, const Communicator& comm);

  std::string SolverName_;
  Communicator Comm_;
  std::unique_ptr<DiffusionSolver> Solver_;
  std::shared_ptr<const TetMesh> Mesh_;
  bool IncrementalAssembly_ = true;
  double MaximumChangedFraction_ = 0.05;
  /// Material and irradiance of the last successful vertex solve; HaveLast_
  /// is false when they are not valid.
  bool HaveLast_ = false;
  OpticalProperties LastMaterial_;
  std::vector<double> LastIrradiance_;
  long long ChangedTets_ = -1;
  long long MaterialComparisons_ = 0;
  /// The tets UpdateKeptMaterial found changed, for the next SolveKeptMaterial.
  std::optional<std::vector<int>> PendingChanges_;
};

} // namespace translucency
