// BoundaryRadiance: OutgoingRadiance at every boundary point, the same bits
// with one thread and with all of them.

#include "Error.h"
#include "Radiance.h"
#include "TestMeshes.h"
#include "TetMesh.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>

namespace
{

using namespace translucency;

struct RadianceCase
{
  TetMesh Mesh;
  std::vector<double> Fluence, Irradiance, Eta;
};

void MakeCase(RadianceCase& c)
{
  const translucency::testing::MeshData data = translucency::testing::CubeMesh(4, 2.0);
  c.Mesh.SetGeometry(data.Points, data.Tets);
  const int n = c.Mesh.GetNumberOfPoints();
  for (int p = 0; p < n; ++p)
  {
    const double* x = c.Mesh.GetPoint(p);
    for (int ch = 0; ch < 3; ++ch)
    {
      c.Fluence.push_back(1.0 + x[0] + 0.5 * ch + 0.25 * x[1] * x[2]);
      c.Irradiance.push_back(0.1 * (1.0 + x[2]) + 0.01 * ch);
    }
    c.Eta.push_back(1.3 + 0.05 * x[0]);
  }
}

TEST(BoundaryRadiance, EqualsOutgoingRadianceAtEachBoundaryPoint)
{
  RadianceCase c;
  MakeCase(c);
  const double view[3] = { 1.0, 7.0, 3.0 };
  for (const double* viewPoint : { static_cast<const double*>(nullptr), view })
  {
    const std::vector<double> L =
      BoundaryRadiance(c.Mesh, c.Fluence, c.Irradiance, c.Eta, viewPoint, RadianceReadout::EnergyConserving);
    const std::vector<int>& boundary = c.Mesh.GetBoundaryPoints();
    ASSERT_EQ(L.size(), 3 * boundary.size());
    int seen = 0;
    for (size_t k = 0; k < boundary.size(); ++k)
    {
      const int i = boundary[k];
      const double* nrm = &c.Mesh.GetPointNormals()[3 * i];
      double cosOut = 1.0;
      if (viewPoint)
      {
        const double* x = c.Mesh.GetPoint(i);
        const double d[3] = { view[0] - x[0], view[1] - x[1], view[2] - x[2] };
        cosOut = (d[0] * nrm[0] + d[1] * nrm[1] + d[2] * nrm[2]) /
          std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      }
      seen += cosOut > 0.0;
      for (int ch = 0; ch < 3; ++ch)
      {
        EXPECT_EQ(L[3 * k + ch],
          OutgoingRadiance(c.Fluence[3 * i + ch], c.Irradiance[3 * i + ch], c.Eta[i], cosOut,
            RadianceReadout::EnergyConserving));
      }
    }
    EXPECT_GT(seen, 0);
  }
}

TEST(BoundaryRadiance, SerialTwinGivesTheSameBits)
{
  RadianceCase c;
  MakeCase(c);
  const double view[3] = { -3.0, 1.0, 5.0 };
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const std::vector<double> serial = BoundaryRadiance(c.Mesh, c.Fluence, c.Irradiance, c.Eta, view);
  omp_set_num_threads(std::max(threads, 2));
  const std::vector<double> parallel =
    BoundaryRadiance(c.Mesh, c.Fluence, c.Irradiance, c.Eta, view);
  omp_set_num_threads(threads);
  EXPECT_EQ(serial, parallel);
  c.Eta.pop_back();
  EXPECT_THROW(BoundaryRadiance(c.Mesh, c.Fluence, c.Irradiance, c.Eta, nullptr), Error);
}

} // namespace
