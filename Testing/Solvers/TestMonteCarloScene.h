/**
 * @file TestMonteCarloScene.h
 * @brief The Monte Carlo tests' scene with every kind of launch: a jittered
 * 10 mm cube of a three-channel medium with a point source and a pencil beam
 * inside and a directional light on it (the tally checks of
 * TestMonteCarloSources and the ranks' share of TestReplicatedMonteCarlo).
 */
#pragma once

#include "InteriorSources.h"
#include "LightSources.h"
#include "OpticalProperties.h"
#include "TestMeshes.h"
#include "TestProblems.h"
#include "TetMesh.h"

namespace translucency
{
namespace testing
{

struct MonteCarloScene
{
  TetMesh Mesh;
  OpticalProperties Material;
  Sources Interior;
  LightSource Light;

  MonteCarloScene()
  {
    const MeshData data = CubeMesh(6, 10.0, 0.2, 3);
    Mesh.SetGeometry(data.Points, data.Tets);
    const double muA[3] = { 0.1, 0.2, 0.05 }, muS[3] = { 1.0, 0.5, 2.0 };
    Material = OpticalProperties::Uniform(Mesh.GetNumberOfTets(), muA, muS, 1.4);
    PointSource point;
    point.Position = { 4.1, 5.2, 3.3 };
    point.Power = { 1.0, 0.5, 2.0 };
    Interior.AddPointSource(point);
    PencilBeam beam;
    beam.Position = { 5.0, 4.0, 10.0 };
    beam.Direction = { 0.3, 0.0, -1.0 };
    beam.Power = { 0.5, 1.0, 0.0 };
    Interior.AddPencilBeam(beam);
    Light.Type = LightSource::Kind::Directional;
    Light.Direction = { 0.0, -1.0, 0.0 };
    Light.Power = { 0.002, 0.001, 0.0 };
  }
  MonteCarloScene(const MonteCarloScene&) = delete; // the problem borrows the members
  MonteCarloScene& operator=(const MonteCarloScene&) = delete;

  /// The light and the interior sources on the mesh (borrows this scene).
  DiffusionProblem Problem() const
  {
    DiffusionProblem problem = MakeProblem(Mesh, Material);
    problem.Lights = { Light };
    problem.InteriorSources = &Interior;
    return problem;
  }
};

} // namespace testing
} // namespace translucency
