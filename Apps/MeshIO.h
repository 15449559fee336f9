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

/// Check a VTK XML file (.vtu .vtp .vti) before a VTK reader sees it: the
/// <VTKFile> header (type for the extension, byte_order, header_type,
/// compressor), the <Piece> counts (integers in [0, 2^31-1]), and every
/// <DataArray> (type, NumberOfComponents in [1, 1024], NumberOfTuples, format)
/// against its data: the number of ascii values, the size in the header of
/// inline binary or appended data against the tuples x components x type size
/// the attributes ask for, and against the bytes the file holds. VTK 9.2's
/// readers hang, abort or crash on such inconsistencies. Throws
/// translucency::Error naming the file, the element and the attribute.
void CheckVtkXmlFile(const std::string& path);

/// The points (x, y, z per point) and tets (4 point ids per cell) of a
/// tetrahedral grid as the Solvers/ core takes them. Throws translucency::Error
/// naming the first bad point or cell (vtkTranslucency::ToTetArrays).
void GridToCoreArrays(vtkUnstructuredGrid* grid, std::vector<double>& points, std::vector<int>& tets);

} // namespace translucency_app
