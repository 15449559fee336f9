/**
 * @file MonteCarlo.h
 * @brief The Monte Carlo reference: a volumetric random-walk photon tracer on
 * the tet mesh, the independent ground truth the diffusion solvers are
 * compared with (the role photon mapping / path tracing plays in the four
 * papers).
 */
#pragma once

#include "Detectors.h"
#include "DiffusionSolver.h"
#include "TimeResolved.h"

#include <array>
#include <cstddef>
#include <vector>

namespace translucency
{

/**
 * Photons start on the lit boundary, walk from tet to tet through shared
 * faces in the per-tet medium (mu_a, sigma_s', RefractiveIndex) and leave
 * through the Fresnel-refracting boundary.
 *
 * Sources: the problem's lights (DiffusionProblem::Lights,
 * UniformIrradiance, Shadows), not its Irradiance array, and its interior
 * sources (DiffusionProblem::InteriorSources): an isotropic point source
 * launches from its position (in the tet TetLocator finds) in a uniform
 * direction; a pencil beam is followed as a real beam: it enters at the
 * closest surface point of its entry point (LocatePencilEntry: within
 * SurfaceTolerance(), direction into the object) along the Snell-refracted
 * direction with the power (1 - R_sp) P (the specular part does not enter,
 * as for the directional light, whose q carries F_t), not the diffusion
 * side's equivalent point source one 1/mu_t' deep. The irradiance q_l
 * of each light alone is computed with ComputeBoundaryIrradiance() (same
 * shadows as the diffusion pipeline); the power entering through boundary
 * triangle f is S_f times the mean of q_l at its corners (q linear on f: the
 * total injected power is exactly what the diffusion solvers' boundary
 * source injects); a triangle is picked with probability proportional to it,
 * a point in it with density proportional to the linear q_l, and the
 * direction is the light's, refracted by Snell's law (uniform light: cosine
 * x F_t by rejection, visible directions only when shadowed). Each photon
 * carries P_c / N (W), P_c the injected power of channel c: the N photons
 * of a channel are shared among the lights' triangles and the interior
 * sources in proportion to their power (every photon has the same weight).
 *
 * Transport: free flights between scattering events with mu_s = sigma_s' /
 * (1 - g) (g = 0 by default: isotropic scattering with mu_s = sigma_s', the
 * similarity relation the diffusion model rests on); Henyey-Greenstein phase
 * function. Absorption is continuous: the weight decays as exp(-mu_a s)
 * along the path, so the power absorbed on a segment is exactly the weight
 * lost on it, w (1 - exp(-mu_a s)), and the track-length fluence tally of
 * the segment is that power / mu_a. Russian roulette below 1e-4 of the
 * launch weight (survival 1/10, weight x 10). Interior faces are
 * index-matched (the diffusion model has no interior interface condition);
 * at a boundary face the photon is reflected with probability R (exact
 * unpolarised Fresnel reflectance with the tet's eta, total internal
 * reflection included), otherwise it escapes.
 *
 * Tallies (W/mm^2, like the diffusion solvers): fluence per tet by the
 * track-length estimator (sum of weight x length in the tet / V_t); fluence
 * per mesh vertex = V_t-weighted mean of its tets' fluence, i.e. the sum of
 * their track lengths / V_i (this smooths over one ring of tets); radiant
 * exitance per boundary point (escaping weight shared among the exit
 * triangle's corners by barycentric weights, / (S_i / 3)), converted to the
 * radiance along the normal that eq. 3's angular form implies:
 * L_n = M F_t(1) / (pi UniformTransmittance(eta)) (see Documentation/Solvers.md).
 *
 * Detectors (SetDetectors, Detectors.h): the same read-out as the diffusion
 * solvers' ReadDetectors applied to the Monte Carlo point tallies, i.e.
 * the weights of LocateDetectors' footprint on the point fluence (the
 * track-length fluence of the ring of tets around each vertex) and on the
 * tallied boundary-point exitance above. A point detector (radius 0) thus
 * reads the P1 interpolant of the boundary-point exitance at its surface
 * point (photons escaping through the triangles around it, shared by
 * barycentric weights); a fibre reads the area mean of it over its disc.
 * The tallies are made per photon (so each detector has its standard error
 * from the batches, like the point arrays), not from the point arrays.
 * Exitance is what escapes (W/mm^2), with no diffusion formula in it.
 *
 * Time of flight (SetTimeGates): each photon carries its time t = (sum over
 * its segments of length x eta of the tet) / c (c = 299.792458 mm/ns,
 * SpeedOfLightMillimetresPerNanosecond; every source emits at t = 0). The
 * escaping weight is binned by exit time, the track-length fluence by the
 * time along each segment (split exactly at the gate boundaries, with the
 * continuous-absorption weight), and each gate's sum is divided by the
 * gate width: the gate average in J/(mm^2 ns) per J of pulse (a source of
 * P W is a pulse of P J), exactly the normalisation of the diffusion TPSF
 * (TimeResolved.h), so the sum over the gates times the width is the CW
 * reading minus what arrives outside [T0, T1].
 *
 * Statistics: the photons of a channel are split into B batches (default
 * 32); the standard errors come from the spread of the batch estimates.
 * Every photon has its own random stream, a function of (seed, channel,
 * photon index); batches are tallied separately and added in batch order,
 * so the results depend on (seed, photons, batches) but not on the number
 * of threads or the scheduling: bit-identical.
 *
 * Cost: NumberOfPhotons photons per channel that receives light (3N in
 * total for white light), OpenMP-parallel over the batches (at most
 * min(B, threads) threads are busy).
 *
 * Several processes (the Parallel layer's ReplicatedMonteCarloSolver, under
 * MPI): every process holds the whole problem and calls Solve; process r of
 * P traces the batches b with b % P == r, and the batch sums (and the power
 * balance) are added over the processes (SumOverShare) before the read-out,
 * so every process gets the estimates and standard errors of all B batches:
 * the one-process results up to the order of the additions. At most B
 * processes have work.
 */
class MonteCarloSolver : public DiffusionSolver
{
public:
  std::string GetName() const override { return "montecarlo"; }

  /**
   * Trace the photons and write fluence (3 per mesh point, W/mm^2). The
   * report's FluenceStandardError, Radiance and RadianceStandardError are
   * filled (3 per mesh point; Radiance 0 at interior points); LinearSolver
   * is "photons". Throws translucency::Error for: no mesh / material, a mesh
   * without tets, invalid material, NumberOfPhotons <= 0, no light at all
   * (no Lights, UniformIrradiance 0 and no interior source), an invalid
   * light, an invalid interior source (outside the object, entry point off
   * the surface, ...: the messages of Sources::Place), an invalid detector
   * (those of ReadDetectors) or invalid time gates (TimeGates::Validate). Returns false if
   * the progress callback asked to abort (outputs then unchanged).
   */
  bool Solve(const DiffusionProblem& problem, std::vector<double>& fluence,
    SolverReport& report) override;

  ///@{
  /// Photon budget per lit channel (> 0, default 1e6) and random seed
  /// (default 1). Options DiffusionOption::Photons ("photons") and
  /// DiffusionOption::Seed ("seed").
  void SetNumberOfPhotons(long long n) { NumberOfPhotons_ = n; }
  long long GetNumberOfPhotons() const { return NumberOfPhotons_; }
  void SetSeed(unsigned long long seed) { Seed_ = seed; }
  unsigned long long GetSeed() const { return Seed_; }
  ///@}

  /// The time guard: photons per channel above this budget (default 2^32,
  /// ~4.3e9: hours of tracing) are refused by Solve with an Error naming the
  /// count and this override.
  void SetMaxPhotons(long long n) { MaxPhotons_ = n; }
  long long GetMaxPhotons() const { return MaxPhotons_; }

  /// Reads "photons" (integer >= 1), "seed" (integer >= 0) and
  /// "anisotropy" (g, checked by Solve: in (-1, 1)), see
  /// DiffusionSolver::SetOptions.
  void SetOptions(const SolverOptions& options) override
  {
    options.ReadInteger(GetName(), DiffusionOption::Photons, 1.0,
      "the number of photons must be an integer >= 1", NumberOfPhotons_);
    options.ReadInteger(GetName(), DiffusionOption::Seed, 0.0,
      "the seed must be an integer >= 0", Seed_);
    options.ReadNumber(GetName(), DiffusionOption::Anisotropy, -1.0,
      "the anisotropy g must be in (-1, 1)", Anisotropy_);
  }

  /**
   * Time of flight through the interface: SetTimeGates(gates) and
   * SetDetectors(detectors), then Solve(); result gets the gates, the gate
   * readings (GetGateReadings) and, as IntegratedFluence, the photons' fluence
   * of all time. No fluence snapshots per gate (`snapshotGates` must be
   * empty, else translucency::Error).
   */
  bool SolveTimeResolved(const DiffusionProblem& problem, const TimeGates& gates,
    const std::vector<Detector>& detectors, const std::vector<int>& snapshotGates,
    TimeResolvedResult& result, SolverReport& report) override;

  /// The detector, gate and power tallies of the last Solve (always true).
  bool GetTalliedReadouts(TalliedReadouts& readouts) const override;

  ///@{
  /// Henyey-Greenstein mean cosine g in (-1, 1), default 0. The scattering
  /// coefficient is sigma_s' / (1 - g), so sigma_s' stays the reduced one.
  void SetAnisotropy(double g) { Anisotropy_ = g; }
  double GetAnisotropy() const { return Anisotropy_; }
  ///@}

  ///@{
  /// Number of batches for the standard errors (>= 2, default 32). With
  /// fewer photons than batches, one photon per batch.
  void SetNumberOfBatches(int n) { NumberOfBatches_ = n; }
  int GetNumberOfBatches() const { return NumberOfBatches_; }
  ///@}

  ///@{
  /// OpenMP threads (default 0: omp_get_max_threads()). Does not change
  /// the results.
  void SetNumberOfThreads(int n) override { NumberOfThreads_ = n; }
  int GetNumberOfThreads() const { return NumberOfThreads_; }
  ///@}

  ///@{
  /// Rays per boundary point of the shadowed uniform light (default 32, as
  /// vtkSurfaceIrradiance; 0 = unshadowed exact). The problem does not carry
  /// it: set it to what made the problem's Irradiance.
  void SetUniformLightSamples(int n) { UniformLightSamples_ = n; }
  int GetUniformLightSamples() const { return UniformLightSamples_; }
  ///@}

  ///@{
  /// Detectors read by the next Solve() (default none; Detectors.h).
  void SetDetectors(const std::vector<Detector>& detectors) override { Detectors_ = detectors; }
  const std::vector<Detector>& GetDetectors() const { return Detectors_; }
  ///@}

  ///@{
  /// Time gates of the time-of-flight tallies (Count 0, the default: none).
  /// StepsPerGate is not used (there are no time steps).
  void SetTimeGates(const TimeGates& gates) { Gates_ = gates; }
  const TimeGates& GetTimeGates() const { return Gates_; }
  ///@}

  ///@{
  /// Detector readings of the last Solve(), one per detector (all time:
  /// the continuous-wave values, W/mm^2 per channel; Area and
  /// SurfacePosition as ReadDetectors), and their standard errors (W/mm^2;
  /// NaN with a single batch).
  const std::vector<DetectorReading>& GetDetectorReadings() const { return Readings_; }
  const std::vector<DetectorReading>& GetDetectorStandardErrors() const { return ReadingErrors_; }
  ///@}

  ///@{
  /// Time-of-flight readings of the last Solve() with time gates:
  /// [gate][detector], gate averages in J/(mm^2 ns) per J of pulse (the
  /// layout of TimeResolvedResult::Readings), and their standard errors.
  const std::vector<std::vector<DetectorReading>>& GetGateReadings() const { return GateReadings_; }
  const std::vector<std::vector<DetectorReading>>& GetGateStandardErrors() const
  {
    return GateReadingErrors_;
  }
  ///@}

  /// Power bookkeeping of one channel (W), valid after Solve(). With
  /// continuous absorption, Injected + RouletteGain = Absorbed + Escaped +
  /// Lost holds to round-off; RouletteGain has mean 0.
  struct PowerBalance
  {
    double Injected = 0.0;     ///< sum of the launch weights
    double Absorbed = 0.0;     ///< weight lost along the paths
    double Escaped = 0.0;      ///< weight that left through the boundary
    double RouletteGain = 0.0; ///< weight added by survivors minus weight killed
    double Lost = 0.0;         ///< weight of photons stopped by a safety limit
    long long Photons = 0;     ///< photons traced
    long long LostPhotons = 0; ///< photons stopped by a safety limit (should be 0)
    long long Steps = 0;       ///< free-flight segments (tet crossings + events)
  };
  const PowerBalance& GetPowerBalance(int c) const { return Balance_[c]; }

  ///@{
  /// Tallies of the last Solve(): fluence per tet (3 per tet, W/mm^2) and
  /// radiant exitance per mesh point (3 per point, W/mm^2, 0 inside), with
  /// their standard errors.
  const std::vector<double>& GetTetFluence() const { return TetFluence_; }
  const std::vector<double>& GetExitance() const { return Exitance_; }
  const std::vector<double>& GetExitanceStandardError() const { return ExitanceError_; }
  ///@}

  /// Photons traced in the last Solve() (all channels) and threads used.
  long long GetNumberOfPhotonsTraced() const { return PhotonsTraced_; }
  int GetNumberOfThreadsUsed() const { return ThreadsUsed_; }
  /// Photons per second per thread of the last Solve()'s tracing.
  double GetPhotonsPerSecondPerThread() const { return Rate_; }

protected:
  /**
   * The share of this process when one run is split over P processes (see
   * the class comment): it traces the batches b with b % size == rank.
   * Default 0 of 1: every batch.
   */
  void SetShare(int rank, int size)
  {
    ShareRank_ = rank;
    ShareSize_ = size;
  }
  int GetShareSize() const { return ShareSize_; }
  /// Collective over the share's processes (every one calls it with the same
  /// `count`): each of `values` becomes its sum over them, the same on every
  /// process. The default (one process) leaves them.
  virtual void SumOverShare(double* values, std::size_t count) const
  {
    (void)values;
    (void)count;
  }

private:
  int ShareRank_ = 0;
  int ShareSize_ = 1;
  long long NumberOfPhotons_ = 1000000;
  long long MaxPhotons_ = 4294967296LL;
  unsigned long long Seed_ = 1;
  double Anisotropy_ = 0.0;
  int NumberOfBatches_ = 32;
  int NumberOfThreads_ = 0;
  int UniformLightSamples_ = 32;

  std::vector<Detector> Detectors_;
  TimeGates Gates_;

  std::array<PowerBalance, NumberOfChannels> Balance_{};
  std::vector<DetectorReading> Readings_, ReadingErrors_;
  std::vector<std::vector<DetectorReading>> GateReadings_, GateReadingErrors_;
  std::vector<double> TetFluence_;
  std::vector<double> Exitance_;
  std::vector<double> ExitanceError_;
  long long PhotonsTraced_ = 0;
  int ThreadsUsed_ = 0;
  double Rate_ = 0.0;
};

} // namespace translucency
