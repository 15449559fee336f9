#include "ModelRange.h"

#include "OpticalProperties.h"
#include "TetMesh.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace translucency
{

namespace
{
const char* ChannelName(int c)
{
  static const char* names[3] = { "R", "G", "B" };
  return names[c];
}
}

std::vector<double> TetSizes(const TetMesh& mesh)
{
  const int numTets = mesh.GetNumberOfTets();
  std::vector<double> sizes(static_cast<std::size_t>(numTets));
  // A regular tet of edge h has volume h^3 / (6 sqrt 2).
  const double factor = 6.0 * std::sqrt(2.0);
#pragma omp parallel for schedule(static)
  for (int t = 0; t < numTets; ++t)
  {
    sizes[static_cast<std::size_t>(t)] = std::cbrt(factor * mesh.GetTetVolume(t));
  }
  return sizes;
}

ModelRangeReport CheckModelRange(
  const TetMesh& mesh, const OpticalProperties& material, const std::vector<double>* sizes)
{
  std::vector<double> own;
  if (!sizes)
  {
    own = TetSizes(mesh);
    sizes = &own;
  }
  ModelRangeReport report;
  const int numTets = mesh.GetNumberOfTets();
  // The albedo over the volume: fixed chunks in parallel, combined in order
  // (the same sums and the same lowest tet at any thread count; a paint at
  // 1M tets runs this again).
  constexpr int chunk = 16384;
  const int numChunks = (numTets + chunk - 1) / chunk;
  struct Part
  {
    double Total = 0.0, Low = 0.0, MinimumAlbedo = 1.0;
    int Tet = -1, Channel = -1;
  };
  std::vector<Part> parts(static_cast<std::size_t>(numChunks));
  const double* muA = material.AbsorptionCoefficient.data();
  const double* sigmaS = material.ReducedScatteringCoefficient.data();
#pragma omp parallel for schedule(static)
  for (int k = 0; k < numChunks; ++k)
  {
    Part& part = parts[static_cast<std::size_t>(k)];
    part.MinimumAlbedo = report.MinimumAlbedo;
    const int end = std::min(numTets, (k + 1) * chunk);
    for (int t = k * chunk; t < end; ++t)
    {
      const double volume = mesh.GetTetVolume(t);
      part.Total += volume;
      bool low = false;
      for (int c = 0; c < 3; ++c)
      {
        const std::size_t i = 3 * static_cast<std::size_t>(t) + c;
        const double mut = muA[i] + sigmaS[i];
        const double albedo = mut > 0.0 ? sigmaS[i] / mut : 1.0;
        if (albedo < part.MinimumAlbedo)
        {
          part.MinimumAlbedo = albedo;
          part.Tet = t;
          part.Channel = c;
        }
        low = low || albedo < DiffusionMinimumAlbedo;
      }
      part.Low += low ? volume : 0.0;
    }
  }
  double total = 0.0, lowAlbedo = 0.0;
  for (const Part& part : parts)
  {
    total += part.Total;
    lowAlbedo += part.Low;
    if (part.MinimumAlbedo < report.MinimumAlbedo)
    {
      report.MinimumAlbedo = part.MinimumAlbedo;
      report.MinimumAlbedoTet = part.Tet;
      report.MinimumAlbedoChannel = part.Channel;
    }
  }
  report.LowAlbedoVolumeFraction = total > 0.0 ? lowAlbedo / total : 0.0;
  // The tet size against l* where it matters: the tets under the surface,
  // weighted by their boundary area (inside, the fluence varies on the much
  // longer diffusion length 1/mu_eff, and graded meshes are coarse there).
  const std::vector<double>& areas = mesh.GetBoundaryTriangleAreas();
  const std::vector<int>& owners = mesh.GetBoundaryTriangleTets();
  double area = 0.0, coarse = 0.0;
  for (std::size_t f = 0; f < owners.size(); ++f)
  {
    const int t = owners[f];
    area += areas[f];
    bool tooCoarse = false;
    for (int c = 0; c < 3; ++c)
    {
      const std::size_t k = 3 * static_cast<std::size_t>(t) + c;
      const double mut =
        material.AbsorptionCoefficient[k] + material.ReducedScatteringCoefficient[k];
      const double ratio = (*sizes)[static_cast<std::size_t>(t)] * mut; // size / l*
      if (ratio > report.LargestSizeInMeanFreePaths)
      {
        report.LargestSizeInMeanFreePaths = ratio;
        report.LargestSizeTet = t;
        report.LargestSizeChannel = c;
      }
      tooCoarse = tooCoarse || ratio > DiffusionMaximumTetSizeInMeanFreePaths;
    }
    coarse += tooCoarse ? areas[f] : 0.0;
  }
  report.CoarseAreaFraction = area > 0.0 ? coarse / area : 0.0;
  return report;
}

std::string ModelRangeReport::AlbedoMessage() const
{
  std::ostringstream text;
  text.precision(3);
  if (this->LowAlbedoVolumeFraction > DiffusionToleratedVolumeFraction)
  {
    text << "the diffusion model is out of its range in " << 100.0 * this->LowAlbedoVolumeFraction
         << " % of the volume: transport albedo mu_s'/(mu_a + mu_s') below "
         << DiffusionMinimumAlbedo << " (lowest " << this->MinimumAlbedo << " in tet "
         << this->MinimumAlbedoTet << ", channel " << ChannelName(this->MinimumAlbedoChannel)
         << "); expect errors of tens of per cent there: check with the montecarlo solver.";
  }
  return text.str();
}

std::string ModelRangeReport::ResolutionMessage() const
{
  std::ostringstream text;
  text.precision(3);
  if (this->CoarseAreaFraction > DiffusionToleratedVolumeFraction)
  {
    text << "The mesh is coarse for this material under " << 100.0 * this->CoarseAreaFraction
         << " % of the surface: tets larger than " << DiffusionMaximumTetSizeInMeanFreePaths
         << " transport mean free paths 1/(mu_a + mu_s') (largest "
         << this->LargestSizeInMeanFreePaths << " in tet " << this->LargestSizeTet
         << ", channel " << ChannelName(this->LargestSizeChannel)
         << "); the lit boundary layer is not resolved: use more tets.";
  }
  return text.str();
}

std::string ModelRangeReport::Message() const
{
  const std::string albedo = this->AlbedoMessage(), resolution = this->ResolutionMessage();
  return albedo.empty() || resolution.empty() ? albedo + resolution : albedo + " " + resolution;
}

} // namespace translucency
