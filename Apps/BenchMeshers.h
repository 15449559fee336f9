/**
 * @file BenchMeshers.h
 * @brief `translucency bench --meshers`: both tetrahedralisers of
 * vtkTetrahedralizeSurface (TetGen, gmsh's HXT when built) on the same
 * surface in one run, graded (hxt also without its optimisation pass) and
 * with uniform sizing: time, tets/s and the
 * shape of the tets (min dihedral histogram, radius-edge ratios, edge-length
 * spread) from translucency::ComputeTetQuality.
 */
#pragma once

#include <string>
#include <vector>

namespace translucency_app
{

/// The options of `translucency bench --meshers` (declared in BenchCommand.cxx).
struct MesherBenchOptions
{
  std::string MeshPath = "Data/bunny.ply";
  std::vector<double> Tets = { 1000000 };
  int Runs = 3;
  std::string JsonPath;
  bool GradedOnly = false; ///< --graded-only: no uniform-sizing rows
};

/// Runs the mesher bench and prints its table; 0 on success. Throws
/// translucency::Error with the filter's message when a mesher fails.
int BenchMeshers(const MesherBenchOptions& options);

} // namespace translucency_app
