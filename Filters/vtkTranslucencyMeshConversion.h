/**
 * @file vtkTranslucencyMeshConversion.h
 * @brief Private helpers shared by the Translucency filters: VTK data set
 * <-> core types. Each returns false and fills `error` with a message that
 * names the problem (array, cell, value) instead of throwing.
 */
#ifndef vtkTranslucencyMeshConversion_h
#define vtkTranslucencyMeshConversion_h

#include "OpticalProperties.h"
#include "TetMesh.h"

#include <string>
#include <vector>

class vtkDataArray;
class vtkFieldData;
class vtkPointData;
class vtkUnstructuredGrid;

namespace vtkTranslucency
{
/// Array names of the data contract (SPEC "Data contract").
constexpr const char* AbsorptionName = "AbsorptionCoefficient";
constexpr const char* ScatteringName = "ReducedScatteringCoefficient";
constexpr const char* RefractiveIndexName = "RefractiveIndex";
constexpr const char* IrradianceName = "Irradiance";
constexpr const char* FluenceName = "Fluence";
constexpr const char* RadianceName = "Radiance";
constexpr const char* OriginalCellIdsName = "vtkOriginalCellIds";

/// Copy points and tets of `grid` into `mesh` (builds the topology). Fails
/// if the grid is empty or holds a cell that is not a linear tetrahedron, or
/// if the core rejects the geometry (degenerate tet, ...).
bool ToTetMesh(vtkUnstructuredGrid* grid, translucency::TetMesh& mesh, std::string& error);

/// Read the three coefficient cell arrays of `grid` into `material`, checked
/// for presence, number of components and values.
bool ToOpticalProperties(
  vtkUnstructuredGrid* grid, translucency::OpticalProperties& material, std::string& error);

/// Read a point array with `components` components as doubles. Fails if it
/// is missing or has the wrong number of components.
bool ReadPointArray(vtkUnstructuredGrid* grid, const char* name, int components,
  std::vector<double>& values, std::string& error);

/// A new vtkDoubleArray named `name` with 3 components holding `values`.
vtkDataArray* NewTripleArray(const char* name, const std::vector<double>& values);

/// A cheap fingerprint of the geometry (points and cells MTime and counts),
/// so a filter can keep its topology while only coefficients or lights change.
std::string GeometryKey(vtkUnstructuredGrid* grid);
}

#endif
