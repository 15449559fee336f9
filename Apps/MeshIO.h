/**
 * @file MeshIO.h
 * @brief Reading a mesh file by its extension, and handing a tet grid to the
 * Solvers/ core.
 */
#pragma once

#include <vtkSmartPointer.h>

#include <string>
#include <vector>

class vtkPolyData;
class vtkUnstructuredGrid;

namespace translucency_app
{

/// Read a surface (.ply .stl .obj .vtp) into `surface` or a tet mesh (.vtu
/// .node .ele) into `grid`. False with `error` naming the file on failure.
bool ReadMesh(const std::string& path, vtkSmartPointer<vtkPolyData>& surface,
  vtkSmartPointer<vtkUnstructuredGrid>& grid, std::string& error);

/// The points (x, y, z per point) and tets (4 point ids per cell) of a
/// tetrahedral grid as the Solvers/ core takes them. Throws translucency::Error
/// naming the cell when a cell does not have 4 points.
void GridToCoreArrays(vtkUnstructuredGrid* grid, std::vector<double>& points, std::vector<int>& tets);

} // namespace translucency_app
