#include "OpticalProperties.h"

#include "Error.h"
#include "Strings.h"

#include <algorithm>
#include <cctype>
#include <climits>
#include <cmath>
#include <cstring>
#include <sstream>

namespace translucency
{

namespace
{

const char* const ChannelNames[NumberOfChannels] = { "R", "G", "B" };

} // namespace

OpticalProperties OpticalProperties::Uniform(int numTets,
  const double muA[3],
  const double sigmaS[3],
  double eta)
{
  if (numTets < 0)
  {
    throw Error("OpticalProperties::Uniform: negative number of tets " + std::to_string(numTets));
  }
  OpticalProperties p;
  const size_t n = static_cast<size_t>(numTets);
  p.AbsorptionCoefficient.resize(3 * n);
  p.ReducedScatteringCoefficient.resize(3 * n);
  p.RefractiveIndex.assign(n, eta);
  for (size_t t = 0; t < n; ++t)
  {
    for (int c = 0; c < 3; ++c)
    {
      p.AbsorptionCoefficient[3 * t + c] = muA[c];
      p.ReducedScatteringCoefficient[3 * t + c] = sigmaS[c];
    }
  }
  return p;
}

namespace
{
bool SameBits(const std::vector<double>& a, const std::vector<double>& b)
{
  return a.size() == b.size() &&
    (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}
}

bool OpticalProperties::SameCoefficients(const OpticalProperties& other) const
{
  return SameBits(AbsorptionCoefficient, other.AbsorptionCoefficient) &&
    SameBits(ReducedScatteringCoefficient, other.ReducedScatteringCoefficient) &&
    SameBits(RefractiveIndex, other.RefractiveIndex);
}

void OpticalProperties::ValidateTets(int numTets, const std::vector<int>& tets) const
{
  const std::size_t n = static_cast<std::size_t>(std::max(numTets, 0));
  bool valid = numTets >= 0 && AbsorptionCoefficient.size() == 3 * n &&
    ReducedScatteringCoefficient.size() == 3 * n && RefractiveIndex.size() == n &&
    (Anisotropy.empty() || Anisotropy.size() == 3 * n);
  for (std::size_t k = 0; valid && k < tets.size(); ++k)
  {
    const int t = tets[k];
    if (t < 0 || static_cast<std::size_t>(t) >= n)
    {
      Validate(numTets);
      throw Error("OpticalProperties::ValidateTets: changed tet " + std::to_string(t) +
        " is not one of the " + std::to_string(n) + " tets");
    }
    const std::size_t i = static_cast<std::size_t>(t);
    for (int c = 0; c < 3; ++c)
    {
      const double a = AbsorptionCoefficient[3 * i + c], s = ReducedScatteringCoefficient[3 * i + c];
      valid = valid && std::isfinite(a) && a >= 0.0 && std::isfinite(s) && s >= 0.0 && a + s > 0.0;
      if (!Anisotropy.empty())
      {
        const double g = Anisotropy[3 * i + c];
        valid = valid && std::isfinite(g) && g > -1.0 && g < 1.0;
      }
    }
    valid = valid && std::isfinite(RefractiveIndex[i]) && RefractiveIndex[i] > 0.0;
  }
  if (!valid)
  {
    Validate(numTets); // names the array, tet, channel and value (throws)
  }
}

void OpticalProperties::Validate(int numTets) const
{
  if (numTets < 0)
  {
    throw Error("OpticalProperties::Validate: negative number of tets " + std::to_string(numTets));
  }
  const size_t n = static_cast<size_t>(numTets);
  auto checkSize = [&](const std::vector<double>& a, const char* name, size_t perTet)
  {
    if (a.size() != perTet * n)
    {
      std::ostringstream os;
      os << name << " has " << a.size() << " values but the mesh has " << n << " tets ("
         << perTet * n << " values expected, " << perTet << " per tet)";
      throw Error(os.str());
    }
  };
  checkSize(AbsorptionCoefficient, "AbsorptionCoefficient", 3);
  checkSize(ReducedScatteringCoefficient, "ReducedScatteringCoefficient", 3);
  checkSize(RefractiveIndex, "RefractiveIndex", 1);

  // One parallel pass (the arrays can hold millions of values); the lowest
  // failing index of each check is reported.
  const long long numValues = static_cast<long long>(3 * n);
  const double* muA = AbsorptionCoefficient.data();
  const double* sigmaS = ReducedScatteringCoefficient.data();
  long long badA = LLONG_MAX, badS = LLONG_MAX, badSum = LLONG_MAX;
#pragma omp parallel for reduction(min : badA, badS, badSum) schedule(static)
  for (long long k = 0; k < numValues; ++k)
  {
    const double a = muA[k], s = sigmaS[k];
    if (!(std::isfinite(a) && a >= 0.0))
    {
      badA = std::min(badA, k);
    }
    if (!(std::isfinite(s) && s >= 0.0))
    {
      badS = std::min(badS, k);
    }
    if (!(a + s > 0.0))
    {
      badSum = std::min(badSum, k);
    }
  }
  const long long numTetsLL = static_cast<long long>(n);
  const double* eta = RefractiveIndex.data();
  long long badEta = LLONG_MAX;
#pragma omp parallel for reduction(min : badEta) schedule(static)
  for (long long t = 0; t < numTetsLL; ++t)
  {
    if (!(std::isfinite(eta[t]) && eta[t] > 0.0))
    {
      badEta = std::min(badEta, t);
    }
  }

  auto report = [](const char* name, long long k, double v)
  {
    std::ostringstream os;
    os << name << " of tet " << k / 3 << ", channel " << ChannelNames[k % 3] << " is " << v
       << " 1/mm: must be finite and >= 0";
    throw Error(os.str());
  };
  if (badA != LLONG_MAX)
  {
    report("AbsorptionCoefficient", badA, muA[badA]);
  }
  if (badS != LLONG_MAX)
  {
    report("ReducedScatteringCoefficient", badS, sigmaS[badS]);
  }
  if (badEta != LLONG_MAX)
  {
    std::ostringstream os;
    os << "RefractiveIndex of tet " << badEta << " is " << eta[badEta]
       << ": must be finite and > 0";
    throw Error(os.str());
  }
  if (badSum != LLONG_MAX)
  {
    // Both are >= 0 here, so both are zero.
    std::ostringstream os;
    os << "tet " << badSum / 3 << ", channel " << ChannelNames[badSum % 3]
       << " has AbsorptionCoefficient + ReducedScatteringCoefficient = 0 1/mm: the "
          "diffusion coefficient kappa = 1/(3 (mu_a + sigma_s')) would be infinite";
    throw Error(os.str());
  }
  if (!Anisotropy.empty())
  {
    checkSize(Anisotropy, "Anisotropy", 3);
    for (size_t k = 0; k < Anisotropy.size(); ++k)
    {
      if (!(std::isfinite(Anisotropy[k]) && Anisotropy[k] > -1.0 && Anisotropy[k] < 1.0))
      {
        std::ostringstream os;
        os << "Anisotropy of tet " << k / 3 << ", channel " << ChannelNames[k % 3] << " is "
           << Anisotropy[k] << ": must be finite and in (-1, 1)";
        throw Error(os.str());
      }
    }
  }
}

const std::vector<MaterialPreset>& GetMaterialPresets()
{
  // Jensen, Marschner, Levoy, Hanrahan 2001, "A Practical Model for
  // Subsurface Light Transport", Fig. 5 table: sigma_s' and sigma_a in 1/mm
  // (R, G, B), eta = 1.3 for all.
  static const std::vector<MaterialPreset> presets = {
    { "apple", { 2.29, 2.39, 1.97 }, { 0.0030, 0.0034, 0.046 }, 1.3 },
    { "chicken1", { 0.15, 0.21, 0.38 }, { 0.015, 0.077, 0.19 }, 1.3 },
    { "chicken2", { 0.19, 0.25, 0.32 }, { 0.018, 0.088, 0.20 }, 1.3 },
    { "cream", { 7.38, 5.47, 3.15 }, { 0.0002, 0.0028, 0.0163 }, 1.3 },
    { "ketchup", { 0.18, 0.07, 0.03 }, { 0.061, 0.97, 1.45 }, 1.3 },
    { "marble", { 2.19, 2.62, 3.00 }, { 0.0021, 0.0041, 0.0071 }, 1.3 },
    { "potato", { 0.68, 0.70, 0.55 }, { 0.0024, 0.0090, 0.12 }, 1.3 },
    { "skimmilk", { 0.70, 1.22, 1.90 }, { 0.0014, 0.0025, 0.0142 }, 1.3 },
    { "skin1", { 0.74, 0.88, 1.01 }, { 0.032, 0.17, 0.48 }, 1.3 },
    { "skin2", { 1.09, 1.59, 1.79 }, { 0.013, 0.070, 0.145 }, 1.3 },
    { "spectralon", { 11.6, 20.4, 14.9 }, { 0.00, 0.00, 0.00 }, 1.3 },
    { "wholemilk", { 2.55, 3.21, 3.77 }, { 0.0011, 0.0024, 0.014 }, 1.3 },
  };
  return presets;
}

const MaterialPreset& FindMaterialPreset(const std::string& name)
{
  const std::string key = ToLower(name);
  const std::vector<MaterialPreset>& presets = GetMaterialPresets();
  for (const MaterialPreset& p : presets)
  {
    if (p.Name == key)
    {
      return p;
    }
  }
  std::ostringstream os;
  os << "unknown material preset '" << name << "'; known presets:";
  for (size_t k = 0; k < presets.size(); ++k)
  {
    os << (k == 0 ? " " : ", ") << presets[k].Name;
  }
  throw Error(os.str());
}

} // namespace translucency
