/**
 * @class   vtkInverseDiffusion
 * @brief   Acquire per-element kappa and mu_a from illumination patterns and
 *          measured outgoing radiance (inverse diffusion, Polygrid, Sec. 4).
 *
 * Input: a tetrahedral vtkUnstructuredGrid (any tet mesh, or a block built by
 * translucency::BuildGridBlock) holding, for each measurement k = 0, 1, ...,
 * M-1 (numbered from 0 without gaps), the point arrays
 *  - `Irradiance_<k>`: incoming light q of pattern k (3 components, W/mm^2,
 *    boundary points; the `Irradiance` array of vtkSurfaceIrradiance),
 *  - `Radiance_<k>`: measured outgoing radiance (3 components, W/mm^2/sr,
 *    read at observed boundary points; TransCut eq. 3 at normal exit),
 *  - optionally `ObservedMask_<k>` (1 component, non-zero = observed), or one
 *    `ObservedMask` for every pattern; without a mask every boundary point is
 *    observed;
 * and the cell array `RefractiveIndex` (optional: DefaultRefractiveIndex
 * otherwise). If ElementArrayName names an integer cell array, tets with the
 * same value share one kappa and mu_a (e.g. the voxels of a grid block);
 * otherwise each tet is its own element.
 *
 * Output port 0: the input mesh with the recovered cell arrays
 * `AbsorptionCoefficient` (mu_a, 3 components, 1/mm), `DiffusionCoefficient`
 * (kappa, 3 components, mm), `ReducedScatteringCoefficient` (sigma_s' =
 * 1/(3 kappa) - mu_a, clamped at 0 with a warning where the fit left it
 * negative), `RefractiveIndex`, and the point arrays `FittedRadiance_<k>`
 * (the forward read-out of the recovered material for each pattern).
 * Output port 1: a vtkTable with one row per iteration and channel: Channel,
 * Stage (0 = homogeneous fit, 1 = heterogeneous), Iteration, Objective,
 * DataTerm, GradientNorm, Step, Evaluations.
 *
 * @warning The optimisation does 2M linear solves per gradient plus ~10 M per
 * line search; see Documentation/InverseDiffusion.md for costs and for the
 * ambiguity of the recovered volume far from the observed surface.
 *
 * @sa translucency::InverseDiffusion vtkSurfaceIrradiance vtkOutgoingRadiance
 */
#ifndef vtkInverseDiffusion_h
#define vtkInverseDiffusion_h

#include "TranslucencyFiltersModule.h" // for export macro
#include "vtkUnstructuredGridAlgorithm.h"

#include <string>

class vtkTranslucencyCommunicator;
struct vtkTranslucencyParallelPlan;

class TRANSLUCENCYFILTERS_EXPORT vtkInverseDiffusion : public vtkUnstructuredGridAlgorithm
{
public:
  static vtkInverseDiffusion* New();
  vtkTypeMacro(vtkInverseDiffusion, vtkUnstructuredGridAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /// Regulariser weight lambda (paper Sec. 4.2). Default 1e-5.
  vtkSetClampMacro(Lambda, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(Lambda, double);
  ///@}

  ///@{
  /// Conjugate-gradient iteration limit per channel. Default 100.
  vtkSetClampMacro(MaxIterations, int, 0, VTK_INT_MAX);
  vtkGetMacro(MaxIterations, int);
  ///@}

  ///@{
  /// Stop when the normalised objective is below this (paper: 1e-4). Default 1e-4.
  vtkSetMacro(RelativeThreshold, double);
  vtkGetMacro(RelativeThreshold, double);
  ///@}

  ///@{
  /// Initial homogeneous guess (R, G, B; 1/mm). Defaults 0.01 and 1.0.
  vtkSetVector3Macro(InitialAbsorption, double);
  vtkGetVector3Macro(InitialAbsorption, double);
  vtkSetVector3Macro(InitialReducedScattering, double);
  vtkGetVector3Macro(InitialReducedScattering, double);
  ///@}

  ///@{
  /// Fit a homogeneous material first (paper Sec. 4.2). Default on.
  vtkSetMacro(HomogeneousFit, bool);
  vtkGetMacro(HomogeneousFit, bool);
  vtkBooleanMacro(HomogeneousFit, bool);
  /// How the homogeneous pair is fitted: GAUSS_NEWTON (default,
  /// Levenberg-Marquardt on tangent solves) or CONJUGATE_GRADIENT (the
  /// paper's CG with golden-section line search).
  enum HomogeneousMethods
  {
    GAUSS_NEWTON = 0,
    CONJUGATE_GRADIENT = 1
  };
  vtkSetClampMacro(HomogeneousMethod, int, GAUSS_NEWTON, CONJUGATE_GRADIENT);
  vtkGetMacro(HomogeneousMethod, int);
  /// Start each golden-section bracket at the Gauss-Newton minimiser along
  /// the search direction (one tangent pass per iteration). Default on.
  vtkSetMacro(GaussNewtonLineSearch, bool);
  vtkGetMacro(GaussNewtonLineSearch, bool);
  vtkBooleanMacro(GaussNewtonLineSearch, bool);
  ///@}

  ///@{
  /// Cell array grouping tets into elements (empty: one element per tet).
  /// Default empty.
  vtkSetStdStringFromCharMacro(ElementArrayName);
  vtkGetCharFromStdStringMacro(ElementArrayName);
  ///@}

  ///@{
  /// Refractive index used when the input has no RefractiveIndex. Default 1.3.
  vtkSetClampMacro(DefaultRefractiveIndex, double, 1e-3, VTK_DOUBLE_MAX);
  vtkGetMacro(DefaultRefractiveIndex, double);
  ///@}

  ///@{
  /// Statistics of the last run: forward passes, adjoint passes, seconds.
  vtkGetMacro(NumberOfEvaluations, int);
  vtkGetMacro(NumberOfGradients, int);
  vtkGetMacro(EvaluationSeconds, double);
  vtkGetMacro(GradientSeconds, double);
  /// Tangent passes (Gauss-Newton steps: one blocked back-solve each).
  vtkGetMacro(NumberOfTangents, int);
  vtkGetMacro(TangentSeconds, double);
  ///@}

  /// The iteration history (output port 1).
  vtkDataObject* GetHistoryOutput() { return this->GetOutputDataObject(1); }

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
  vtkInverseDiffusion();
  ~vtkInverseDiffusion() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int FillOutputPortInformation(int port, vtkInformation* info) override;
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

  double Lambda = 1e-5;
  int MaxIterations = 100;
  double RelativeThreshold = 1e-4;
  double InitialAbsorption[3] = { 0.01, 0.01, 0.01 };
  double InitialReducedScattering[3] = { 1.0, 1.0, 1.0 };
  bool HomogeneousFit = true;
  int HomogeneousMethod = GAUSS_NEWTON;
  bool GaussNewtonLineSearch = true;
  std::string ElementArrayName;
  double DefaultRefractiveIndex = 1.3;
  int NumberOfEvaluations = 0;
  int NumberOfGradients = 0;
  double EvaluationSeconds = 0.0;
  double GradientSeconds = 0.0;
  int NumberOfTangents = 0;
  double TangentSeconds = 0.0;

private:
  vtkInverseDiffusion(const vtkInverseDiffusion&) = delete;
  void operator=(const vtkInverseDiffusion&) = delete;
};

#endif
