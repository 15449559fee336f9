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

/// Tetrahedralize `surface` to about `targetTets` tets (vtkTetrahedralizeSurface,
/// spatially ordered) and copy the result to the core's arrays (3 coordinates
/// per point, 4 point ids per tet). Returns the TetGen time (ms). Throws
/// translucency::Error with the filter's message on failure.
double TetrahedralizeForBench(vtkPolyData* surface, double targetTets,
  vtkSmartPointer<vtkUnstructuredGrid>& grid, std::vector<double>& points, std::vector<int>& tets);

/// `translucency bench --linear-solvers ...` (args without "bench").
int BenchLinearSolvers(const std::vector<std::string>& args);

/// Its help text.
extern const char* const BenchLinearSolversHelp;

} // namespace translucency_app
