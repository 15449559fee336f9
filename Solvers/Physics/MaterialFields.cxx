#include "MaterialFields.h"

#include "Error.h"
#include "OpticalProperties.h"

#include <cmath>
#include <cstdlib>
#include <map>
#include <sstream>

namespace translucency
{

namespace
{
constexpr double Pi = 3.141592653589793;
} // namespace

//------------------------------------------------------------------------------
MaterialCoefficients MaterialCoefficients::FromPreset(const std::string& name)
{
  const MaterialPreset& p = FindMaterialPreset(name);
  MaterialCoefficients m;
  for (int c = 0; c < 3; ++c)
  {
    m.Absorption[c] = p.Absorption[c];
    m.ReducedScattering[c] = p.ReducedScattering[c];
  }
  m.RefractiveIndex = p.RefractiveIndex;
  return m;
}

//------------------------------------------------------------------------------
void MaterialCoefficients::Validate() const
{
  // The core's rules on a one-tet material (the message names the value).
  OpticalProperties::Uniform(1, Absorption.data(), ReducedScattering.data(), RefractiveIndex)
    .Validate(1);
}

//------------------------------------------------------------------------------
MaterialCoefficients MaterialTable::Resolve(const std::string& reference) const
{
  for (const MaterialTableEntry& m : Entries)
  {
    if (!m.Name.empty() && m.Name == reference)
    {
      return m.Coefficients;
    }
  }
  char* end = nullptr;
  const long id = std::strtol(reference.c_str(), &end, 10);
  if (!reference.empty() && end && *end == '\0')
  {
    for (const MaterialTableEntry& m : Entries)
    {
      if (m.Id == id)
      {
        return m.Coefficients;
      }
    }
  }
  try
  {
    return MaterialCoefficients::FromPreset(reference);
  }
  catch (const std::exception& e)
  {
    throw Error("unknown material '" + reference + "': " +
      (Entries.empty() ? std::string("no material table is set and ")
                       : std::string("not a name or id of the material table and ")) +
      e.what());
  }
}

//------------------------------------------------------------------------------
MaterialField MaterialField::Uniform(int numTets, const MaterialCoefficients& material)
{
  MaterialField field;
  field.Palette.push_back(material);
  field.Which.assign(static_cast<size_t>(numTets), 0);
  return field;
}

//------------------------------------------------------------------------------
void MaterialField::Scale(double factor)
{
  for (MaterialCoefficients& m : Palette)
  {
    for (int c = 0; c < 3; ++c)
    {
      m.Absorption[c] *= factor;
      m.ReducedScattering[c] *= factor;
    }
  }
}

//------------------------------------------------------------------------------
void MaterialField::Validate() const
{
  for (const MaterialCoefficients& m : Palette)
  {
    m.Validate();
  }
}

//------------------------------------------------------------------------------
MaterialField MaterialsFromIds(const std::vector<double>& ids, const MaterialTable& table,
  const std::function<std::string(int tet, double id)>& describe)
{
  MaterialField field;
  std::map<long long, int> slot; // table id -> palette index
  for (const MaterialTableEntry& m : table.Entries)
  {
    if (m.Id >= 0)
    {
      slot[m.Id] = static_cast<int>(field.Palette.size());
      field.Palette.push_back(m.Coefficients);
    }
  }
  field.Which.resize(ids.size());
  for (size_t i = 0; i < ids.size(); ++i)
  {
    const double v = ids[i];
    const double r = std::round(v);
    auto it = (v == r && std::abs(r) < 9e18) ? slot.find(static_cast<long long>(r)) : slot.end();
    if (it == slot.end())
    {
      throw Error(describe(static_cast<int>(i), v) + ", which " +
        (v == r ? "is not an id of" : "is not an integer id of") + " the material table '" +
        table.FileName + "'");
    }
    field.Which[i] = it->second;
  }
  return field;
}

//------------------------------------------------------------------------------
MaterialField SphericalInclusion(const std::vector<Point3>& centroids, const Point3& center,
  double radius, const MaterialCoefficients& inside, const MaterialCoefficients& outside)
{
  MaterialField field;
  field.Palette = { outside, inside };
  field.Which.resize(centroids.size());
  const double r2 = radius * radius;
  for (size_t i = 0; i < centroids.size(); ++i)
  {
    const Point3& c = centroids[i];
    const double d2 = (c[0] - center[0]) * (c[0] - center[0]) +
      (c[1] - center[1]) * (c[1] - center[1]) + (c[2] - center[2]) * (c[2] - center[2]);
    field.Which[i] = d2 <= r2 ? 1 : 0;
  }
  return field;
}

//------------------------------------------------------------------------------
void ValidateLayerThicknesses(const std::vector<double>& thicknesses)
{
  for (double t : thicknesses)
  {
    if (!(t >= 0.0) || !std::isfinite(t))
    {
      std::ostringstream os;
      os << "layer thickness " << t << " mm must be finite and >= 0";
      throw Error(os.str());
    }
  }
}

//------------------------------------------------------------------------------
MaterialField Layers(const std::vector<double>& depths, const std::vector<double>& thicknesses,
  const std::vector<MaterialCoefficients>& materials)
{
  if (materials.empty())
  {
    throw Error("the layered mode needs at least one layer (AddLayer)");
  }
  if (thicknesses.size() != materials.size())
  {
    throw Error("the layered mode needs one thickness per layer material");
  }
  ValidateLayerThicknesses(thicknesses);
  MaterialField field;
  field.Palette = materials;
  field.Which.resize(depths.size());
  const int last = static_cast<int>(thicknesses.size()) - 1;
  for (size_t i = 0; i < depths.size(); ++i)
  {
    int k = 0;
    double bottom = thicknesses[0];
    while (k < last && depths[i] >= bottom)
    {
      ++k;
      bottom += thicknesses[k];
    }
    field.Which[i] = k;
  }
  return field;
}

//------------------------------------------------------------------------------
Point3 VeinsField::Phase(int seed)
{
  const double golden[3] = { 0.7548776662466927, 0.5698402909980532, 0.4301597090019468 };
  Point3 phase;
  for (int a = 0; a < 3; ++a)
  {
    const double p = static_cast<double>(seed) * golden[a];
    phase[a] = p - std::floor(p);
  }
  return phase;
}

//------------------------------------------------------------------------------
bool VeinsField::Evaluate(
  const std::vector<Point3>& centroids, const Noise& noise, MaterialField& field) const
{
  Point3 d = Direction_;
  const double length = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  if (length != 0.0)
  {
    for (double& v : d)
    {
      v /= length;
    }
  }
  if (!(length > 0.0) || !std::isfinite(d[0] + d[1] + d[2]))
  {
    throw Error("the vein direction must be a non-zero vector");
  }
  if (!(Frequency_ > 0.0) || !std::isfinite(Frequency_))
  {
    std::ostringstream os;
    os << "the vein frequency must be > 0 (1/mm), not " << Frequency_;
    throw Error(os.str());
  }
  const size_t n = centroids.size();
  MaterialField result;
  result.Palette.resize(n);
  result.Which.resize(n);
  for (size_t i = 0; i < n; ++i)
  {
    if (i % 10000 == 0 && Progress_ &&
      !Progress_(static_cast<double>(i) / static_cast<double>(n)))
    {
      return false;
    }
    const Point3& x = centroids[i];
    double turbulence = 0.0;
    if (Turbulence_ > 0.0)
    {
      double scale = 1.0;
      for (int o = 0; o < Octaves_; ++o)
      {
        turbulence += std::abs(noise(x, scale * Frequency_)) / scale;
        scale *= 2.0;
      }
    }
    const double dx = d[0] * x[0] + d[1] * x[1] + d[2] * x[2];
    const double s = std::sin(2.0 * Pi * (Frequency_ * dx + Turbulence_ * turbulence));
    const double w = std::pow(1.0 - std::abs(s), Sharpness_);
    MaterialCoefficients& m = result.Palette[i];
    for (int c = 0; c < 3; ++c)
    {
      m.Absorption[c] = (1.0 - w) * Base_.Absorption[c] + w * Vein_.Absorption[c];
      m.ReducedScattering[c] =
        (1.0 - w) * Base_.ReducedScattering[c] + w * Vein_.ReducedScattering[c];
    }
    m.RefractiveIndex = (1.0 - w) * Base_.RefractiveIndex + w * Vein_.RefractiveIndex;
    result.Which[i] = static_cast<int>(i);
  }
  field = std::move(result);
  return true;
}

//------------------------------------------------------------------------------
void CheckProbedValues(
  int tet, const Point3& centroid, const std::string& arrayName, const std::array<double, 3>& values)
{
  for (int c = 0; c < 3; ++c)
  {
    if (!(values[c] >= 0.0) || !std::isfinite(values[c]))
    {
      std::ostringstream os;
      os.precision(17);
      os << "tet " << tet << " gets the value " << values[c] << " (component " << c
         << ") from the volume array '" << arrayName << "' at its centroid (" << centroid[0]
         << ", " << centroid[1] << ", " << centroid[2] << "); it must be finite and >= 0";
      throw Error(os.str());
    }
  }
}

} // namespace translucency
