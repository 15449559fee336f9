/**
 * @file Detectors.h
 * @brief Read-outs of a diffusion solution on the surface: detectors (point
 * or fibre; fluence and exitance per channel) and the power balance.
 * Documentation/DiffuseOptics.md has the conventions.
 */
#pragma once

#include "Fresnel.h"
#include "InteriorSources.h"

#include <utility>
#include <vector>

namespace translucency
{

/**
 * Power balance of a solution (per channel, W), with the P1 integrals of the
 * vertex discretisations (exact for a P1 phi; the lumped integrals of the
 * discrete divergence have the same values):
 *  - Absorbed = integral of mu_a phi over the object;
 *  - Escaped = integral over the surface of the exitance J = (phi - 2 q)/(2 A)
 *    (the flux leaving; DetectorReading::Exitance);
 *  - BoundaryInjected = integral of q (boundary irradiance entering).
 * For a converged solve Absorbed + Escaped = BoundaryInjected + the interior
 * sources' InjectedPower (both discretisations satisfy it to solver
 * tolerance: summing the rows of their systems gives exactly these integrals
 * when eta is uniform on the surface). `irradiance` may be null (q = 0).
 */
struct PowerBalance
{
  std::array<double, NumberOfChannels> Absorbed{};
  std::array<double, NumberOfChannels> Escaped{};
  std::array<double, NumberOfChannels> BoundaryInjected{};
};
/**
 * The PowerBalance of `fluence` (3 values per mesh point, W/mm^2).
 * `rule`: the Robin coefficients the solve used (Fresnel::BoundaryRule;
 * Moments with the "extended-moments" collimated model). With Moments the
 * exitance is J = q + (phi - 4 q / (1 - Fdr)) / (2 A) (the flux of the
 * Robin condition plus the injected q; with the fit's A = (1 + Fdr) /
 * (1 - Fdr) this is the (phi - 2 q) / (2 A) above).
 */
PowerBalance ComputePowerBalance(const TetMesh& mesh, const OpticalProperties& material,
  const std::vector<double>& fluence, const std::vector<double>* irradiance,
  Fresnel::BoundaryRule rule = Fresnel::BoundaryRule::Fit,
  const std::vector<char>* boundaryFaces = nullptr);
/// ComputePowerBalance for a material the caller validated in the same
/// solve (the distributed solver's every Solve): its sizes are checked, its
/// values not again.
PowerBalance ComputePowerBalanceOfValidMaterial(const TetMesh& mesh,
  const OpticalProperties& material, const std::vector<double>& fluence,
  const std::vector<double>* irradiance, Fresnel::BoundaryRule rule,
  const std::vector<char>* boundaryFaces);

/// A detector on the surface: a point or a fibre face of radius Radius.
struct Detector
{
  std::array<double, 3> Position{}; ///< mm, on the surface (within SurfaceTolerance())
  double Radius = 0.0; ///< fibre radius (mm, >= 0); 0 = the value at the point
  /// Name used in error messages; "" = "detector <k>" (1-based).
  std::string Label;
};

/// What a detector reads (per channel).
struct DetectorReading
{
  std::array<double, 3> SurfacePosition{}; ///< the closest surface point (mm)
  double Area = 0.0; ///< surface area averaged over (mm^2); 0 for a point detector
  std::array<double, NumberOfChannels> Fluence{};  ///< phi, W/mm^2
  /// Exitance (diffuse reflectance) J = (phi - 2 q) / (2 A), W/mm^2: the
  /// hemispherical integral of TransCut eq. 3's radiance (F_t integrates to
  /// 1 - Fdr), equal to the flux -kappa dphi/dn of the Robin condition where
  /// q = 0. A from the refractive index of the tet under the point.
  std::array<double, NumberOfChannels> Exitance{};
};

/**
 * Where a detector reads: its closest surface point and the P1 samples its
 * reading averages (ReadDetectors): reading = sum of Weight x (the P1 value
 * at Weights in Triangle), divided by Area for a fibre. A point detector
 * (and a fibre whose disc catches no sub-triangle) has one sample of
 * weight 1 and Area 0.
 */
struct DetectorFootprint
{
  struct Sample
  {
    int Triangle = -1;   ///< boundary triangle (TetMesh numbering)
    double Weights[3]{}; ///< barycentric weights in it
    double Weight = 0.0; ///< mm^2 (sub-triangle area) for a fibre, 1 for a point
  };
  std::array<double, 3> SurfacePosition{}; ///< mm
  double Area = 0.0;                       ///< mm^2, 0 for a point detector
  std::vector<Sample> Samples;

  /// The reading as weights of mesh-point values: reading = sum over the
  /// pairs (point i, w_i) of w_i x value_i (sorted by point, merged; the
  /// weights sum to 1).
  std::vector<std::pair<int, double>> GetPointWeights(const TetMesh& mesh) const;
};

/**
 * The fibre samples of one boundary triangle (p0, p1, p2; area mm^2, number
 * f): the triangle is skipped unless it faces the same way as `normal` and
 * may reach the disc of `radius` (mm, > 0) around `centre`; else it is split
 * into m^2 sub-triangles no larger than radius / 4 (m <= 64) and each whose
 * centroid is in the disc is appended to `samples` (weight: its area),
 * its area added to `area`. LocateDetectors and the distributed read-out
 * (Parallel/DistributedSources.h) share it.
 */
void AppendFibreSamples(const double* p0, const double* p1, const double* p2, double triangleArea,
  int f, const std::array<double, 3>& centre, const std::array<double, 3>& normal, double radius,
  std::vector<DetectorFootprint::Sample>& samples, double& area);

/**
 * Adds `weight` x (the P1 fluence and exitance at barycentric weights w of
 * boundary triangle f) to `reading` (A and Fdr of the tet under f, `rule`
 * as in ComputePowerBalance). `irradiance` may be null (q = 0).
 */
void AccumulateDetectorSample(const TetMesh& mesh, const OpticalProperties& material, int f,
  const double w[3], double weight, const std::vector<double>& fluence,
  const std::vector<double>* irradiance, Fresnel::BoundaryRule rule, DetectorReading& reading);

/**
 * The checks of a detector, once for every surface query (LocateDetectors on
 * a mesh, the distributed read-out over the ranks' physical faces): before
 * the search, a finite position and a finite radius >= 0 (`nearest` null);
 * after it, the nearest surface point `nearest` at `distance` (mm) at most
 * `tolerance` (mm) away. Throws translucency::Error starting with `name`.
 */
void CheckDetector(const Detector& detector, const std::string& name,
  const std::array<double, 3>* nearest = nullptr, double distance = 0.0, double tolerance = 0.0);

/// The footprints of the detectors (the checks and errors of ReadDetectors).
std::vector<DetectorFootprint> LocateDetectors(
  const TetMesh& mesh, const std::vector<Detector>& detectors);

/**
 * Read detectors from a solution. `fluence` and `irradiance` (may be null:
 * q = 0) have 3 values per mesh point; the readings are linear in them (a
 * complex solution can be read as its real and imaginary parts). A point
 * detector (Radius 0) reads the P1 interpolant at the closest surface
 * point; a fibre reads the area-weighted mean over the surface within
 * Radius of that point (triangles facing the same way as the detector's,
 * each split into sub-triangles no larger than Radius / 4, a sub-triangle
 * counted if its centroid is inside the disc). Throws translucency::Error
 * naming the detector when it is more than SurfaceTolerance() from the
 * surface, or its position or radius is invalid. `rule` as in
 * ComputePowerBalance (the exitance's A and Fdr).
 */
std::vector<DetectorReading> ReadDetectors(const TetMesh& mesh,
  const OpticalProperties& material, const std::vector<Detector>& detectors,
  const std::vector<double>& fluence, const std::vector<double>* irradiance,
  Fresnel::BoundaryRule rule = Fresnel::BoundaryRule::Fit);

/**
 * ReadDetectors with the footprints located once (LocateDetectors), for
 * many solutions on the same mesh (the time gates): the same readings. The
 * material is not validated again (the caller did); the arrays are checked.
 */
std::vector<DetectorReading> ReadDetectorFootprints(const TetMesh& mesh,
  const OpticalProperties& material, const std::vector<DetectorFootprint>& footprints,
  const std::vector<double>& fluence, const std::vector<double>* irradiance,
  Fresnel::BoundaryRule rule = Fresnel::BoundaryRule::Fit);

} // namespace translucency
