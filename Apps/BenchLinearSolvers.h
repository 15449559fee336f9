/**
 * @file BenchLinearSolvers.h
 * @brief `translucency bench --linear-solvers [NAMES]`: every linear solver
 * of the build (or the named ones) on the bunny at several sizes, side by
 * side (BenchLinearSolvers.cxx), and the mesh building it shares with the
 * plain `translucency bench`.
 */
#pragma once

#include <vtkSmartPointer.h>

#include <string>
#include <vector>

class vtkPolyData;
class vtkUnstructuredGrid;

namespace translucency_app
{

/// Tetrahedralize `surface` to about `targetTets` tets (vtkTetrahedralizeSurface
/// with the tetgen mesher, so that the benches' figures compare across sessions;
/// spatially ordered) and copy the result to the core's arrays (3 coordinates
/// per point, 4 point ids per tet). Returns the TetGen time (ms). Throws
/// translucency::Error with the filter's message on failure.
double TetrahedralizeForBench(vtkPolyData* surface, double targetTets,
  vtkSmartPointer<vtkUnstructuredGrid>& grid, std::vector<double>& points, std::vector<int>& tets);

/// The options of `translucency bench --linear-solvers` (declared in BenchCommand.cxx).
struct LinearSolverBenchOptions
{
  std::vector<std::string> Names; ///< solvers to run; empty: every one of the build
  std::string MeshPath = "Data/bunny.ply";
  std::vector<double> Tets = { 100000, 500000, 1000000 };
  int Runs = 5;
  std::string JsonPath;
  std::string PlotPath; ///< error vs time picture (and its .csv); empty: none
  int HypreRanks = 2;   ///< ranks of the multi-rank hypre-amg row; < 2: none
  bool DoCut = true;    ///< the cut -> new fluence figure
};

/// The data file of `--plot FILE`: FILE with its extension replaced by .csv
/// (the folder's name may hold dots).
std::string PlotDataPath(const std::string& plotPath);

/// `translucency bench --linear-solvers ...`.
int BenchLinearSolvers(const LinearSolverBenchOptions& options);

} // namespace translucency_app
