/**
 * @class   vtkFractureTetMesh
 * @brief   Split a tet mesh into pieces, the Voronoi cells of seed points
 * (Documentation/Pipeline.md, "Interactions": Fracture).
 *
 * Each tet goes to the seed nearest its centroid (a tie goes to the seed added
 * first); see translucency::TetFracture. Seeds are given with AddSeedPoint(),
 * or picked among the tet centroids with SetRandomSeeds(n, seed), which then
 * replace the added points (n = 0, the default, uses the added points).
 *
 * The output is a vtkMultiBlockDataSet (chosen over
 * vtkPartitionedDataSetCollection because every ParaView 5.11 view and filter,
 * Merge Blocks included, takes it without an assembly): block k is a
 * vtkUnstructuredGrid, the k-th non-empty piece in seed order, named
 * "piece_<k>" (vtkCompositeDataSet::NAME()), with its own compact points (the
 * input points its tets use, in increasing input id). Each piece is a closed
 * translucent object: its boundary is its own boundary, so it can go through
 * vtkSurfaceIrradiance and vtkSolveDiffusion alone. All cell and point arrays
 * are carried over; the cell array `vtkOriginalCellIds` and the point array
 * `vtkOriginalPointIds` map each piece to the input, composed with the
 * input's own maps if present (a fracture of a cut or of a piece still points
 * at the original mesh). The field data of the input are passed to every
 * piece, plus the int arrays `FracturePiece` (k) and `FractureSeed` (the
 * seed's index).
 *
 * Recombination: vtkAppendFilter with every block as an input (MergePoints
 * off), or ParaView's Merge Blocks; points with the same `vtkOriginalPointIds`
 * are then the same original point: the union of the pieces holds every original tet once,
 * with its original vertices (as original point ids) and its cell values.
 * Testing/Python/TestFracture.py does exactly this.
 *
 * @warning Point arrays computed on the whole mesh (Irradiance, Fluence) are
 * carried over as they are: re-run vtkSurfaceIrradiance and vtkSolveDiffusion
 * on each piece. A piece may have several connected components (a Voronoi
 * cell crossing a thin part of the mesh).
 *
 * @sa vtkStrokeCut vtkAppendFilter
 */
#ifndef vtkFractureTetMesh_h
#define vtkFractureTetMesh_h

#include "TranslucencyFiltersModule.h" // for export macro
#include "vtkMultiBlockDataSetAlgorithm.h"

#include <vector> // for the seed list
#include <string> // for the parallel path

class vtkTranslucencyCommunicator;
struct vtkTranslucencyParallelPlan;

class TRANSLUCENCYFILTERS_EXPORT vtkFractureTetMesh : public vtkMultiBlockDataSetAlgorithm
{
public:
  static vtkFractureTetMesh* New();
  vtkTypeMacro(vtkFractureTetMesh, vtkMultiBlockDataSetAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /// Seed points (world coordinates, mm). Default none: with no seed and no
  /// random seeds the update is an error.
  void AddSeedPoint(double x, double y, double z);
  void RemoveAllSeedPoints();
  int GetNumberOfSeedPoints() const { return static_cast<int>(this->SeedPoints.size() / 3); }
  ///@}

  /**
   * Use `count` seeds picked among the tet centroids, reproducibly from
   * `seed`, instead of the added points. count = 0 (default) turns it off.
   */
  void SetRandomSeeds(int count, int seed);
  vtkGetMacro(NumberOfRandomSeeds, int);
  vtkGetMacro(RandomSeed, int);

  /// Number of pieces of the last update (non-empty Voronoi cells).
  vtkGetMacro(NumberOfPieces, int);

  ///@{
  /**
   * The parallel seam (Documentation/Parallel.md, "What runs where").
   * GetParallelPath(): the path the last execution took: "serial" (one
   * process), "per piece", "distributed" or "gathered".
   * GetParallelPlan(): the plan this filter declares for more than one MPI
   * process, with its reason ("per piece: ..."); set by every execution, a
   * one-process one included ("" before the first).
   */
  const char* GetParallelPath() const { return this->ParallelPath.c_str(); }
  const char* GetParallelPlan() const { return this->ParallelPlan.c_str(); }
  ///@}

protected:
  vtkFractureTetMesh();
  ~vtkFractureTetMesh() override = default;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  /// Empties the outputs before anything upstream runs, so that a failure
  /// upstream leaves them empty (vtkTranslucencyDispatch::UpdateExtent).
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  friend struct vtkTranslucencyDispatchAccess; // RunFilter, UpdateExtent
  /// The plan for more than one process (vtkTranslucencyDispatch: called on
  /// every rank; collective over `comm`).
  vtkTranslucencyParallelPlan PlanParallel(
    vtkInformationVector** inputVector, const vtkTranslucencyCommunicator& comm);
  /// The serial path (one process, or rank 0 of a gathered run).
  int RequestSerial(vtkInformation*, vtkInformationVector**, vtkInformationVector*);
  std::string ParallelPath = "serial";
  std::string ParallelPlan;

  std::vector<double> SeedPoints;
  int NumberOfRandomSeeds = 0;
  int RandomSeed = 0;
  int NumberOfPieces = 0;

private:
  vtkFractureTetMesh(const vtkFractureTetMesh&) = delete;
  void operator=(const vtkFractureTetMesh&) = delete;
};

#endif
