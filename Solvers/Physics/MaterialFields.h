/**
 * @file MaterialFields.h
 * @brief Per-tet materials from presets, a material table, inclusions, layers
 * and marble veins: the generators behind vtkAssignScatteringCoefficients.
 *
 * Every generator takes per-tet data computed by the caller (tet centroids in
 * mm, depths below the surface in mm, material ids) and returns a
 * MaterialField: a small palette of materials and each tet's palette entry.
 * Geometry that VTK does well (the distance to the boundary, probing an
 * image) stays in the filter; the rules that turn it into coefficients live
 * here.
 */
#pragma once

#include <array>
#include <functional>
#include <string>
#include <vector>

namespace translucency
{

/// A point or a tet centroid (x, y, z), mm.
using Point3 = std::array<double, 3>;

/// The coefficients of one material.
struct MaterialCoefficients
{
  std::array<double, 3> Absorption{};        ///< mu_a (R, G, B), 1/mm
  std::array<double, 3> ReducedScattering{}; ///< sigma_s' (R, G, B), 1/mm
  double RefractiveIndex = 1.3;              ///< eta (dimensionless), default 1.3

  /// The coefficients of a measured preset (case-insensitive name; throws
  /// translucency::Error listing the known names when there is none).
  static MaterialCoefficients FromPreset(const std::string& name);

  /// Throw translucency::Error, naming the value, unless the material passes
  /// OpticalProperties::Validate (finite, mu_a >= 0, mu_a + sigma_s' > 0, eta > 0).
  void Validate() const;
};

/// One entry of a material table (JSON, read by vtkMaterialTableReader).
struct MaterialTableEntry
{
  int Id = -1;      ///< >= 0, or -1 when the entry has no id
  std::string Name; ///< "" when the entry has neither name nor preset
  MaterialCoefficients Coefficients;
};

/// A material table and the file it came from (for the messages).
struct MaterialTable
{
  std::vector<MaterialTableEntry> Entries;
  std::string FileName; ///< "" when no table file is set

  /**
   * A material reference: the name of an entry, else the id of an entry
   * written as an integer, else a measured preset name. Throws
   * translucency::Error naming the reference when it is none of these.
   */
  MaterialCoefficients Resolve(const std::string& reference) const;
};

/**
 * Per-tet materials: tet t has Palette[Which[t]]. The procedural modes
 * (veins, probed volumes) have one palette entry per tet.
 */
struct MaterialField
{
  std::vector<MaterialCoefficients> Palette;
  std::vector<int> Which; ///< palette index per tet

  /// One material on numTets tets.
  static MaterialField Uniform(int numTets, const MaterialCoefficients& material);

  /// Multiply mu_a and sigma_s' of every material by factor (eta unchanged).
  void Scale(double factor);

  /// MaterialCoefficients::Validate on every palette entry.
  void Validate() const;

  /// The material of tet t.
  const MaterialCoefficients& At(int t) const { return Palette[Which[t]]; }
};

/**
 * Materials by table id: tet t gets the entry with id ids[t].
 * @param describe writes the start of the message for a tet whose id is not
 *   an integer id of the table, e.g. "tet 3 has material id 5 (array 'R')";
 *   the core appends ", which is not an id of the material table 'FILE'".
 * Throws translucency::Error for the first such tet.
 */
MaterialField MaterialsFromIds(const std::vector<double>& ids, const MaterialTable& table,
  const std::function<std::string(int tet, double id)>& describe);

/**
 * Spherical inclusion: tets whose centroid lies in the closed ball
 * (center, radius; mm) get `inside`, the others `outside`.
 */
MaterialField SphericalInclusion(const std::vector<Point3>& centroids, const Point3& center,
  double radius, const MaterialCoefficients& inside, const MaterialCoefficients& outside);

/// Throw translucency::Error unless every layer thickness (mm) is finite and >= 0.
void ValidateLayerThicknesses(const std::vector<double>& thicknesses);

/**
 * Layers by depth: layer k (outermost first) holds the depths (mm) in
 * [sum of the thicknesses before k, that sum + thicknesses[k]); depths below
 * all layers get the last layer. materials[k] is layer k's material; throws
 * translucency::Error without layers or on a bad thickness.
 */
MaterialField Layers(const std::vector<double>& depths, const std::vector<double>& thicknesses,
  const std::vector<MaterialCoefficients>& materials);

/**
 * Marble-like veins. With the turbulence
 * t(x) = sum_{o < Octaves} 2^-o |N(x; 2^o f)| (N the noise at frequency
 * 2^o f), s(x) = sin(2 pi (f d.x + Turbulence t(x))) (f = Frequency,
 * d = unit Direction) and the vein weight w = (1 - |s|)^Sharpness, a tet with
 * centroid x gets (1 - w) Base + w Vein (each coefficient and eta blended
 * linearly).
 */
class VeinsField
{
public:
  /// N(x; f): a noise in [-1, 1] at x (mm) with frequency f (1/mm) in each
  /// axis; the filter passes vtkPerlinNoise with the phase VeinPhase(seed).
  using Noise = std::function<double(const Point3& x, double frequency)>;

  /// Base and vein materials.
  void SetMaterials(const MaterialCoefficients& base, const MaterialCoefficients& vein)
  {
    Base_ = base;
    Vein_ = vein;
  }
  /// Direction across the veins (any non-zero length), default (1, 0, 0).
  void SetDirection(const Point3& direction) { Direction_ = direction; }
  /// Frequency f of the veins (> 0), 1/mm; default 0.2.
  void SetFrequency(double frequency) { Frequency_ = frequency; }
  /// Number of noise octaves of the turbulence, default 4.
  void SetOctaves(int octaves) { Octaves_ = octaves; }
  /// Weight of the turbulence (0: straight veins), default 1.
  void SetTurbulence(double turbulence) { Turbulence_ = turbulence; }
  /// Exponent of the vein weight (larger: thinner veins), default 8.
  void SetSharpness(double sharpness) { Sharpness_ = sharpness; }
  /// Called every 10000 tets with the fraction done; return false to stop.
  void SetProgressCallback(std::function<bool(double)> callback) { Progress_ = std::move(callback); }

  /// The noise phase of a seed: the R3 low-discrepancy sequence, each in [0, 1).
  static Point3 Phase(int seed);

  /**
   * The field at the tet centroids (mm). Throws translucency::Error for a
   * zero or non-finite direction or a frequency that is not > 0. Returns
   * false (field unchanged) when the progress callback stopped it.
   */
  bool Evaluate(const std::vector<Point3>& centroids, const Noise& noise, MaterialField& field) const;

private:
  MaterialCoefficients Base_, Vein_;
  Point3 Direction_{ 1.0, 0.0, 0.0 };
  double Frequency_ = 0.2;
  int Octaves_ = 4;
  double Turbulence_ = 1.0;
  double Sharpness_ = 8.0;
  std::function<bool(double)> Progress_;
};

/**
 * Throw translucency::Error, naming the tet, its centroid (mm) and the array,
 * unless the three probed values are finite and >= 0.
 */
void CheckProbedValues(int tet, const Point3& centroid, const std::string& arrayName,
  const std::array<double, 3>& values);

} // namespace translucency
