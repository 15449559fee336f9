// AimPencilBeam (AimedPencilBeam.h): the entry point of a beam given by two
// points, as ParaView's line widget places it, on the cube [0, 2]^3.

#include "AimedPencilBeam.h"
#include "Error.h"
#include "TetMesh.h"

#include "../TestMeshes.h"

#include <gtest/gtest.h>

#include <string>

namespace
{

using namespace translucency;

TetMesh Cube()
{
  const translucency::testing::MeshData data = translucency::testing::CubeMesh(4, 2.0);
  TetMesh mesh;
  mesh.SetGeometry(data.Points, data.Tets);
  return mesh;
}

std::string ErrorOf(const TetMesh& mesh, std::array<double, 3> from, std::array<double, 3> to)
{
  try
  {
    AimPencilBeam(mesh, from, to, { 1, 1, 1 }, "beam A");
  }
  catch (const Error& e)
  {
    return e.what();
  }
  return "";
}

TEST(AimedPencilBeam, EntersWhereTheRayHitsTheSurface)
{
  const TetMesh mesh = Cube();
  // Oblique, from above the top face z = 2 towards a point inside.
  const PencilBeam beam = AimPencilBeam(mesh, { 0.3, 0.7, 5.0 }, { 1.3, 1.2, 1.0 },
    { 1.0, 2.0, 3.0 }, "beam A");
  // The ray x = 0.3 + s, y = 0.7 + 0.5 s, z = 5 - 4 s meets z = 2 at s = 0.75.
  EXPECT_NEAR(beam.Position[0], 1.05, 1e-12);
  EXPECT_NEAR(beam.Position[1], 1.075, 1e-12);
  EXPECT_NEAR(beam.Position[2], 2.0, 1e-12);
  EXPECT_EQ(beam.Direction[0], 1.0);
  EXPECT_EQ(beam.Direction[1], 0.5);
  EXPECT_EQ(beam.Direction[2], -4.0);
  EXPECT_EQ(beam.Power[2], 3.0);
  EXPECT_EQ(beam.Label, "beam A");
  // Placeable: the entry is on the surface and the direction points in.
  Sources sources;
  sources.AddPencilBeam(beam);
  EXPECT_NO_THROW(sources.Validate());
}

TEST(AimedPencilBeam, StartOnTheSurfaceIsTheEntry)
{
  const TetMesh mesh = Cube();
  // Point 1 on the face x = 0 (as a bounds domain puts it), slightly inside too.
  for (const double x : { 0.0, 0.01 })
  {
    const PencilBeam beam = AimPencilBeam(mesh, { x, 1.1, 0.9 }, { 1.5, 1.1, 0.9 },
      { 1, 1, 1 }, "beam A");
    EXPECT_NEAR(beam.Position[0], 0.0, 1e-12) << "start at x = " << x;
    EXPECT_NEAR(beam.Position[1], 1.1, 1e-12);
    EXPECT_NEAR(beam.Position[2], 0.9, 1e-12);
  }
}

TEST(AimedPencilBeam, ErrorsNameTheBeamAndThePoints)
{
  const TetMesh mesh = Cube();
  const std::string same = ErrorOf(mesh, { 1, 1, 4 }, { 1, 1, 4 });
  EXPECT_NE(same.find("beam A: from Point 1 (1, 1, 4) towards Point 2 (1, 1, 4)"),
    std::string::npos)
    << same;
  EXPECT_NE(same.find("the two points are the same"), std::string::npos) << same;
  EXPECT_NE(ErrorOf(mesh, { 5, 5, 4 }, { 5, 5, 0 }).find("misses the object"),
    std::string::npos);
  EXPECT_NE(ErrorOf(mesh, { 1, 1, 4 }, { 1, 1, 8 }).find("misses the object"),
    std::string::npos); // pointing away from the object
  EXPECT_NE(ErrorOf(mesh, { 1, 1, 1 }, { 1, 1, 0.5 }).find("Point 1 is inside the object"),
    std::string::npos);
  EXPECT_NE(ErrorOf(mesh, { 1, 1, NAN }, { 1, 1, 0.5 }).find("must be finite"),
    std::string::npos);
}

} // namespace
