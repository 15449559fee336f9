/**
 * @file VertexDiffusionSolver.h
 * @brief A DiffusionSolver for discretisations whose unknowns are the mesh
 * vertices and whose matrix is SPD (discrete divergence, FEM): assemble, then
 * solve the three channels with the LinearSolver named by SetLinearSolver()
 * ("" = GetDefaultLinearSolverName()), with warm start.
 *
 * The LinearSolver object (and its hierarchy or factor) is kept across
 * solves: Setup(patternChanged = true) after a mesh change (another mesh
 * object, or its size or pattern changed), Setup(false) when only matrix
 * values changed (paint, material, deformation), no Setup at all when only
 * the right-hand side changed (relight). Changing the name creates a new
 * solver object.
 */
#pragma once

#include "CollimatedSource.h"
#include "DiffusionSolver.h"
#include "Discretization.h"
#include "LinearSolver.h"
#include "TimeResolved.h"

#include <complex>
#include <cstdint>

namespace translucency
{

/**
 * Throw translucency::Error, starting with `name`, naming both lengths when
 * the mesh cannot resolve the diffusion wave of modulation `frequency` (Hz,
 * omega = 2 pi f): its shortest wavelength 2 pi / Im k, k = sqrt((mu_a + i
 * omega eta / c) / kappa), below the edge of a regular tet of the mean
 * volume, or omega eta / c not finite. Shared by the vertex solvers and sp3.
 */
void CheckFrequencyResolution(const std::string& name, const TetMesh& mesh,
  const OpticalProperties& material, double frequency, double omega);

class VertexDiffusionSolver : public DiffusionSolver
{
public:
  /// Takes ownership of the discretisation.
  explicit VertexDiffusionSolver(std::unique_ptr<Discretization> discretization);

  std::string GetName() const override { return Discretization_->GetName(); }
  bool Solve(const DiffusionProblem& problem, std::vector<double>& fluence,
    SolverReport& report) override;
  void Reset() override;
  /// The discretisation's assembly threads (Discretization::SetNumberOfThreads).
  void SetNumberOfThreads(int n) override { Discretization_->SetNumberOfThreads(n); }

  /**
   * Frequency domain: solve the complex diffusion equation
   *   -div(kappa grad Phi) + (mu_a + i omega eta / c) Phi = S,  omega = 2 pi f,
   * (kappa real, c = 299792458e3 mm/s the speed of light in vacuum, eta the
   * tet's refractive index) with the same boundary condition and sources as
   * Solve(), the sources and the boundary irradiance modulated at f with
   * phase 0. The matrix is this discretisation's real matrix plus i times
   * its mass matrix (Discretization::AddMass) times omega eta / c: complex
   * symmetric, solved by COCG (ComplexConjugateGradient.h) to GetRelTol()
   * within GetMaxIter() iterations, no warm start. The preconditioner
   * follows the linear solver a continuous-wave Solve() would use (the name
   * of SetLinearSolver, or by size GetDefaultLinearSolverName(unknowns)):
   * multigrid-agg -> its cycle built on the real part A, applied to the real
   * and imaginary parts (the three channels together; report.LinearSolver
   * "cocg-multigrid-agg"); any other -> the Jacobi preconditioner of the
   * complex diagonal, per channel ("cocg-jacobi"). A hierarchy is built per
   * call (set-up time in report.SetupMilliseconds). The extended collimated
   * models: the beam and its volume source carry the beam's own modulation
   * exp(-i omega eta s / c) (ComputeCollimatedFrequencyLoad; a complex
   * right-hand side); `fluence` is then Phi_d + E_c~, and report has the
   * beam's amplitude and phase (CollimatedFluence, CollimatedFluencePhase).
   * @param frequency modulation frequency f in Hz (finite, > 0; else
   *        translucency::Error naming the value); refused too when the
   *        diffusion wave's shortest wavelength 2 pi / Im k, k = sqrt((mu_a
   *        + i 2 pi f eta / c) / kappa), is below the mesh's typical edge
   *        (the edge of a regular tet of the mean volume): the mesh cannot
   *        carry the phase (CheckFrequencyResolution)
   * @param fluence complex Phi, 3 values per mesh point (W/mm^2 per W of
   *        source modulation amplitude); amplitude |Phi|, phase arg(Phi)
   *        (negative: the fluence lags the source)
   * Returns false if the progress callback aborted.
   */
  bool SolveFrequencyDomain(const DiffusionProblem& problem, double frequency,
    std::vector<std::complex<double>>& fluence, SolverReport& report) override;

  /// Throw translucency::Error naming both lengths when the mesh cannot
  /// resolve the diffusion wave of modulation `frequency` (Hz, omega = 2 pi f).
  void CheckFrequencyResolution(const TetMesh& mesh, const OpticalProperties& material,
    double frequency, double omega) const;

  /**
   * Time-resolved (TimeResolved.h has the equation, the scheme and the
   * units): the response to a pulse of the sources and the boundary
   * irradiance at t = 0 (energy P J for a source of power P), averaged over
   * `gates`, by implicit time stepping (one backward-Euler step, then BDF2)
   * with this discretisation's mass matrix; each step is solved to
   * GetRelTol() within GetMaxIter() iterations from the extrapolated
   * previous values by the linear solver a continuous-wave Solve() would use
   * (SetLinearSolver's name, or by size GetDefaultLinearSolverName(unknowns):
   * multigrid-agg, its hierarchy built once per call and its values set up
   * again only when the step changes, from LargeSystemUnknowns on; cg-jacobi
   * below). The extended collimated models: the beam's volume source is a
   * delayed pulse per point (ComputeCollimatedTimeLoad), the integrated
   * fluence and the snapshots include E_c where the pulse arrives.
   * Implemented in TimeResolved.cxx.
   * @param gates validated (TimeGates::Validate throws translucency::Error)
   * @param detectors read at every gate (ReadDetectors); may be empty
   * @param snapshotGates gates (0-based) whose gate-averaged fluence is kept
   *        (an index outside 0..N-1 is a translucency::Error)
   * @param result the readings, the integrated fluence and the snapshots;
   *        report: Iterations are summed over the steps, Residual is the
   *        largest of the steps', Converged false if any step did not.
   * Returns false if the progress callback aborted.
   */
  bool SolveTimeResolved(const DiffusionProblem& problem, const TimeGates& gates,
    const std::vector<Detector>& detectors, const std::vector<int>& snapshotGates,
    TimeResolvedResult& result, SolverReport& report) override;
  /**
   * Earlier step solutions of the same step matrix whose A-norm-best
   * combination with the extrapolated guess starts each time step
   * (SolutionRecycler in double precision: exact, no extra product),
   * 0..SolutionRecycler::MaxCapacity (4); default 4. 0: the extrapolation
   * 2 phi^n - phi^(n-1) alone (before session 21). Used by the multigrid-agg
   * step solver; the cg-jacobi steps start from the extrapolation. Measured
   * (DiffuseOptics.md, Performance): 100 gates at 200k tets need 0.3x the
   * iterations of the extrapolation alone.
   */
  void SetTimeStepRecycledSolutions(int k);
  /// Reads "time-step-recycled" (DiffusionOption::TimeStepRecycled, an
  /// integer 0..4), see DiffusionSolver::SetOptions.
  void SetOptions(const SolverOptions& options) override
  {
    int k = TimeStepRecycled_;
    if (options.ReadInteger(GetName(), DiffusionOption::TimeStepRecycled, 0.0,
          "the recycled step solutions must be an integer 0..4", k))
    {
      SetTimeStepRecycledSolutions(k);
    }
  }
  int GetTimeStepRecycledSolutions() const { return TimeStepRecycled_; }

  /**
   * Painting (TransCut Sec. 5.2): the next Solve() only rebuilds the rows of
   * the vertices of `changedTets` (tet ids) instead of assembling the whole
   * system, and warm-starts from the previous solution. The caller
   * guarantees that, compared with the previous successful Solve(), only the
   * material of these tets changed (same irradiance). Falls back to a full
   * assembly (SolverReport::Assembly tells which was done) if there was no
   * previous successful Solve() on this mesh object with its current geometry
   * (TetMesh::GetGeometryRevision) or the discretisation has no incremental
   * update. One-shot: cleared
   * by the next Solve() or Reset().
   *
   * With `irradianceChanged` (a relight, possibly with a paint) the
   * irradiance may differ too: the right-hand side is then rebuilt for it
   * (Discretization::UpdateRightHandSide, O(boundary points)) and the
   * matrices and the linear solver's set-up are kept when no tet changed
   * (SolverReport::Assembly "right-hand side"). Falls back to a full
   * assembly as above, or when the discretisation has no such update.
   */
  void SetChangedTets(std::vector<int> changedTets, bool irradianceChanged = false) override;

  /// The discretisation (e.g. to set its number of threads).
  Discretization& GetDiscretization() { return *Discretization_; }
  /// The system of the last Solve (valid until the next one).
  const DiffusionSystem& GetSystem() const { return System_; }

  /// The linear solver of the last Solve (null before the first one).
  LinearSolver* GetLinearSolverObject() { return Linear_.get(); }
  /// The default linear solver of small systems (below
  /// LargeSystemUnknowns unknowns), and the first of GetLinearSolverNames().
  static std::string GetDefaultLinearSolverName();
  /**
   * The linear solver used when SetLinearSolver("") (the default), chosen by
   * size: cg-jacobi (no set-up) below LargeSystemUnknowns unknowns per
   * channel, multigrid-agg from there on (measured in `bench
   * --linear-solvers`, Documentation/Performance.md: set-up + cold solve
   * 0.80x of cg-jacobi and warm relights 0.46x at 27k unknowns, 0.31x and
   * 0.21x at 183k).
   */
  static std::string GetDefaultLinearSolverName(int unknowns);
  /// Size (unknowns per channel, about 90k tets) from which the default is
  /// multigrid-agg.
  static constexpr int LargeSystemUnknowns = 20000;

private:
  std::unique_ptr<Discretization> Discretization_;
  DiffusionSystem System_;
  std::unique_ptr<LinearSolver> Linear_;
  std::string LinearName_; ///< lower-case name Linear_ was created for
  bool LinearReady_ = false;
  int TimeStepRecycled_ = 4; ///< SetTimeStepRecycledSolutions
  /// The values of the previous assembly, to detect value-only changes.
  std::array<std::vector<double>, NumberOfChannels> PreviousValues_;
  std::array<Eigen::VectorXd, NumberOfChannels> Solution_;
  const TetMesh* LastMesh_ = nullptr;
  int LastPoints_ = -1;
  int LastTets_ = -1;
  std::size_t LastNonZeros_ = 0;
  std::uint64_t LastRevision_ = 0; ///< TetMesh::GetGeometryRevision of the last solve
  bool HasChangedTets_ = false;
  bool IrradianceChanged_ = false; ///< SetChangedTets' second argument
  /// System_'s right-hand side holds a volume load (interior sources, the
  /// extended collimated beam): an incremental update rebuilds it.
  bool SystemHasSources_ = false;
  std::vector<int> ChangedTets_;
  /// The extended collimated source of the last solves (a paint
  /// re-integrates the changed tets only; SolverReport::Collimated).
  CollimatedSourceCache CollimatedCache_;
};

} // namespace translucency
