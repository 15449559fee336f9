// The input checks of the vertex assemblies (VertexAssembly.h) are min /
// max / sum reductions over each array (vectorised) instead of a logical
// test per value: these are the cases where the two could differ (sums that
// overflow, NaN hidden from min / max, -0, infinities of opposite signs in
// one tet, a bad value in the second thread's half), for both assemblies
// that share them and 1 or 2 threads. A valid input must assemble, an
// invalid one must be refused naming the array, tet / point and channel.

#include "DiscreteDivergence.h"
#include "Error.h"
#include "FiniteElement.h"
#include "TestMeshes.h"
#include "TestProblems.h"
#include "TestRandomProblems.h"
#include "TetMesh.h"

#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace
{
using namespace translucency;
using namespace translucency::testing;

struct Input
{
  OpticalProperties Material;
  std::vector<double> Irradiance;
};

std::unique_ptr<Discretization> Make(bool fem, int threads)
{
  if (fem)
  {
    auto d = std::make_unique<FiniteElement>();
    d->SetNumberOfThreads(threads);
    return d;
  }
  auto d = std::make_unique<DiscreteDivergence>();
  d->SetNumberOfThreads(threads);
  return d;
}

TEST(AssemblyChecks, ReductionsAcceptAndRefuseLikeAPerValueTest)
{
  MeshData data = CubeMesh(4, 2.0, 0.2, 3);
  TetMesh mesh;
  mesh.SetGeometry(data.Points, data.Tets);
  const int numTets = mesh.GetNumberOfTets();
  const int last = numTets - 1; // in the second thread's half
  const int lastPoint = mesh.GetNumberOfPoints() - 1;
  const Input good{ RandomMaterial(numTets, 5), RandomIrradiance(mesh, 6) };

  struct Case
  {
    const char* What;
    void (*Change)(Input&, int lastTet, int lastPoint);
    const char* Named; ///< "" = valid
  };
  const Case cases[] = {
    { "sums overflow to +inf: valid",
      [](Input& in, int t, int p)
      {
        for (int k : { 0, 1, t })
        {
          in.Material.AbsorptionCoefficient[3 * k] = DBL_MAX;
          in.Material.ReducedScatteringCoefficient[3 * k + 1] = DBL_MAX;
          in.Material.RefractiveIndex[k] = DBL_MAX;
        }
        in.Irradiance[3 * p] = DBL_MAX;
        in.Irradiance[0] = DBL_MAX;
      },
      "" },
    { "-0 absorption and irradiance: valid",
      [](Input& in, int t, int p)
      {
        in.Material.AbsorptionCoefficient[3 * t + 2] = -0.0;
        in.Irradiance[3 * p + 1] = -0.0;
      },
      "" },
    { "mu_a +inf and sigma_s' -inf in one tet",
      [](Input& in, int t, int)
      {
        in.Material.AbsorptionCoefficient[3 * t + 1] = std::numeric_limits<double>::infinity();
        in.Material.ReducedScatteringCoefficient[3 * t + 1] = -std::numeric_limits<double>::infinity();
      },
      "of tet LAST, channel G" },
    { "NaN mu_a in the last tet",
      [](Input& in, int t, int)
      { in.Material.AbsorptionCoefficient[3 * t + 2] = std::numeric_limits<double>::quiet_NaN(); },
      "AbsorptionCoefficient of tet LAST, channel B" },
    { "NaN sigma_s' next to a huge valid value",
      [](Input& in, int t, int)
      {
        in.Material.ReducedScatteringCoefficient[0] = DBL_MAX;
        in.Material.ReducedScatteringCoefficient[3 * t] = std::numeric_limits<double>::quiet_NaN();
      },
      "ReducedScatteringCoefficient of tet LAST, channel R" },
    { "-inf eta", [](Input& in, int t, int)
      { in.Material.RefractiveIndex[t] = -std::numeric_limits<double>::infinity(); },
      "RefractiveIndex of tet LAST" },
    { "-0 eta", [](Input& in, int t, int) { in.Material.RefractiveIndex[t] = -0.0; },
      "RefractiveIndex of tet LAST" },
    { "-inf irradiance", [](Input& in, int, int p)
      { in.Irradiance[3 * p + 2] = -std::numeric_limits<double>::infinity(); },
      "Irradiance of point LASTPOINT, channel B" },
    { "NaN irradiance after a huge value",
      [](Input& in, int, int p)
      {
        in.Irradiance[0] = DBL_MAX;
        in.Irradiance[3 * p] = std::numeric_limits<double>::quiet_NaN();
      },
      "Irradiance of point LASTPOINT, channel R" },
    { "zero mu_a + sigma_s'",
      [](Input& in, int t, int)
      {
        in.Material.AbsorptionCoefficient[3 * t] = 0.0;
        in.Material.ReducedScatteringCoefficient[3 * t] = 0.0;
      },
      "tet LAST, channel R" },
  };
  for (bool fem : { false, true })
  {
    for (int threads : { 1, 2 })
    {
      for (const Case& c : cases)
      {
        SCOPED_TRACE(std::string(c.What) + (fem ? ", fem" : ", divergence") + ", " +
          std::to_string(threads) + " threads");
        Input in = good;
        c.Change(in, last, lastPoint);
        auto d = Make(fem, threads);
        DiffusionSystem system;
        const std::string message =
          ErrorMessage([&] { d->Assemble(mesh, in.Material, in.Irradiance, system); });
        std::string named = c.Named;
        for (const auto& [key, value] :
          { std::make_pair(std::string("LASTPOINT"), std::to_string(lastPoint)),
            std::make_pair(std::string("LAST"), std::to_string(last)) })
        {
          const std::size_t at = named.find(key);
          if (at != std::string::npos)
          {
            named.replace(at, key.size(), value);
          }
        }
        if (named.empty())
        {
          EXPECT_EQ(message, "");
          EXPECT_EQ(system.NumberOfUnknowns, mesh.GetNumberOfPoints());
        }
        else
        {
          EXPECT_TRUE(Contains(message, named)) << message;
        }
        // The same object assembles valid input again.
        EXPECT_EQ(ErrorMessage([&] { d->Assemble(mesh, good.Material, good.Irradiance, system); }), "");
      }
    }
  }
}

} // namespace
