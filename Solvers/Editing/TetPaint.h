/**
 * @file TetPaint.h
 * @brief Paint the optical coefficients of a tet mesh along a 3D stroke
 * (TransCut, Sec. 5.2).
 *
 * Every cell t gets the influence weight
 *
 *     w_t = Strength * exp(-d_t^2 / (2 Width^2))   if d_t <= R, else 0,
 *
 * d_t the distance (mm) from the cell's centroid (mean of its vertices) to
 * the nearest stroke point, and R the cut-off radius where the weight falls
 * to CutoffWeight:
 *
 *     R = Width * sqrt(2 ln(Strength / CutoffWeight))
 *
 * (CutoffWeight = 0: R infinite, the exact Gaussian everywhere;
 * CutoffWeight >= Strength: nothing is painted). With the default 1e-6 the
 * weights dropped are below 1e-6, so a paint changes a coefficient x by less
 * than 1e-6 |T - x| (SET) outside R = 5.26 Width (Strength 1). Only cells
 * whose centroid lies in the stroke's bounding box inflated by R are
 * examined; their nearest stroke point is searched in a uniform grid of cell
 * size >= R over the stroke points (27 grid cells), so the cost is one
 * centroid and one box test per cell plus the work near the stroke.
 *
 * For each channel c with ChannelMask[c] set, the coefficients x (mu_a and
 * sigma_s', 1/mm) of a cell with w > 0 become, with the target T of the same
 * coefficient and channel:
 *  - Set:      x' = (1 - w) x + w T         (T a value, 1/mm)
 *  - Multiply: x' = x (1 + w (T - 1))       (T a factor)
 *  - Add:      x' = x + w T                 (T a change, 1/mm, may be < 0)
 * then x' is clamped to >= 0. If a channel of a cell would end with
 * mu_a + sigma_s' = 0, that channel keeps its old values (counted in
 * GetNumberOfKeptChannels()). Cells with w = 0 and masked channels keep their
 * values bit for bit, so Width = 0 or Strength = 0 change nothing. A cell
 * whose centroid is not finite (NaN or infinite points) gets w = 0.
 *
 * Parallel over cells with OpenMP; the result (values, weights, the list of
 * changed cells) does not depend on the number of threads.
 */
#pragma once

#include <array>
#include <cstdint>
#include <vector>

namespace translucency
{

class TetPaint
{
public:
  /// How the target combines with the old value (see the file documentation).
  enum class Mode
  {
    Set = 0,
    Multiply = 1,
    Add = 2
  };

  /// Stroke points (3 coordinates each, mm). Default none (an error in Paint).
  void SetStrokePoints(std::vector<double> points) { Stroke_ = std::move(points); }
  const std::vector<double>& GetStrokePoints() const { return Stroke_; }
  /// Gaussian width sigma (mm, finite, >= 0; 0 paints nothing). Default 1.
  void SetWidth(double width) { Width_ = width; }
  double GetWidth() const { return Width_; }
  /// Strength in [0, 1] (0 paints nothing). Default 1.
  void SetStrength(double strength) { Strength_ = strength; }
  double GetStrength() const { return Strength_; }
  /// Weight below which a cell is not painted (in [0, 1]; 0 = exact
  /// Gaussian, no cut-off). Default 1e-6.
  void SetCutoffWeight(double weight) { CutoffWeight_ = weight; }
  double GetCutoffWeight() const { return CutoffWeight_; }
  /// Paint mode. Default Set.
  void SetMode(Mode mode) { Mode_ = mode; }
  Mode GetMode() const { return Mode_; }
  /// Targets of mu_a and sigma_s' (R, G, B): values (1/mm, Set), factors
  /// (Multiply) or changes (1/mm, Add). Default 0.
  void SetTargetAbsorption(const std::array<double, 3>& t) { TargetAbsorption_ = t; }
  void SetTargetScattering(const std::array<double, 3>& t) { TargetScattering_ = t; }
  /// Channels painted (R, G, B). Default all.
  void SetChannelMask(const std::array<bool, 3>& mask) { Mask_ = mask; }

  /// The cut-off radius R (mm) of the current settings: 0 if nothing is
  /// painted, +infinity without cut-off.
  double GetCutoffRadius() const;

  /**
   * The polyline through `points` (3 coordinates each, mm, in order) as
   * stroke points at most `spacing` (mm, finite, > 0) apart: the given
   * points are kept, in order, and each segment gets the fewest evenly spaced
   * points between its ends that achieve the spacing. Every point of the
   * polyline is then within spacing / 2 of a sample, so painting the samples
   * follows the line drawn, not only its vertices (the ParaView polyline
   * widget gives a few handles). Throws translucency::Error naming the value
   * if the spacing is not finite and > 0, a coordinate is not finite, the
   * point count is not a multiple of 3, or the result would exceed
   * `maximumPoints` points (a stroke far longer than the spacing).
   */
  static std::vector<double> SamplePolyline(
    const std::vector<double>& points, double spacing, std::int64_t maximumPoints = 10000000);

  /**
   * Paint the cells given in CSR form (cell k has the point ids
   * connectivity[offsets[k] .. offsets[k+1]-1], numberOfCells + 1 offsets)
   * of `points` (3 coordinates per point, numberOfPoints points).
   * `absorption` and `scattering` (3 values per cell, 1/mm) are updated in
   * place; `weights` (one per cell, may be null) receives w_t. Point and id
   * types: float or double, int or long long (the layouts VTK uses;
   * explicitly instantiated for these four).
   * Throws translucency::Error on invalid settings (no stroke point, a
   * negative or non-finite width, ...) and on a point id out of range or an
   * empty cell (naming the cell).
   */
  template <typename PointT, typename IdT>
  void Paint(const PointT* points, std::int64_t numberOfPoints, const IdT* offsets,
    const IdT* connectivity, std::int64_t numberOfCells, double* absorption, double* scattering,
    double* weights);

  /// Convenience overload: tets (4 point ids each) of points (3 per point).
  void Paint(const std::vector<double>& points, const std::vector<int>& tets,
    std::vector<double>& absorption, std::vector<double>& scattering,
    std::vector<double>* weights);

  /// Ids of the cells whose coefficients changed in the last Paint, ascending.
  const std::vector<int>& GetChangedCells() const { return Changed_; }
  /// Cell channels that kept their values because mu_a + sigma_s' would be 0.
  long long GetNumberOfKeptChannels() const { return Kept_; }
  /// Cells examined (centroid inside the inflated stroke box) in the last Paint.
  long long GetNumberOfCandidateCells() const { return Candidates_; }

  /// Number of OpenMP threads (0 = OpenMP default). Default 0.
  void SetNumberOfThreads(int n) { NumberOfThreads_ = n; }
  int GetNumberOfThreads() const { return NumberOfThreads_; }

private:
  void Validate() const;

  std::vector<double> Stroke_;
  double Width_ = 1.0;
  double Strength_ = 1.0;
  double CutoffWeight_ = 1e-6;
  Mode Mode_ = Mode::Set;
  std::array<double, 3> TargetAbsorption_{};
  std::array<double, 3> TargetScattering_{};
  std::array<bool, 3> Mask_{ { true, true, true } };
  int NumberOfThreads_ = 0;
  std::vector<int> Changed_;
  long long Kept_ = 0;
  long long Candidates_ = 0;
};

} // namespace translucency
