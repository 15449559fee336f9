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

#include <memory>
#include <string>
#include <vtkType.h> // for vtkIdType

#include <vector>

class vtkDataArray;
class vtkDataSetAttributes;
class vtkFieldData;
class vtkPointData;
class vtkPolyData;
class vtkUnstructuredGrid;

namespace vtkTranslucency
{
/// Array names of the data contract (Documentation/Pipeline.md, "Data contract and units").
constexpr const char* AbsorptionName = "AbsorptionCoefficient";
constexpr const char* ScatteringName = "ReducedScatteringCoefficient";
constexpr const char* RefractiveIndexName = "RefractiveIndex";
constexpr const char* IrradianceName = "Irradiance";
constexpr const char* FluenceName = "Fluence";
constexpr const char* RadianceName = "Radiance";
constexpr const char* OriginalCellIdsName = "vtkOriginalCellIds";
constexpr const char* OriginalPointIdsName = "vtkOriginalPointIds";

/// The checks a surface needs before any VTK filter touches it
/// (vtkStaticCleanPolyData crashes on infinite or huge coordinates and on
/// point ids out of range): every coordinate finite and below `maxCoordinate`
/// in magnitude (mm), every cell array consistent, every point id in range.
/// The message names the first bad point or cell.
bool CheckSurfacePointsAndIds(vtkPolyData* input, double maxCoordinate, std::string& error);

/// Copy the points (3 per point, mm) and tets (4 point ids each) of `grid`,
/// checking every point (finite coordinates) and every cell (a linear
/// tetrahedron, 4 point ids, ids in range) before its ids are read; the
/// message names the first bad point or cell. An empty grid is not an error.
bool ToTetArrays(vtkUnstructuredGrid* grid, std::vector<double>& points, std::vector<int>& tets,
  std::string& error);

/// The cells of `grid` this piece owns (not flagged vtkGhostType
/// DUPLICATECELL: a ghost copy is another rank's tet), in order; their 4 point
/// ids from `cells` (ToTetArrays' tets) are appended to `tets`.
std::vector<vtkIdType> OwnedTets(
  vtkUnstructuredGrid* grid, const std::vector<int>& cells, std::vector<int>& tets);

/// Copy points and tets of `grid` into `mesh` (builds the topology). Fails
/// if the grid is empty or holds a cell that is not a linear tetrahedron, or
/// if the core rejects the geometry (degenerate tet, ...). Every cell is
/// checked (type, 4 point ids, ids in range; the message names the cell) and
/// every point (finite coordinates). Coincident points that both carry tets
/// (an internal crack, treated as boundary) are not an error (vtkStrokeCut and
/// hand-made meshes may crack a mesh on purpose): `warning`, if given, names
/// them ("" if none).
bool ToTetMesh(vtkUnstructuredGrid* grid, translucency::TetMesh& mesh, std::string& error,
  std::string* warning = nullptr);

/// Read the three coefficient cell arrays of `grid` into `material`, checked
/// for presence, number of components and values.
bool ToOpticalProperties(
  vtkUnstructuredGrid* grid, translucency::OpticalProperties& material, std::string& error);

/// The three coefficient cell arrays of `grid` in place, no copy.
struct CoefficientValues
{
  const double* Absorption = nullptr;      ///< 3 per cell
  const double* Scattering = nullptr;      ///< 3 per cell
  const double* RefractiveIndex = nullptr; ///< 1 per cell
};
/// `grid`'s AbsorptionCoefficient, ReducedScatteringCoefficient and
/// RefractiveIndex in place when each is a vtkDoubleArray (contiguous) of
/// `tuples` tuples with 3, 3 and 1 components; each null otherwise (absent,
/// another type or shape: read them with ToOpticalProperties, which names
/// the problem).
CoefficientValues CoefficientArraysInPlace(vtkUnstructuredGrid* grid, vtkIdType tuples);

/// Read a point array with `components` components as doubles. Fails if it
/// is missing or has the wrong number of components.
bool ReadPointArray(vtkUnstructuredGrid* grid, const char* name, int components,
  std::vector<double>& values, std::string& error);

/// Read the `RefractiveIndex` cell array (1 component, every value finite
/// and > 0; the message names the first bad tet).
bool ReadRefractiveIndex(vtkUnstructuredGrid* grid, std::vector<double>& values, std::string& error);

/// Copy the arrays of `in` for the entities `kept` (ids into `in`) into
/// `out`, then add the id map `name` (vtkOriginalCellIds / PointIds), composed
/// with the input's own map of that name if it has one, so ids always point
/// at the original mesh (used by vtkStrokeCut and vtkFractureTetMesh).
void CopyAttributes(vtkDataSetAttributes* in, vtkDataSetAttributes* out,
  const std::vector<int>& kept, const char* name);

/// Set the cells of `grid` to the tets `tets` (4 point ids each, VTK_TETRA).
void SetTets(vtkUnstructuredGrid* grid, const std::vector<int>& tets);

/// Name the 3 components of a colour-channel array "R", "G", "B" (ParaView
/// shows them instead of X, Y, Z). Every RGB array of the filters' outputs
/// gets them; vectors (Normals) keep X, Y, Z.
void SetRGBComponentNames(vtkDataArray* array);

/// A new vtkDoubleArray named `name` with 3 components (R, G, B: see
/// SetRGBComponentNames) holding `values`.
vtkDataArray* NewTripleArray(const char* name, const std::vector<double>& values);

/**
 * The core mesh (topology included) of `grid`, built once and shared: the
 * filters of one pipeline pass shallow copies of the same vtkPoints and
 * vtkCellArray downstream, so vtkSurfaceIrradiance, vtkSolveDiffusion and
 * vtkOutgoingRadiance get the same object instead of each rebuilding the
 * topology. The key is the identity and modification time of the points and
 * cells; a small process-wide cache (the last 4 meshes) holds them. Returns
 * null and fills `error` if the grid is not a valid tet mesh. `built` tells
 * whether this call built the mesh (false: taken from the cache); `warning`
 * (if given) gets ToTetMesh's warning when this call built the mesh, "" else.
 */
std::shared_ptr<const translucency::TetMesh> AcquireTetMesh(vtkUnstructuredGrid* grid,
  std::string& error, bool* built = nullptr, std::string* warning = nullptr);
}

#endif
