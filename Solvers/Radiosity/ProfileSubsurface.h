/**
 * @file ProfileSubsurface.h
 * @brief The paper's S operator: a 1D scattering profile over the shortest
 * optical path inside the object (TranslucentRadiosity, Sec. 4, 5.2,
 * eq. 8 and the heterogeneity heuristic eq. 16).
 */
#pragma once

#include "SubsurfaceOperator.h"

#include <vector>

namespace translucency
{

/**
 * Jensen et al. 2001 dipole diffuse reflectance profile R_d(r) (1/mm^2):
 * alpha'/(4 pi) [ z_r (s_tr d_r + 1) e^{-s_tr d_r} / d_r^3 +
 *                 z_v (s_tr d_v + 1) e^{-s_tr d_v} / d_v^3 ],
 * sigma_t' = mu_a + sigma_s', alpha' = sigma_s'/sigma_t',
 * s_tr = sqrt(3 mu_a sigma_t'), z_r = 1/sigma_t', z_v = z_r (1 + 4A/3),
 * d_{r,v} = sqrt(r^2 + z_{r,v}^2). Its integral over the plane is
 * DipoleTotalReflectance().
 */
double DipoleProfile(double r, double muA, double sigmaS, double eta);

/**
 * S as a sparse matrix built from the dipole profile (the paper's method):
 *  - a uniform voxel grid over the object's bounding box (voxel size h; a
 *    voxel is inside if its centre lies in a tet, found with TetLocator), each
 *    voxel carrying the material of that tet;
 *  - every patch mapped to the nearest inside voxel of its centroid;
 *  - Dijkstra on the 26-connected graph of inside voxels from each source
 *    voxel (edge lengths h, h sqrt 2, h sqrt 3), stopped at max_d (paper
 *    Sec. 5.2, third strategy), cached per source voxel (several patches
 *    share one), with the length travelled in each material along the path;
 *  - optical distance r_ij = max(voxel path length, |c_i - c_j|) (the path
 *    cannot be shorter than the straight line); same voxel: |c_i - c_j|;
 *  - S_ji = int_{A_i} R(r(x, c_j)) dA_x (paper eq. 8 with the exit
 *    point fixed at the centroid, Sec. 5.2), evaluated with 100 sub-triangle
 *    samples of patch i when |c_i - c_j| < 3 sqrt(A_i) (Euclidean distances:
 *    the pair is close and the path straight) and with the centroid
 *    otherwise. R_d is the flux leaving the half-space (its boundary
 *    condition already holds the internal reflection), i.e. an exitance per
 *    transmitted power, so no exit Fresnel factor is applied (Jensen's
 *    BSSRDF F_t(in) R_d F_t(out)/pi would apply T_u once more);
 *  - R for a path through several materials by eq. 16, generalised to N
 *    materials: (sum_m R_m(0) r_m / r) prod_m R_m(r_m) / R_m(0), r_m = f_m r
 *    with f_m the fraction of the voxel path in material m. One material
 *    gives R(r).
 * A material change (Setup() again on the same mesh) reuses the cached
 * distances and fractions and only re-evaluates the profile.
 */
class ProfileSubsurface : public SubsurfaceOperator
{
public:
  std::string GetName() const override { return "profile"; }
  void Setup(const RadiosityScene& scene, int object) override;
  void Apply(const std::vector<double>& q, std::vector<double>& radiosity) override;
  std::size_t GetMemoryBytes() const override;

  /// Voxel size h (mm); 0 = automatic: the largest side of the bounding box / 40.
  void SetVoxelSize(double h) { VoxelSize_ = h; }
  /// Cut-off max_d (mm); 0 = automatic: the smallest r > h at which every
  /// material's profile is below 1e-4 of its value at r = h (capped at the
  /// bounding-box diagonal).
  void SetMaxDistance(double d) { MaxDistance_ = d; }
  double GetMaxDistance() const { return UsedMaxDistance_; }
  double GetVoxelSize() const { return UsedVoxelSize_; }
  int GetNumberOfInsideVoxels() const { return NumberOfInside_; }
  /// Stored entries of S.
  long long GetNumberOfNonZeros() const { return static_cast<long long>(Columns_.size()); }

private:
  /// Rebuild the matrix values from the cached geometry (material change).
  void Evaluate(const RadiosityScene& scene, int object);

  const TetMesh* Mesh_ = nullptr;
  double VoxelSize_ = 0.0;
  double MaxDistance_ = 0.0;
  double UsedVoxelSize_ = 0.0;
  double UsedMaxDistance_ = 0.0;
  int NumberOfInside_ = 0;
  int NumberOfMaterials_ = 0;
  std::vector<int> TetMaterial_;   ///< material id per tet
  std::vector<int> MaterialTet_;   ///< one representative tet per material
  // S in CSR by exit patch j (rows): entries over entry patches i.
  std::vector<int> RowOffsets_;
  std::vector<int> Columns_;
  std::vector<float> Distances_;   ///< optical distance r_ij (mm)
  std::vector<unsigned char> Near_; ///< sampled (1) or centroid (0)
  /// Material fractions f_m per entry (NumberOfMaterials_ each; empty if one material).
  std::vector<float> Fractions_;
  std::vector<double> Values_;     ///< 3 per entry (R, G, B)
};

} // namespace translucency
