/**
 * @class   vtkOutgoingRadiance
 * @brief   Boundary surface of a solved tet mesh with its outgoing radiance.
 *
 * Extracts the boundary triangles of the input tetrahedral mesh (outward
 * oriented) as a vtkPolyData and evaluates, at every surface point,
 * L_o(x, w_o) = F_t(w_o)/(4 pi eta^2) [ (1 + 1/A) phi(x) - 4/(1 + Fdr) q(x) ]
 * (TransCut eq. 3, after Arbree et al., with the n^2 law that conserves
 * energy; SetRadianceReadoutToPaper() drops the 1/eta^2 as the paper prints
 * it) from the input's point arrays
 * `Fluence` (phi) and `Irradiance` (q) and the cell array `RefractiveIndex`.
 * After an sp3 solve (point arrays `SP3Phi1`, `SP3Phi2`) it evaluates the
 * outgoing P3 radiance of those moments instead
 * (translucency::Sp3OutgoingRadiance; Documentation/Solvers.md, "SP3").
 *
 * Output point data: `Radiance` (3 components, W/mm^2/sr, linear, not tone
 * mapped; clamped below at 0 where eq. 3 would go negative, which happens under
 * strong direct light on meshes too coarse to resolve the fluence near the
 * surface), `Fluence`, `Irradiance`, `Normals` (outward unit normals) and
 * `vtkOriginalPointIds` (ids in the tet mesh), and `RadianceRGB`: the
 * display colours (unsigned char, R, G, B) of Exposure x Radiance, clamped
 * and sRGB-encoded (translucency/Physics/ToneMap.h), the mapping of the
 * CLI's `render --png`: colour by it with Map Scalars off to see the
 * translucent object as the CLI renders it. The field array
 * `RadianceExposure` holds the exposure used.
 *
 * The outgoing direction w_o is the surface normal by default (F_t at normal
 * exit); with UseViewPoint on, it points from each surface point to the
 * ViewPoint (a camera position), and points facing away get 0.
 *
 * Under MPI (the global controller runs more than one MPI process) each
 * rank outputs the physical boundary faces of its own tets, no gather: a
 * face shared with a tet of another rank is not boundary; a point's normal
 * and refractive index sum the faces of every rank around it, so every
 * value equals the serial one and a point on the seam between two ranks'
 * faces is output by both with the same values. `vtkOriginalPointIds` are
 * then ids in the rank's piece, and the automatic exposure is the serial
 * one (every boundary point once). TRANSLUCENCY_GATHERED_RADIANCE=1 (every
 * rank) gathers to rank 0 instead (the whole surface there). See
 * Documentation/Parallel.md.
 *
 * @sa vtkSolveDiffusion vtkSurfaceIrradiance
 */
#ifndef vtkOutgoingRadiance_h
#define vtkOutgoingRadiance_h

#include "vtkPolyDataAlgorithm.h"
#include "TranslucencyFiltersModule.h" // for export macro

#include <memory>
#include <string> // for the parallel path

class vtkTranslucencyCommunicator;
struct vtkTranslucencyParallelPlan;

class TRANSLUCENCYFILTERS_EXPORT vtkOutgoingRadiance : public vtkPolyDataAlgorithm
{
public:
  static vtkOutgoingRadiance* New();
  vtkTypeMacro(vtkOutgoingRadiance, vtkPolyDataAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /// Evaluate F_t towards ViewPoint instead of along the normal (default off).
  vtkSetMacro(UseViewPoint, bool);
  vtkGetMacro(UseViewPoint, bool);
  vtkBooleanMacro(UseViewPoint, bool);
  ///@}

  /// The read-outs (translucency::RadianceReadout, in the same order).
  enum Readout
  {
    ENERGY_CONSERVING = 0, ///< eq. 3 / eta^2 (the n^2 law): conserves energy
    PAPER = 1              ///< TransCut eq. 3 as printed: eta^2 times too much light
  };

  ///@{
  /**
   * Which read-out evaluates the radiance. ENERGY_CONSERVING (the default)
   * divides eq. 3 by eta^2, the n^2 law for radiance leaving a denser medium:
   * a non-absorbing object emits the power it receives, and the Monte Carlo
   * reference agrees with it. PAPER is eq. 3 as printed (it omits the 1/eta^2
   * and so emits 1.69x the power received at eta = 1.3): use it only to
   * reproduce TransCut's figures.
   */
  vtkSetClampMacro(RadianceReadout, int, ENERGY_CONSERVING, PAPER);
  vtkGetMacro(RadianceReadout, int);
  void SetRadianceReadoutToEnergyConserving() { this->SetRadianceReadout(ENERGY_CONSERVING); }
  void SetRadianceReadoutToPaper() { this->SetRadianceReadout(PAPER); }
  ///@}

  ///@{
  /**
   * The earlier switch of the same choice, kept for scripts: on =
   * ENERGY_CONSERVING (now the default), off = PAPER.
   */
  void SetNSquaredLaw(bool on) { this->SetRadianceReadout(on ? ENERGY_CONSERVING : PAPER); }
  bool GetNSquaredLaw() const { return this->RadianceReadout == ENERGY_CONSERVING; }
  void NSquaredLawOn() { this->SetNSquaredLaw(true); }
  void NSquaredLawOff() { this->SetNSquaredLaw(false); }
  ///@}

  ///@{
  /**
   * Multiplier of the radiance (sr mm^2/W) before display for `RadianceRGB`.
   * 0 (default) = automatic: 0.9 / the 99th percentile of the per-point
   * brightest channel, as the CLI's --exposure default.
   */
  vtkSetClampMacro(Exposure, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(Exposure, double);
  ///@}

  /// The exposure of the last execution (Exposure, or the automatic one).
  double GetExposureUsed() const { return this->ExposureUsed; }

  ///@{
  /// Camera position (mm) used when UseViewPoint is on. Default (0, 0, 0).
  vtkSetVector3Macro(ViewPoint, double);
  vtkGetVector3Macro(ViewPoint, double);
  ///@}

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

  /// After a per-piece execution: the physical boundary faces over every rank.
  long long GetNumberOfSurfaceTriangles() const { return this->NumberOfSurfaceTriangles; }

protected:
  vtkOutgoingRadiance();
  ~vtkOutgoingRadiance() override;

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

  bool UseViewPoint = false;
  int RadianceReadout = ENERGY_CONSERVING;
  double ViewPoint[3] = { 0.0, 0.0, 0.0 };
  double Exposure = 0.0;
  double ExposureUsed = 1.0;
  long long NumberOfSurfaceTriangles = 0;

private:
  /// The per-piece path under MPI (vtkTranslucencyDistributedRadiance).
  int RequestPerPiece(vtkInformationVector** inputVector, vtkInformationVector* outputVector,
    const vtkTranslucencyCommunicator& comm);

  vtkOutgoingRadiance(const vtkOutgoingRadiance&) = delete;
  void operator=(const vtkOutgoingRadiance&) = delete;

  struct Internals;
  std::unique_ptr<Internals> Internal;
};

#endif
