/**
 * @file SceneFile.h
 * @brief The radiosity scene file (JSON) of `translucency radiosity`: objects
 * (built-in boxes or mesh files; translucent or opaque), materials, albedos,
 * lights, camera and solver settings. The format is documented in
 * Documentation/Radiosity.md.
 */
#pragma once

#include "LightSources.h"

#include <vtkSmartPointer.h>

#include <string>
#include <vector>

class vtkPartitionedDataSetCollection;

namespace translucency_app
{

/// Camera of the pictures (mm). Empty position: looking along +y at the scene.
struct SceneCamera
{
  std::vector<double> Position;
  std::vector<double> FocalPoint;
  std::vector<double> ViewUp{ 0.0, 0.0, 1.0 };
  double ViewAngle = 40.0; ///< degrees
};

/// Solver settings a scene file may give (the command line overrides some).
struct SceneSettings
{
  int RaysPerPatch = 256;
  double RelTol = 0.005;
  int MaxIter = 200;
  std::string SOperator = "diffusion";
  std::string Iteration = "gauss-seidel";
  std::string LinearSolver = "cg-jacobi";
  double FormFactorThreshold = 0.0;
  double VoxelSize = 0.0;
  double MaxDistance = 0.0;
};

/// A loaded scene: one partition per object (named after the object).
struct LoadedScene
{
  vtkSmartPointer<vtkPartitionedDataSetCollection> Objects;
  std::vector<std::string> Names;
  std::vector<bool> Translucent;
  std::vector<translucency::LightSource> Lights;
  SceneCamera Camera;
  SceneSettings Settings;
};

/**
 * Read `path` and build the objects: boxes are triangulated with cells of
 * about `cell_size` mm (cellSizeOverride > 0 replaces every object's), mesh
 * files are read (.ply .stl .obj .vtp .vtu .node/.ele; relative to the scene
 * file), translucent surfaces are tetrahedralised with TetGen and given their
 * coefficients. Throws translucency::Error naming the file, the object and
 * the problem.
 */
LoadedScene LoadScene(const std::string& path, double cellSizeOverride = 0.0);

} // namespace translucency_app
