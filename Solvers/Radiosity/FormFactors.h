/**
 * @file FormFactors.h
 * @brief Sparse form-factor matrix of a radiosity scene by Monte Carlo ray
 * casting with visibility (TranslucentRadiosity, Sec. 5.1 computes the
 * same matrix with hemicubes; we cast rays through our BVH instead).
 */
#pragma once

#include "ResourceLimits.h"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace translucency
{

class RadiosityScene;

/**
 * F in CSR form: row i holds F_ij, the fraction of the energy leaving patch
 * i (a Lambertian emitter) that arrives directly at the front of patch j, so
 * that the irradiance of patch i from the radiosities B is
 * sum_j F_ij B_j (classical radiosity, paper eq. 1; this is the F of eq. 14).
 */
struct FormFactorMatrix
{
  int NumberOfPatches = 0;
  std::vector<int> RowOffsets; ///< size NumberOfPatches + 1
  std::vector<int> Columns;    ///< sorted within each row
  std::vector<float> Values;

  /// y = F x for 3 values per patch (R, G, B).
  void Multiply(const std::vector<double>& x, std::vector<double>& y) const;
  /// Sum of row i.
  double RowSum(int i) const;
  /// F_ij (0 if not stored).
  double Get(int i, int j) const;
  /// Bytes held by the three arrays.
  std::size_t MemoryBytes() const
  {
    return RowOffsets.size() * sizeof(int) + Columns.size() * sizeof(int) +
      Values.size() * sizeof(float);
  }
};

/**
 * Computes FormFactorMatrix by casting, from every patch i, N rays from
 * uniformly distributed points of the patch in cosine-weighted directions
 * over its front hemisphere (stratified: a sqrt(N) x sqrt(N) grid of jittered
 * cells in the unit square mapped to the disk, concentric map, then lifted;
 * the pattern is rotated about the normal by a random angle per patch so
 * that neighbouring patches do not share directions).
 * F_ij = (number of rays whose first hit is the front of patch j) / N: an
 * unbiased estimate of the patch-to-patch form factor
 * (1/A_i) int_Ai int_Aj cos cos V / (pi r^2), with standard error
 * sqrt(F (1 - F) / N). A ray that hits the back of a patch or escapes
 * carries its energy out of the scene.
 *
 * Sparse and thresholded: only patches hit are stored; entries below
 * Threshold are then dropped (their energy is lost; the dropped fraction is
 * reported). Memory is reported by GetMemoryBytes().
 *
 * Why our BVH (Solvers/RayCaster) and not a VTK locator (vtkOBBTree,
 * vtkCellLocator) or Embree: the core must stay VTK-free, the BVH is
 * thread-safe for concurrent const queries from an OpenMP loop (the VTK
 * locators' IntersectWithLine keeps per-object scratch state), it is already
 * tested against brute force, and it adds no dependency.
 *
 * Random numbers: a counter-based hash of (seed, patch, ray), so the result
 * is the same for any number of OpenMP threads.
 */
class FormFactorComputer
{
public:
  /// Rays per patch (>= 1). Default 256.
  void SetRaysPerPatch(int n) { RaysPerPatch_ = n; }
  int GetRaysPerPatch() const { return RaysPerPatch_; }
  /// Entries F_ij < threshold are dropped (>= 0). Default 0 (keep every hit).
  void SetThreshold(double t) { Threshold_ = t; }
  double GetThreshold() const { return Threshold_; }
  /**
   * Budget of rays per Compute (patches x rays per patch), default 2^33
   * (~8.6e9 rays, minutes on a workstation): above it Compute throws an Error
   * naming the product and this override (the time guard; memory is bounded
   * by the memory limit below).
   */
  void SetMaxRays(double rays) { MaxRays_ = rays; }
  double GetMaxRays() const { return MaxRays_; }
  /// Bytes F may take at most (patches x min(rays, patches) entries, 12 bytes
  /// each); default GetDefaultMemoryLimit() (8 GiB).
  void SetMemoryLimit(std::size_t bytes) { MemoryLimit_ = bytes; }
  std::size_t GetMemoryLimit() const { return MemoryLimit_; }
  /// Seed of the ray directions. Default 1.
  void SetSeed(std::uint64_t seed) { Seed_ = seed; }
  /// Called with the fraction done; returning false aborts (Compute returns false).
  void SetProgressCallback(std::function<bool(double)> callback) { Progress_ = std::move(callback); }

  /**
   * Compute F for the built scene. OpenMP-parallel over patches. Throws
   * translucency::Error on invalid settings. Returns false if aborted.
   */
  bool Compute(const RadiosityScene& scene, FormFactorMatrix& F);

  ///@{
  /// Statistics of the last Compute(): milliseconds, rays cast, stored
  /// entries, the energy fraction dropped by the threshold (sum of dropped
  /// F_ij over all rows / number of patches) and the bytes of F.
  double GetMilliseconds() const { return Milliseconds_; }
  long long GetNumberOfRays() const { return NumberOfRays_; }
  long long GetNumberOfNonZeros() const { return NumberOfNonZeros_; }
  double GetDroppedFraction() const { return DroppedFraction_; }
  std::size_t GetMemoryBytes() const { return MemoryBytes_; }
  ///@}

private:
  int RaysPerPatch_ = 256;
  double MaxRays_ = 8589934592.0;
  std::size_t MemoryLimit_ = GetDefaultMemoryLimit();
  double Threshold_ = 0.0;
  std::uint64_t Seed_ = 1;
  std::function<bool(double)> Progress_;
  double Milliseconds_ = 0.0;
  long long NumberOfRays_ = 0;
  long long NumberOfNonZeros_ = 0;
  double DroppedFraction_ = 0.0;
  std::size_t MemoryBytes_ = 0;
};

} // namespace translucency
