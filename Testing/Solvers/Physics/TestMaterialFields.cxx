// The material generators of MaterialFields.h: table ids, references,
// inclusions, layers and veins, on hand-made centroids and depths.

#include "Error.h"
#include "MaterialFields.h"
#include "OpticalProperties.h"

#include <gtest/gtest.h>

#include <cmath>

namespace
{

using namespace translucency;

MaterialCoefficients Make(double muA, double sigmaS, double eta)
{
  MaterialCoefficients m;
  m.Absorption = { muA, 2.0 * muA, 3.0 * muA };
  m.ReducedScattering = { sigmaS, 2.0 * sigmaS, 3.0 * sigmaS };
  m.RefractiveIndex = eta;
  return m;
}

MaterialTable TwoEntries()
{
  MaterialTable table;
  table.FileName = "two.json";
  table.Entries.push_back({ 7, "skin", Make(0.01, 1.0, 1.4) });
  table.Entries.push_back({ 2, "", Make(0.02, 2.0, 1.5) });
  return table;
}

TEST(MaterialFields, PresetMatchesTheTable)
{
  const MaterialCoefficients m = MaterialCoefficients::FromPreset("Marble");
  const MaterialPreset& p = FindMaterialPreset("marble");
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_EQ(m.Absorption[c], p.Absorption[c]);
    EXPECT_EQ(m.ReducedScattering[c], p.ReducedScattering[c]);
  }
  EXPECT_EQ(m.RefractiveIndex, p.RefractiveIndex);
  EXPECT_THROW(MaterialCoefficients::FromPreset("cheese"), Error);
}

TEST(MaterialFields, TableIdsMapEachTetToItsEntry)
{
  const MaterialTable table = TwoEntries();
  const MaterialField field =
    MaterialsFromIds({ 7.0, 2.0, 2.0, 7.0 }, table, [](int, double) { return std::string(); });
  ASSERT_EQ(field.Which.size(), 4u);
  EXPECT_EQ(field.At(0).RefractiveIndex, 1.4);
  EXPECT_EQ(field.At(1).RefractiveIndex, 1.5);
  EXPECT_EQ(field.At(2).Absorption[2], 3.0 * 0.02);
  EXPECT_EQ(field.At(3).ReducedScattering[1], 2.0);
}

TEST(MaterialFields, UnknownAndNonIntegerIdsNameTheTetAndTheTable)
{
  const MaterialTable table = TwoEntries();
  const auto describe = [](int tet, double id) {
    return "tet " + std::to_string(tet) + " id " + std::to_string(id);
  };
  try
  {
    MaterialsFromIds({ 7.0, 3.0 }, table, describe);
    FAIL() << "no error for id 3";
  }
  catch (const Error& e)
  {
    EXPECT_NE(std::string(e.what()).find("tet 1 id 3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("is not an id of the material table 'two.json'"),
      std::string::npos)
      << e.what();
  }
  try
  {
    MaterialsFromIds({ 2.5 }, table, describe);
    FAIL() << "no error for id 2.5";
  }
  catch (const Error& e)
  {
    EXPECT_NE(std::string(e.what()).find("is not an integer id"), std::string::npos) << e.what();
  }
}

TEST(MaterialFields, ReferencesAreNamesThenIdsThenPresets)
{
  const MaterialTable table = TwoEntries();
  EXPECT_EQ(table.Resolve("skin").RefractiveIndex, 1.4);
  EXPECT_EQ(table.Resolve("2").RefractiveIndex, 1.5);
  EXPECT_EQ(table.Resolve("ketchup").Absorption[0],
    MaterialCoefficients::FromPreset("ketchup").Absorption[0]);
  EXPECT_THROW(table.Resolve("3"), Error);
  EXPECT_THROW(MaterialTable().Resolve("nothing"), Error);
}

TEST(MaterialFields, InclusionHoldsTheTetsInTheClosedBallOnly)
{
  const std::vector<Point3> centroids = { { 0.0, 0.0, 0.0 }, { 1.0, 0.0, 0.0 },
    { 0.0, 1.0000001, 0.0 }, { 0.5, 0.5, 0.5 }, { 3.0, 3.0, 3.0 } };
  const MaterialCoefficients inside = Make(0.1, 1.0, 1.2), outside = Make(0.2, 2.0, 1.3);
  const MaterialField field =
    SphericalInclusion(centroids, { 0.0, 0.0, 0.0 }, 1.0, inside, outside);
  const std::vector<bool> expected = { true, true, false, true, false };
  for (size_t i = 0; i < centroids.size(); ++i)
  {
    EXPECT_EQ(field.At(static_cast<int>(i)).RefractiveIndex, expected[i] ? 1.2 : 1.3) << i;
  }
}

TEST(MaterialFields, LayerBoundariesAtTheSumsOfTheThicknesses)
{
  const std::vector<MaterialCoefficients> materials = { Make(0.1, 1.0, 1.1),
    Make(0.2, 1.0, 1.2), Make(0.3, 1.0, 1.3) };
  const std::vector<double> thicknesses = { 0.5, 1.5, 1.0 };
  // Layer 0: [0, 0.5), layer 1: [0.5, 2), layer 2: [2, inf).
  const std::vector<double> depths = { 0.0, 0.4999, 0.5, 1.9999, 2.0, 2.9, 3.0, 100.0 };
  const std::vector<int> expected = { 0, 0, 1, 1, 2, 2, 2, 2 };
  const MaterialField field = Layers(depths, thicknesses, materials);
  EXPECT_EQ(field.Which, expected);
  EXPECT_EQ(field.At(4).RefractiveIndex, 1.3);
  EXPECT_THROW(Layers(depths, { 0.5, -1.0, 1.0 }, materials), Error);
  EXPECT_THROW(Layers(depths, { 0.5, NAN, 1.0 }, materials), Error);
  EXPECT_THROW(Layers(depths, {}, {}), Error);
}

/// A smooth stand-in for the Perlin noise, in [-1, 1].
double TestNoise(const Point3& x, double f)
{
  return std::sin(f * (1.3 * x[0] + 0.7 * x[1] - 0.4 * x[2]));
}

std::vector<Point3> Grid()
{
  std::vector<Point3> points;
  for (int i = 0; i < 10; ++i)
  {
    for (int j = 0; j < 10; ++j)
    {
      for (int k = 0; k < 10; ++k)
      {
        points.push_back({ 0.37 * i, 0.41 * j - 1.0, 0.53 * k });
      }
    }
  }
  return points;
}

TEST(MaterialFields, VeinsBlendBetweenTheTwoMaterialsDeterministically)
{
  const MaterialCoefficients base = Make(0.1, 1.0, 1.2), vein = Make(0.4, 3.0, 1.5);
  VeinsField veins;
  veins.SetMaterials(base, vein);
  veins.SetDirection({ 1.0, 2.0, 0.5 });
  veins.SetFrequency(0.7);
  const std::vector<Point3> points = Grid();
  MaterialField a, b;
  ASSERT_TRUE(veins.Evaluate(points, TestNoise, a));
  ASSERT_TRUE(veins.Evaluate(points, TestNoise, b));
  ASSERT_EQ(a.Palette.size(), points.size());
  double lowest = 1.0, highest = 0.0;
  for (size_t i = 0; i < points.size(); ++i)
  {
    const MaterialCoefficients& m = a.At(static_cast<int>(i));
    const double w = (m.RefractiveIndex - 1.2) / 0.3;
    EXPECT_GE(w, -1e-12);
    EXPECT_LE(w, 1.0 + 1e-12);
    lowest = std::min(lowest, w);
    highest = std::max(highest, w);
    for (int c = 0; c < 3; ++c)
    {
      EXPECT_NEAR(m.Absorption[c], (1 - w) * base.Absorption[c] + w * vein.Absorption[c], 1e-12);
      EXPECT_GE(m.ReducedScattering[c], base.ReducedScattering[c] - 1e-12);
      EXPECT_LE(m.ReducedScattering[c], vein.ReducedScattering[c] + 1e-12);
      EXPECT_EQ(m.ReducedScattering[c], b.At(static_cast<int>(i)).ReducedScattering[c]);
    }
  }
  // Veins are thin (sharpness 8): most of the volume is base, some is vein.
  EXPECT_LT(lowest, 0.01);
  EXPECT_GT(highest, 0.5);
}

TEST(MaterialFields, StraightVeinsFollowTheDirection)
{
  // No turbulence: w = (1 - |sin(2 pi f d.x)|)^s, the same on planes d.x = const.
  VeinsField veins;
  veins.SetMaterials(Make(0.1, 1.0, 1.0), Make(0.1, 1.0, 2.0));
  veins.SetDirection({ 0.0, 0.0, 3.0 });
  veins.SetFrequency(0.25);
  veins.SetTurbulence(0.0);
  veins.SetSharpness(2.0);
  const std::vector<Point3> points = { { 0.0, 0.0, 1.0 }, { 5.0, -3.0, 1.0 }, { 0.0, 0.0, 2.0 } };
  MaterialField field;
  ASSERT_TRUE(veins.Evaluate(points, TestNoise, field));
  const double w = std::pow(1.0 - std::abs(std::sin(2.0 * M_PI * 0.25)), 2.0);
  EXPECT_NEAR(field.At(0).RefractiveIndex, 1.0 + w, 1e-14);
  EXPECT_EQ(field.At(0).RefractiveIndex, field.At(1).RefractiveIndex);
  EXPECT_NEAR(field.At(2).RefractiveIndex, 2.0, 1e-14); // sin(pi) = 0: the vein itself
}

TEST(MaterialFields, VeinsCheckTheirSettingsAndStopOnRequest)
{
  VeinsField veins;
  MaterialField field;
  veins.SetDirection({ 0.0, 0.0, 0.0 });
  EXPECT_THROW(veins.Evaluate(Grid(), TestNoise, field), Error);
  veins.SetDirection({ 1.0, 0.0, 0.0 });
  veins.SetFrequency(0.0);
  EXPECT_THROW(veins.Evaluate(Grid(), TestNoise, field), Error);
  veins.SetFrequency(1.0);
  veins.SetProgressCallback([](double) { return false; });
  EXPECT_FALSE(veins.Evaluate(Grid(), TestNoise, field));
  EXPECT_TRUE(field.Palette.empty());
}

TEST(MaterialFields, VeinPhaseIsInTheUnitCube)
{
  for (int seed : { 0, 1, 17, 123456 })
  {
    const Point3 p = VeinsField::Phase(seed);
    for (double v : p)
    {
      EXPECT_GE(v, 0.0);
      EXPECT_LT(v, 1.0);
    }
  }
  EXPECT_EQ(VeinsField::Phase(0), (Point3{ 0.0, 0.0, 0.0 }));
}

TEST(MaterialFields, ScaleAndValidate)
{
  MaterialField field = MaterialField::Uniform(3, Make(0.1, 1.0, 1.3));
  field.Scale(2.0);
  EXPECT_EQ(field.At(2).Absorption[1], 0.4);
  EXPECT_EQ(field.At(2).RefractiveIndex, 1.3);
  EXPECT_NO_THROW(field.Validate());
  field.Palette[0].Absorption[0] = -1.0;
  EXPECT_THROW(field.Validate(), Error);
  EXPECT_THROW(CheckProbedValues(4, { 1.0, 2.0, 3.0 }, "mua", { 0.0, NAN, 1.0 }), Error);
  EXPECT_NO_THROW(CheckProbedValues(4, { 1.0, 2.0, 3.0 }, "mua", { 0.0, 0.5, 1.0 }));
}

} // namespace
