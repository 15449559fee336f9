/**
 * @class   vtkTetrahedralizeSurface
 * @brief   Fill a closed triangle surface with quality tetrahedra (TetGen).
 *
 * vtkTetrahedralizeSurface takes a vtkPolyData holding a closed, manifold,
 * non-degenerate triangle surface (lengths in mm) and produces a
 * vtkUnstructuredGrid of linear tetrahedra filling it, using TetGen 1.5 with
 * a radius-edge quality bound and either a maximum tet volume or a target
 * number of tets. The output points and tets are put in a spatial (Morton)
 * order, which makes the downstream assembly and solves cache-friendly.
 *
 * The input is checked before TetGen sees it; the error names the problem:
 * a non-finite coordinate or one of magnitude MaxCoordinate (1e15 mm) or
 * more, a point id out of range or an inconsistent cell array (these first,
 * before any VTK filter touches the data), empty input, a non-triangle cell, a degenerate (zero-area) triangle, an
 * edge used by one triangle (the surface is open; the count and the first
 * edge's position are given) or by more than two (non-manifold), a flat
 * surface enclosing no volume, and triangles crossing each other
 * (self-intersection, found by a TetGen -d pass, because TetGen 1.5.0 crashes
 * instead of reporting it when meshing).
 *
 * @warning TetGen is single-threaded: about 6 s for a million tets. With a
 * target number of tets, TetGen may run twice (the second run corrects the
 * volume bound from the first run's count). TetGen's count is not a smooth
 * function of the bound: for large targets (1e5 and up on the bunny) the result
 * is within about 20 % of the target; small targets are bounded below by the
 * resolution of the input surface and can be off by 50 % or more.
 *
 * @sa vtkAssignScatteringCoefficients vtkSolveDiffusion
 */
#ifndef vtkTetrahedralizeSurface_h
#define vtkTetrahedralizeSurface_h

#include "TranslucencyFiltersModule.h" // for export macro
#include "vtkUnstructuredGridAlgorithm.h"

class TRANSLUCENCYFILTERS_EXPORT vtkTetrahedralizeSurface : public vtkUnstructuredGridAlgorithm
{
public:
  static vtkTetrahedralizeSurface* New();
  vtkTypeMacro(vtkTetrahedralizeSurface, vtkUnstructuredGridAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// The largest coordinate magnitude accepted (mm): 1e15 mm (a million km)
  /// is far beyond any object while leaving TetGen's predicates and the
  /// squared lengths of the checks far from overflow.
  static constexpr double MaxCoordinate = 1e15;

  ///@{
  /**
   * Upper bound on the radius-edge ratio of every tet (TetGen -q). Must be
   * >= 1.1 (TetGen may not terminate below); default 1.414.
   */
  vtkSetClampMacro(Quality, double, 1.1, 100.0);
  vtkGetMacro(Quality, double);
  ///@}

  ///@{
  /**
   * Maximum volume of a tet in mm^3 (TetGen -a). 0 (default) means no bound
   * (unless a target number of tets is set).
   */
  vtkSetClampMacro(MaxTetVolume, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(MaxTetVolume, double);
  ///@}

  ///@{
  /**
   * Aim for about this many tets (0 = off, the default). When set it takes
   * precedence over MaxTetVolume.
   */
  vtkSetClampMacro(TargetNumberOfTets, vtkIdType, 0, VTK_ID_MAX);
  vtkGetMacro(TargetNumberOfTets, vtkIdType);
  ///@}

  ///@{
  /**
   * Memory limit in GiB (default 0: translucency::GetDefaultMemoryLimit(),
   * 8 GiB unless changed, e.g. by the CLI's --memory-limit). Before TetGen
   * runs, the tet count is estimated (TargetNumberOfTets, or the enclosed
   * volume / MaxTetVolume) at ~400 bytes per tet; above the limit the filter
   * fails with a message stating the count, the bytes and this override.
   */
  vtkSetClampMacro(MemoryLimit, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(MemoryLimit, double);
  ///@}

  ///@{
  /**
   * Reorder points and tets along a Morton curve (default on).
   */
  vtkSetMacro(SpatialReordering, bool);
  vtkGetMacro(SpatialReordering, bool);
  vtkBooleanMacro(SpatialReordering, bool);
  ///@}

protected:
  vtkTetrahedralizeSurface();
  ~vtkTetrahedralizeSurface() override = default;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  double Quality = 1.414;
  double MaxTetVolume = 0.0;
  vtkIdType TargetNumberOfTets = 0;
  double MemoryLimit = 0.0;
  bool SpatialReordering = true;

private:
  vtkTetrahedralizeSurface(const vtkTetrahedralizeSurface&) = delete;
  void operator=(const vtkTetrahedralizeSurface&) = delete;
};

#endif
