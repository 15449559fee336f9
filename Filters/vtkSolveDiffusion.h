/**
 * @class   vtkSolveDiffusion
 * @brief   Solve the light diffusion equation on a heterogeneous tet mesh.
 *
 * Reads the cell arrays `AbsorptionCoefficient`, `ReducedScatteringCoefficient`
 * (3 components, 1/mm) and `RefractiveIndex`, and the point array
 * `Irradiance` (q, 3 components, W/mm^2; only boundary points are read) of its
 * input, assembles the discrete-divergence system of the TransCut paper
 * (Sec. 3, eq. 10-14) for the three colour channels on one sparsity pattern,
 * solves each channel by Jacobi-preconditioned conjugate gradient, and adds
 * the point array `Fluence` (phi, 3 components, W/mm^2) to a shallow copy of
 * the input. A script may supply its own `Irradiance` instead of running
 * vtkSurfaceIrradiance.
 *
 * The filter keeps its mesh topology while the input geometry is unchanged
 * and, with WarmStart on, starts each solve from the previous fluence
 * (relighting, painting).
 *
 * @warning A solve that does not reach RelTol within MaxIter iterations is
 * not an error: the filter warns with the channel, iterations and residual,
 * and GetConverged(channel) returns false.
 *
 * @sa vtkSurfaceIrradiance vtkOutgoingRadiance vtkAssignScatteringCoefficients
 */
#ifndef vtkSolveDiffusion_h
#define vtkSolveDiffusion_h

#include "TranslucencyFiltersModule.h" // for export macro
#include "vtkUnstructuredGridAlgorithm.h"

#include <memory>

class TRANSLUCENCYFILTERS_EXPORT vtkSolveDiffusion : public vtkUnstructuredGridAlgorithm
{
public:
  static vtkSolveDiffusion* New();
  vtkTypeMacro(vtkSolveDiffusion, vtkUnstructuredGridAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /// Relative residual ||b - M phi|| / ||b|| to reach per channel. Default 1e-6.
  vtkSetClampMacro(RelTol, double, 1e-16, 1.0);
  vtkGetMacro(RelTol, double);
  ///@}

  ///@{
  /// Iteration limit per channel. Default 2000.
  vtkSetClampMacro(MaxIter, int, 1, VTK_INT_MAX);
  vtkGetMacro(MaxIter, int);
  ///@}

  ///@{
  /// Start from the previous solution when the mesh is unchanged (default on).
  vtkSetMacro(WarmStart, bool);
  vtkGetMacro(WarmStart, bool);
  vtkBooleanMacro(WarmStart, bool);
  ///@}

  ///@{
  /// OpenMP threads for assembly (0 = OpenMP's default). Default 0.
  vtkSetClampMacro(NumberOfThreads, int, 0, 1024);
  vtkGetMacro(NumberOfThreads, int);
  ///@}

  ///@{
  /// Statistics of the last solve, per channel c in 0..2 (R, G, B).
  int GetNumberOfIterations(int channel) const;
  double GetFinalResidual(int channel) const;
  bool GetConverged(int channel) const;
  ///@}

  ///@{
  /// Wall times of the last execution (ms): topology (0 if reused: the
  /// topology is shared with the other filters of the pipeline through a
  /// cache keyed by the input's points and cells), assembly, solve.
  double GetTopologyTime() const { return this->TopologyTime; }
  double GetAssemblyTime() const { return this->AssemblyTime; }
  double GetSolveTime() const { return this->SolveTime; }
  ///@}

  /// Name of the discretisation ("divergence").
  const char* GetSolverName() const;

protected:
  vtkSolveDiffusion();
  ~vtkSolveDiffusion() override;

  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  double RelTol = 1e-6;
  int MaxIter = 2000;
  bool WarmStart = true;
  int NumberOfThreads = 0;
  double TopologyTime = 0.0;
  double AssemblyTime = 0.0;
  double SolveTime = 0.0;

private:
  vtkSolveDiffusion(const vtkSolveDiffusion&) = delete;
  void operator=(const vtkSolveDiffusion&) = delete;

  struct Internals;
  std::unique_ptr<Internals> Internal;
};

#endif
