#include "ModelRange.h"

#include "OpticalProperties.h"
#include "TetMesh.h"

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
  // The albedo over the volume.
  double total = 0.0, lowAlbedo = 0.0;
  for (int t = 0; t < numTets; ++t)
  {
    const double volume = mesh.GetTetVolume(t);
    total += volume;
    bool low = false;
    for (int c = 0; c < 3; ++c)
    {
      const std::size_t k = 3 * static_cast<std::size_t>(t) + c;
      const double mut =
        material.AbsorptionCoefficient[k] + material.ReducedScatteringCoefficient[k];
      const double albedo = mut > 0.0 ? material.ReducedScatteringCoefficient[k] / mut : 1.0;
      if (albedo < report.MinimumAlbedo)
      {
        report.MinimumAlbedo = albedo;
        report.MinimumAlbedoTet = t;
        report.MinimumAlbedoChannel = c;
      }
      low = low || albedo < DiffusionMinimumAlbedo;
    }
    lowAlbedo += low ? volume : 0.0;
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
