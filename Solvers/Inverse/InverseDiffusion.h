/**
 * @file InverseDiffusion.h
 * @brief Acquisition of a heterogeneous material from measurements: inverse
 * diffusion with the adjoint method (Polygrid, Sec. 4, Table I,
 * Appendix A), on the discrete-divergence forward model
 * (DiffusionForwardModel), per colour channel.
 *
 * Objective of one channel (paper Sec. 4.2, f_M, with the data term divided
 * by the sum of the squared measurements so that lambda and the stopping
 * threshold do not depend on the radiance units):
 *   F = sum_m sum_{i observed in m} (L_mi - L^R_mi)^2 / sum_m sum_i L_mi^2
 *       + lambda * sum_{neighbouring elements e,f} (A_ef / d_ef) (kappa_e - kappa_f)^2
 * with L^R = alpha phi - beta q the read-out of the forward solution (TransCut
 * eq. 3 at normal exit), A_ef the area of the faces the elements share and
 * d_ef the distance of their centroids (the finite-volume form of the
 * integral of |grad kappa|^2, the paper's sum_x |grad kappa(x)|^2).
 * Unknowns: log kappa_e and log mu_e (positivity kept by construction).
 * See Documentation/InverseDiffusion.md for the derivation and the choices.
 */
#pragma once

#include "ResourceLimits.h"

#include "DiffusionForwardModel.h"

#include <array>
#include <functional>
#include <string>
#include <vector>

namespace translucency
{

/// One row of the optimisation history.
struct InverseDiffusionIteration
{
  int Channel = 0;        ///< 0, 1, 2 = R, G, B
  std::string Stage;      ///< "homogeneous" (initial fit) or "heterogeneous"
  int Iteration = 0;      ///< 0 = the starting point
  double Objective = 0.0; ///< F after the iteration (normalised, dimensionless)
  double DataTerm = 0.0;  ///< the measurement part of F
  double GradientNorm = 0.0; ///< |dF/d(log parameters)| at the new point
  double Step = 0.0;      ///< line-search step along the search direction
  int Evaluations = 0;    ///< objective evaluations (forward passes) of the line search
};

/// What Run() returns.
struct InverseDiffusionResult
{
  std::vector<double> Kappa;      ///< 3 per element (R, G, B), mm
  std::vector<double> Absorption; ///< 3 per element, 1/mm
  std::vector<InverseDiffusionIteration> History;
  std::array<double, 3> Objective{};  ///< final F per channel
  std::array<double, 3> Threshold{};  ///< stopping threshold on the normalised F
  std::array<int, 3> Iterations{};    ///< heterogeneous CG iterations per channel
  std::array<bool, 3> Converged{};    ///< F < Threshold reached
  std::array<std::string, 3> StopReason;
  int Evaluations = 0;      ///< forward passes (factorisation + M solves), all channels
  int Gradients = 0;        ///< adjoint passes (M solves + accumulation), all channels
  double EvaluationSeconds = 0.0; ///< summed over channels (thread time)
  double GradientSeconds = 0.0;   ///< adjoint passes only, summed over channels
  int Tangents = 0;               ///< tangent passes (blocked back-solves), all channels
  double TangentSeconds = 0.0;    ///< tangent passes, summed over channels
  bool Aborted = false;
};

class InverseDiffusion
{
public:
  /// The model must outlive this object.
  explicit InverseDiffusion(const DiffusionForwardModel& model);

  /**
   * The measurements: for pattern m, irradiance[m] (q, 3 per mesh point,
   * W/mm^2), radiance[m] (measured L, 3 per mesh point, W/mm^2/sr; only
   * observed points are read) and observed[m] (1 per mesh point, non-zero =
   * observed; an empty vector, or no mask at all, means every boundary point).
   * Throws translucency::Error naming the pattern, point and channel on: a
   * different number of irradiance and radiance patterns (or masks), no
   * pattern, wrong sizes, non-finite values, negative irradiance, an observed
   * point that is not on the boundary or a mask with no observed point.
   */
  void SetMeasurements(std::vector<std::vector<double>> irradiance,
    std::vector<std::vector<double>> radiance,
    std::vector<std::vector<unsigned char>> observed = {});
  int GetNumberOfPatterns() const { return static_cast<int>(Irradiance_.size()); }

  ///@{
  /// Regulariser weight lambda (paper Sec. 4.2). Default 1e-5. Must be >= 0.
  void SetLambda(double lambda) { Lambda_ = lambda; }
  double GetLambda() const { return Lambda_; }
  ///@}
  ///@{
  /// Heterogeneous CG iteration limit per channel. Default 100.
  void SetMaxIter(int n) { MaxIter_ = n; }
  int GetMaxIter() const { return MaxIter_; }
  ///@}
  ///@{
  /// Stop when F < RelativeThreshold (F is normalised: this is the paper's
  /// epsilon = 1e-4 x sum of measured L^2, Sec. 4.2). Default 1e-4.
  void SetRelativeThreshold(double t) { RelativeThreshold_ = t; }
  double GetRelativeThreshold() const { return RelativeThreshold_; }
  ///@}
  ///@{
  /// Initial homogeneous guess (per channel) for the homogeneous fit, or the
  /// homogeneous start if the fit is off. Defaults: mu_a = 0.01 /mm,
  /// sigma_s' = 1 /mm. Values must be > 0 (checked by Run()).
  void SetInitialAbsorption(const std::array<double, 3>& mu) { InitialMu_ = mu; }
  void SetInitialReducedScattering(const std::array<double, 3>& s) { InitialSigmaS_ = s; }
  ///@}
  ///@{
  /// Fit a homogeneous (kappa, mu) pair first (paper Sec. 4.2). Default on.
  void SetHomogeneousFit(bool on) { HomogeneousFit_ = on; }
  bool GetHomogeneousFit() const { return HomogeneousFit_; }
  /// Iteration limit of the homogeneous fit. Default 30.
  void SetHomogeneousMaxIter(int n) { HomogeneousMaxIter_ = n; }
  /// The homogeneous fit stops when an iteration lowers F by less than this
  /// fraction. Default 1e-2 (an initialisation need not be precise).
  void SetHomogeneousTolerance(double tol) { HomogeneousTolerance_ = tol; }
  /// How the two homogeneous scalars are fitted: Levenberg-Marquardt on
  /// tangent solves (default; our choice, Documentation/InverseDiffusion.md)
  /// or the paper's CG with golden-section line search (Sec. 4.2).
  enum class HomogeneousMethod
  {
    GaussNewton,
    ConjugateGradient
  };
  void SetHomogeneousMethod(HomogeneousMethod m) { HomogeneousMethod_ = m; }
  HomogeneousMethod GetHomogeneousMethod() const { return HomogeneousMethod_; }
  ///@}
  /**
   * Start from these per-element values instead (3 per element each: kappa
   * in mm, mu_a in 1/mm; all > 0). Empty vectors (default) = homogeneous
   * start. With a heterogeneous start the homogeneous fit is skipped.
   */
  void SetInitialParameters(std::vector<double> kappa, std::vector<double> mu);
  ///@{
  /// Golden-section stop: bracket width < tol x step. Default 0.5.
  void SetLineSearchTolerance(double tol) { LineSearchTolerance_ = tol; }
  /// Start each golden-section bracket at the Gauss-Newton minimiser along
  /// the search direction (one tangent solve per iteration) instead of the
  /// previous step's length. Default on.
  void SetGaussNewtonLineSearch(bool on) { GaussNewtonLineSearch_ = on; }
  bool GetGaussNewtonLineSearch() const { return GaussNewtonLineSearch_; }
  ///@}
  /// OpenMP threads over the channels (0 = default). Default 0.
  void SetNumberOfThreads(int n) { NumberOfThreads_ = n; }
  /// Fraction done in [0, 1], called from one thread; false aborts.
  void SetProgressCallback(std::function<bool(double)> cb) { Progress_ = std::move(cb); }

  /// Run the optimisation (paper Table I) on the three channels in parallel.
  InverseDiffusionResult Run();

  /**
   * Objective of channel c at per-element kappa (mm) and mu (1/mm), and its
   * gradient with respect to kappa and mu (not the logs) by the adjoint
   * method if gKappa and gMu are not null (each NumberOfElements values,
   * overwritten). 2M solves with one factorisation.
   */
  double Objective(int channel, const std::vector<double>& kappa, const std::vector<double>& mu,
    std::vector<double>* gKappa = nullptr, std::vector<double>* gMu = nullptr) const;

  /// The regulariser sum_{e,f} (A_ef / d_ef) (kappa_e - kappa_f)^2 of one channel's kappa (mm).
  double Roughness(const std::vector<double>& kappa) const;

  /**
   * Forward read-out for each irradiance pattern (3 per point, W/mm^2):
   * radiance L = alpha phi - beta q on the boundary points (0 inside), 3 per
   * point. kappa and mu hold 3 per element. One factorisation per channel.
   */
  static std::vector<std::vector<double>> PredictRadiance(const DiffusionForwardModel& model,
    const std::vector<double>& kappa, const std::vector<double>& mu,
    const std::vector<std::vector<double>>& irradiance);

private:
  struct Channel;
  struct Workspace;
  Channel BuildChannel(int channel) const;
  class Optimiser;
  friend class Optimiser;

  const DiffusionForwardModel& Model_;
  std::vector<std::vector<double>> Irradiance_, Radiance_;
  std::vector<std::vector<int>> Observed_; ///< observed point ids per pattern
  double Lambda_ = 1e-5;
  int MaxIter_ = 100;
  double RelativeThreshold_ = 1e-4;
  std::array<double, 3> InitialMu_{ { 0.01, 0.01, 0.01 } };
  std::array<double, 3> InitialSigmaS_{ { 1.0, 1.0, 1.0 } };
  bool HomogeneousFit_ = true;
  int HomogeneousMaxIter_ = 30;
  double HomogeneousTolerance_ = 1e-2;
  HomogeneousMethod HomogeneousMethod_ = HomogeneousMethod::GaussNewton;
  bool GaussNewtonLineSearch_ = true;
  std::vector<double> InitialKappa_, InitialMuPerElement_;
  double LineSearchTolerance_ = 0.5;
  int NumberOfThreads_ = 0;
  std::function<bool(double)> Progress_;
};

/**
 * A block-shaped sample as a tet mesh (paper Sec. 4.1: "material samples are
 * all block-shaped and represented as a regular grid"): nx x ny x nz voxels
 * over [origin, origin + size] (mm), each voxel split into 6 tets (Kuhn
 * subdivision along its main diagonal: conforming). tetElement[t] is the
 * voxel id i + nx (j + ny k) of tet t.
 *
 * Memory: before allocating, the block and the inverse solve on it are
 * estimated at EstimateGridBlockMemory bytes; above `memoryLimit` (default
 * GetDefaultMemoryLimit(), 8 GiB) an Error states the bytes and the override.
 */
void BuildGridBlock(int nx, int ny, int nz, const double origin[3], const double size[3],
  std::vector<double>& points, std::vector<int>& tets, std::vector<int>& tetElement,
  std::size_t memoryLimit = GetDefaultMemoryLimit());

/// Bytes the block of nx x ny x nz voxels and an inverse solve on it need
/// (6 tets per voxel at ~500 bytes each: connectivity, FE system, multigrid,
/// adjoint fields; ~200 bytes per point), as a double (no overflow).
double EstimateGridBlockMemory(double nx, double ny, double nz);

/// The acquisition setups of paper Sec. 4.1 (Fig. 3).
enum class AcquisitionSetup
{
  Back, ///< lit face z = zmin, camera measures the opposite face z = zmax
  Front ///< lit face z = zmin, camera measures its unlit points
};

/**
 * Illumination patterns on the z = zmin face of a block mesh (paper Sec. 4.1:
 * the lit face split into rows x cols regions lit one at a time, q =
 * irradiance W/mm^2 in all channels on the lit region's points, region of a
 * point by half-open intervals of x and y over the face). observed[m] marks
 * the points measured under pattern m (Back: all points of the z = zmax face;
 * Front: the points of the z = zmin face with q = 0). Faces are found by
 * coordinate (within 1e-9 of the bounding box size).
 */
void MakeBlockPatterns(const std::vector<double>& points, int rows, int cols,
  AcquisitionSetup setup, double irradiance, std::vector<std::vector<double>>& patterns,
  std::vector<std::vector<unsigned char>>& observed);

} // namespace translucency
