/**
 * @class   vtkSolveDiffusion
 * @brief   Solve the light diffusion equation on a heterogeneous tet mesh.
 *
 * Reads the cell arrays `AbsorptionCoefficient`, `ReducedScatteringCoefficient`
 * (3 components, 1/mm) and `RefractiveIndex`, and the point array
 * `Irradiance` (q, 3 components, W/mm^2; only boundary points are read) of its
 * input, solves for the three colour channels with the selected solver and
 * adds the point array `Fluence` (phi, 3 components, W/mm^2) to a shallow copy
 * of the input. A script may supply its own `Irradiance` instead of running
 * vtkSurfaceIrradiance.
 *
 * Solvers (all give fluence at the mesh points, so they compare point by point):
 *  - SOLVER_DIVERGENCE ("divergence", default): the TransCut discrete
 *    divergence (paper Sec. 3, eq. 10-14) + Jacobi-preconditioned CG;
 *  - SOLVER_FEM ("fem"): consistent linear Galerkin (the Arbree et al. role);
 *  - SOLVER_QUADGRAPH ("quadgraph"): finite differences on the tet dual graph;
 *  - SOLVER_GRID ("grid"): regular-grid finite differences of spacing GridSpacing;
 *  - SOLVER_MONTECARLO ("montecarlo"): a photon random walk, the ground truth.
 *    It needs the lights, which vtkSurfaceIrradiance records in the field data
 *    (`TranslucencyLights`); it adds `FluenceStandardError`,
 *    `MonteCarloRadiance` and `MonteCarloRadianceStandardError` point arrays.
 *  - SOLVER_SP3 ("sp3"): the simplified spherical harmonics SP3 equations
 *    (Klose & Larsen 2006) at the vertices, with Anisotropy g; continuous wave
 *    and ModulationFrequency (its own exitance for the detectors, amplitude and
 *    phase). In continuous wave it adds the point arrays `SP3Phi1`, `SP3Phi2`
 *    (its composite moments, W/mm^2), from which vtkOutgoingRadiance reads the
 *    P3 radiance instead of eq. 3.
 *
 * The mesh topology is shared with the other filters of the pipeline, and with
 * WarmStart on, an iterative solve starts from the previous solution when the
 * unknowns are unchanged (relighting, painting).
 *
 * Incremental assembly after a paint (TransCut Sec. 5.2; divergence and fem
 * solvers, IncrementalAssembly on; done by translucency::DiffusionFrontEnd,
 * which the filter calls): the front end keeps the
 * coefficients and the irradiance of its last successful solve (7 doubles
 * per tet and 3 per point). When the next input has the same mesh (same
 * topology and points), the same irradiance, and at most
 * MaximumChangedFraction of the tets have a different mu_a, sigma_s' or eta
 * (compared bit for bit with that copy, so any upstream change is seen, not
 * only vtkPaintScatteringCoefficients'), only the matrix rows of the vertices
 * of the changed tets are rebuilt (the result equals a full assembly), and the
 * solve warm-starts from the previous fluence. GetLastAssembly() tells which
 * path was taken ("incremental" or "full"). Discretisations without an
 * incremental update (fem) always assemble in full.
 *
 * Diffuse optics (divergence and fem solvers; Documentation/DiffuseOptics.md):
 *  - interior sources, with every solver (quadgraph and grid in continuous
 *    wave only): isotropic point sources (AddPointSource) and pencil
 *    beams (AddPencilBeam: the Farrell et al. 1992 equivalent source one
 *    transport mean free path below the entry point), in W per channel, on
 *    top of the boundary irradiance (give an all-zero `Irradiance`, e.g.
 *    vtkSurfaceIrradiance with DefaultLights off, for sources alone);
 *  - detectors on the surface (AddDetector, optional fibre radius; with
 *    every solver: quadgraph and grid read them from their vertex Fluence,
 *    continuous wave only): fluence and exitance per channel, read with GetDetectorFluence() and
 *    GetDetectorExitance() and attached as field arrays `DetectorPosition`
 *    (the surface point), `DetectorFluence`, `DetectorExitance` (3
 *    components, W/mm^2, one tuple per detector);
 *  - frequency domain (ModulationFrequency > 0): the complex diffusion
 *    equation; point arrays `FluenceAmplitude`, `FluencePhase` (radians,
 *    arg of the complex fluence: negative = lagging the source) and
 *    `Fluence` = the amplitude; the detectors read amplitudes and also give
 *    `DetectorFluencePhase`, `DetectorExitancePhase`;
 *  - time-resolved (SetTimeGates(T0, T1, N), N > 0): the response to a
 *    pulse at t = 0 of the sources (energy P J for a power P) and of the
 *    irradiance, averaged over N equal gates covering [T0, T1] ns, by
 *    implicit time stepping (translucency::TimeGates); `Fluence` is then the
 *    time integral over [T0, T1] (J/mm^2: the continuous-wave fluence when
 *    the gates cover the whole response), the detector readings are the
 *    time integrals too, and the field arrays `TimeGateCentres` (ns, one
 *    tuple per gate), `DetectorFluenceTPSF<k>` and `DetectorExitanceTPSF<k>`
 *    (k = 0, 1, ...: 3 components, one tuple per gate, J/(mm^2 ns)) hold the
 *    temporal point-spread functions; AddTimeSnapshot(g) adds the point
 *    array `FluenceGate<g>` (the gate-averaged fluence, J/(mm^2 ns));
 *  - collimated beams as an extended source: when the input's field data
 *    has `TranslucencyCollimatedModel` = 1 (vtkSurfaceIrradiance's
 *    CollimatedModel extended), the directional lights of
 *    `TranslucencyLights` enter as the unscattered beam E_c and its volume
 *    source mu_s' E_c; `Fluence` is then phi_d + E_c and the point array
 *    `CollimatedFluence` holds E_c (the detectors and vtkOutgoingRadiance
 *    read phi_d = Fluence - CollimatedFluence). With a ModulationFrequency
 *    the beam is modulated with its delay, exp(-i omega eta s / c):
 *    `CollimatedFluence` is its amplitude, `CollimatedFluencePhase` its
 *    phase (rad), `Fluence` = |Phi_d| + E_c (FluenceAmplitude/Phase: of the
 *    total); with TimeGates it is a delayed pulse per point (the integrals
 *    include E_c where it arrives within [T0, T1]). Quadgraph and grid
 *    refuse it; Monte Carlo (transport) ignores it.
 * A source outside the object, a pencil beam pointing out of the surface, a
 * detector off the surface, a negative frequency or invalid time gates make
 * RequestData fail with an error naming it; so do sources, a frequency or
 * time gates with the quadgraph, grid or montecarlo solvers, and a frequency
 * together with time gates. The sources need the whole mesh in one piece.
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
#include <string>

class vtkStringArray;

class vtkTranslucencyCommunicator;
struct vtkTranslucencyParallelPlan;

class TRANSLUCENCYFILTERS_EXPORT vtkSolveDiffusion : public vtkUnstructuredGridAlgorithm
{
public:
  static vtkSolveDiffusion* New();
  vtkTypeMacro(vtkSolveDiffusion, vtkUnstructuredGridAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// Indices into translucency::GetDiffusionSolverRegistry() (the one table
  /// of the solvers; a test checks that the orders agree). Scripts use them
  /// with SetSolver(int): keep their values.
  enum Solvers
  {
    SOLVER_DIVERGENCE = 0,
    SOLVER_FEM = 1,
    SOLVER_QUADGRAPH = 2,
    SOLVER_GRID = 3,
    SOLVER_MONTECARLO = 4,
    SOLVER_SP3 = 5
  };

  ///@{
  /// The solver (one of Solvers). Default SOLVER_DIVERGENCE.
  vtkSetClampMacro(Solver, int, SOLVER_DIVERGENCE, SOLVER_SP3);
  vtkGetMacro(Solver, int);
  ///@}

  /**
   * Select the solver by name, one of translucency::GetDiffusionSolverNames()
   * (case-insensitive). An unknown name is an error (reported with the list
   * of names); the solver is then left unchanged and false is returned.
   */
  bool SetSolverByName(const char* name);

  /// Name of the selected solver.
  const char* GetSolverName() const;

  /**
   * The collimated model the last solve used (0 surface,
   * 1 extended, 2 extended-moments; -1 before the first), also written to
   * the output's field data (`TranslucencyCollimatedModel`).
   * vtkSurfaceIrradiance's default model (COLLIMATED_DEFAULT) is decided
   * here, where the pencil beams and the solver are known: divergence and
   * fem solve the core's default table's model for the scene's light kinds
   * (translucency::DefaultCollimatedModel, measured against Monte Carlo;
   * Documentation/DiffuseOptics.md), the other solvers the surface model.
   * For an extended model the directional lights' q is taken out of the
   * irradiance of the solve, and the output's `Irradiance` is that of the
   * solve (what vtkOutgoingRadiance reads). Under MPI a default choice is
   * decided as in one process and an extended model is solved on the
   * distributed path (the beam cast against the all-gathered boundary;
   * Documentation/Parallel.md): the same model and field as one process.
   */
  int GetSolvedCollimatedModel() const { return this->SolvedCollimatedModel; }

  ///@{
  /**
   * Iterative solvers: relative residual ||b - M phi|| / ||b|| to reach per
   * channel. Default 1e-2, the interactive stopping rule: the boundary
   * fluence within 1 % of the converged solution, cold and warm-started
   * (translucency::InteractiveRelTol, Documentation/Solvers.md). While
   * RelTol is at least this default, the multigrid-agg solve also stops a
   * channel once its boundary fluence stops changing (estimated error <=
   * translucency::InteractiveChangeTol, 0.3 %). Set it (e.g. 1e-10) for a
   * tighter, residual-only solve.
   */
  vtkSetClampMacro(RelTol, double, 1e-16, 1.0);
  vtkGetMacro(RelTol, double);
  /// The default RelTol: translucency::InteractiveRelTol.
  static double GetInteractiveRelTol();
  ///@}

  ///@{
  /// Iteration limit per channel. Default 2000.
  vtkSetClampMacro(MaxIter, int, 1, VTK_INT_MAX);
  vtkGetMacro(MaxIter, int);
  ///@}

  ///@{
  /**
   * A solve that does not converge (RelTol within MaxIter) is done again in
   * the same execution after a full set-up (a new hierarchy, a full
   * assembly, no warm start); if it still does not converge, RequestData
   * fails with an error naming each channel's residual and iterations and
   * the output is empty, on every rank under MPI (translucency::
   * DiffusionFrontEnd). AcceptUnconverged (default off) keeps the
   * unconverged field with a warning instead: for convergence studies only
   * (translucency compare's error against time stops solves early on
   * purpose), never for a result. Not in the plugin.
   */
  vtkSetMacro(AcceptUnconverged, bool);
  vtkGetMacro(AcceptUnconverged, bool);
  vtkBooleanMacro(AcceptUnconverged, bool);
  ///@}

  ///@{
  /// Start from the previous solution when the unknowns are unchanged (default on).
  vtkSetMacro(WarmStart, bool);
  vtkGetMacro(WarmStart, bool);
  vtkBooleanMacro(WarmStart, bool);
  ///@}

  ///@{
  /// Grid solver: voxel spacing h (mm). Default 0 = chosen from the mesh.
  /// This and the other solver-specific settings (MultiLevel,
  /// NumberOfPhotons, Seed) reach the solver through its options hook
  /// (translucency::DiffusionSolver::SetOptions): the selected solver reads
  /// its own, the others are ignored; an invalid value makes RequestData
  /// fail with an error naming it.
  vtkSetMacro(GridSpacing, double);
  vtkGetMacro(GridSpacing, double);
  ///@}

  ///@{
  /// Monte Carlo: number of photons (default 1e6) and random seed (default 1).
  vtkSetMacro(NumberOfPhotons, vtkTypeInt64);
  vtkGetMacro(NumberOfPhotons, vtkTypeInt64);
  vtkSetClampMacro(Seed, int, 0, VTK_INT_MAX);
  vtkGetMacro(Seed, int);
  ///@}

  ///@{
  /// Monte Carlo: Henyey-Greenstein mean cosine g in (-1, 1) (default 0:
  /// isotropic scattering with mu_s = mu_s'); mu_s = mu_s' / (1 - g), so the
  /// reduced scattering coefficient stays the material's. SP3: the same g
  /// in every tet and channel (OpticalProperties::Anisotropy). The diffusion
  /// solvers ignore it (with a warning when it is not 0): g is already
  /// folded into mu_s'. A value outside (-1, 1) makes RequestData fail.
  vtkSetMacro(Anisotropy, double);
  vtkGetMacro(Anisotropy, double);
  ///@}

  ///@{
  /// Linear solver by name; "" or "default" (default "") = the chosen
  /// solver's default. The names each solver accepts are its registry
  /// entry's (translucency::GetAcceptedLinearSolvers, GetLinearSolverTable):
  /// discrete divergence and FEM every solver of symmetric positive definite
  /// systems this build has (translucency::GetLinearSolverNames(); by
  /// default "cg-jacobi" below 20,000 unknowns, "multigrid-agg" above:
  /// VertexDiffusionSolver::GetDefaultLinearSolverName(int)); QuadGraph and
  /// grid "bicgstab" (default) or "relaxation"; SP3 "bicgstab" or
  /// "multigrid-agg"; Monte Carlo ignores it. Any other name makes
  /// RequestData fail with an error naming the solver and what it accepts.
  vtkSetStdStringFromCharMacro(LinearSolver);
  vtkGetCharFromStdStringMacro(LinearSolver);
  ///@}

  /// Every name LinearSolver accepts in this build, for the plugin's
  /// drop-down: "default", then translucency::GetLinearSolverNames()
  /// (divergence, fem; optional libraries only when built), then
  /// translucency::GetNonSymmetricLinearSolverNames() (quadgraph, grid).
  /// The array is owned by the filter.
  vtkStringArray* GetAvailableLinearSolvers();

  /// The linear solvers each solver accepts, as pairs (solver name, linear
  /// solver name) in registry order: the plugin's Linear Solver drop-down
  /// lists "default" and the chosen Solver's names (its decorator
  /// pqTranslucencyLinearSolverDecorator). The array is owned by the filter.
  vtkStringArray* GetLinearSolverTable();

  ///@{
  /// QuadGraph and grid: coarse-to-fine initialisation (default off).
  vtkSetMacro(MultiLevel, bool);
  vtkGetMacro(MultiLevel, bool);
  vtkBooleanMacro(MultiLevel, bool);
  ///@}

  ///@{
  /// QuadGraph only, NOT the paper's scheme (default off): two-point
  /// finite-volume link weights kappa_ij S_ij / (V_i d_ij) instead of eq. 5's
  /// 1 / d_ij^2; conserves light on graded meshes
  /// (translucency::QuadGraphSolver::SetTwoPointFlux, Documentation/Solvers.md).
  vtkSetMacro(QuadGraphTwoPointFlux, bool);
  vtkGetMacro(QuadGraphTwoPointFlux, bool);
  vtkBooleanMacro(QuadGraphTwoPointFlux, bool);
  ///@}

  ///@{
  /// OpenMP threads for the discrete-divergence assembly (0 = OpenMP's default).
  vtkSetClampMacro(NumberOfThreads, int, 0, 1024);
  vtkGetMacro(NumberOfThreads, int);
  ///@}

  ///@{
  /// Rebuild only the rows of the tets whose coefficients changed since the
  /// last solve (see the class documentation). Default on.
  vtkSetMacro(IncrementalAssembly, bool);
  vtkGetMacro(IncrementalAssembly, bool);
  vtkBooleanMacro(IncrementalAssembly, bool);
  ///@}

  ///@{
  /// Largest fraction of changed tets for which the update is incremental
  /// (the row update is serial; beyond this a parallel full assembly is
  /// faster). Default 0.05.
  vtkSetClampMacro(MaximumChangedFraction, double, 0.0, 1.0);
  vtkGetMacro(MaximumChangedFraction, double);
  ///@}

  ///@{
  /// Interior sources (every solver), W per channel (>= 0), positions
  /// and directions in mm. A pencil beam enters at (x, y, z), on the
  /// surface, travelling along (dx, dy, dz) into the object. None by
  /// default.
  void AddPointSource(double x, double y, double z, double powerR, double powerG, double powerB);
  void AddPencilBeam(double x, double y, double z, double dx, double dy, double dz,
    double powerR, double powerG, double powerB);
  void RemoveAllSources();
  /// Remove one kind only (the plugin's PointSources and PencilBeams
  /// properties each clear their own).
  void RemoveAllPointSources();
  void RemoveAllPencilBeams();
  int GetNumberOfSources() const;
  ///@}

  ///@{
  /// Detectors on the surface: a point (radius 0) or a fibre face of the
  /// given radius (mm), read after each solve. None by default.
  void AddDetector(double x, double y, double z, double radius);
  void RemoveAllDetectors();
  int GetNumberOfDetectors() const;
  ///@}

  ///@{
  /**
   * The plugin's interactive sources (ParaView's handle and line widgets),
   * added to the listed sources while on. Both are off by default.
   *
   * Interactive point source: an isotropic point source at
   * InteractivePointSourcePosition (mm, inside the object; default the
   * origin) of power InteractivePointSourcePower (W per channel R, G, B;
   * default 1, 1, 1).
   *
   * Interactive pencil beam: a beam that starts at
   * InteractivePencilBeamPoint1 (mm, outside the object) and travels towards
   * InteractivePencilBeamPoint2; it enters where that ray first hits the
   * surface (translucency::AimPencilBeam), and is then the same pencil beam
   * as AddPencilBeam(entry, Point2 - Point1, power). Power
   * InteractivePencilBeamPower (W per channel; default 1, 1, 1). Coinciding
   * points, a ray that misses the object and a Point 1 inside the object
   * make RequestData fail with an error naming them.
   */
  vtkSetMacro(InteractivePointSource, bool);
  vtkGetMacro(InteractivePointSource, bool);
  vtkBooleanMacro(InteractivePointSource, bool);
  vtkSetVector3Macro(InteractivePointSourcePosition, double);
  vtkGetVector3Macro(InteractivePointSourcePosition, double);
  vtkSetVector3Macro(InteractivePointSourcePower, double);
  vtkGetVector3Macro(InteractivePointSourcePower, double);
  vtkSetMacro(InteractivePencilBeam, bool);
  vtkGetMacro(InteractivePencilBeam, bool);
  vtkBooleanMacro(InteractivePencilBeam, bool);
  vtkSetVector3Macro(InteractivePencilBeamPoint1, double);
  vtkGetVector3Macro(InteractivePencilBeamPoint1, double);
  vtkSetVector3Macro(InteractivePencilBeamPoint2, double);
  vtkGetVector3Macro(InteractivePencilBeamPoint2, double);
  vtkSetVector3Macro(InteractivePencilBeamPower, double);
  vtkGetVector3Macro(InteractivePencilBeamPower, double);
  /// The entry point (mm) of the interactive pencil beam in the last
  /// execution; (0, 0, 0) when it was off or failed. Under MPI: on every
  /// rank with the distributed solve, on rank 0 with the gathered one.
  vtkGetVector3Macro(InteractivePencilBeamEntry, double);
  ///@}

  ///@{
  /**
   * The plugin's interactive detector (ParaView's handle widget), read
   * after the listed detectors while on (off by default): a detector of
   * radius InteractiveDetectorRadius (mm, >= 0; default 0, a point) at the
   * surface point closest to InteractiveDetectorPosition (mm; anywhere,
   * inside or outside the object: it is projected, as a listed detector's
   * position is, but without the listed detectors' distance limit). Its
   * readings are detector index GetNumberOfDetectors() (the last row of the
   * detector field arrays); DetectorRequestedPosition holds the handle's
   * position, DetectorPosition the surface point. Under MPI a solve with it
   * on is gathered to rank 0 (the closest point over the whole surface).
   */
  vtkSetMacro(InteractiveDetector, bool);
  vtkGetMacro(InteractiveDetector, bool);
  vtkBooleanMacro(InteractiveDetector, bool);
  vtkSetVector3Macro(InteractiveDetectorPosition, double);
  vtkGetVector3Macro(InteractiveDetectorPosition, double);
  vtkSetMacro(InteractiveDetectorRadius, double);
  vtkGetMacro(InteractiveDetectorRadius, double);
  /// The surface point (mm) the interactive detector read in the last
  /// execution; (0, 0, 0) when it was off or failed.
  vtkGetVector3Macro(InteractiveDetectorSurfacePosition, double);
  ///@}

  ///@{
  /// Readings of the last solve for detector k, channel c (0 if out of
  /// range): fluence and exitance (W/mm^2; amplitudes in the frequency
  /// domain), their phases (radians; 0 for a continuous-wave solve), and the
  /// surface point read (mm).
  double GetDetectorFluence(int detector, int channel) const;
  double GetDetectorExitance(int detector, int channel) const;
  double GetDetectorFluencePhase(int detector, int channel) const;
  double GetDetectorExitancePhase(int detector, int channel) const;
  void GetDetectorSurfacePosition(int detector, double position[3]) const;

  /**
   * Power balance of the last solve, per channel R, G, B (W): `injected` =
   * the boundary irradiance integrated over the surface plus the interior
   * sources' power, `absorbed` = integral of mu_a Fluence over the object,
   * `escaped` = integral of the exitance (Fluence - 2 q)/(2 A) over the
   * surface (P1 integrals; translucency::ComputePowerBalance). For the
   * divergence and fem solvers absorbed + escaped = injected to solver
   * tolerance; for the others the gap measures how far they are from
   * conserving light in this discretisation. After a montecarlo solve the
   * photons' own tallies (MonteCarloSolver::GetPowerBalance: launched,
   * absorbed and escaped weight), whose gap is the Russian roulette's
   * zero-mean gain (a statistical error). Computed on demand from the
   * output (nothing is spent when it is not asked for); on the distributed
   * MPI path (GetParallelPath() "distributed") it is the whole object's
   * balance, summed over the ranks during the collective solve (physical
   * faces only), the same on every rank, so calling it on one rank alone
   * is safe. Returns false, with
   * an error, when there is no steady-state solution (never solved, failed,
   * or frequency domain).
   */
  bool ComputePowerBalance(double injected[3], double absorbed[3], double escaped[3]);

  /**
   * The model-range warning of the last execution, empty when the material
   * is in the diffusion model's range (translucency::CheckModelRange:
   * transport albedo mu_s'/(mu_a + mu_s') below 0.9 on more than 1 % of the
   * volume). Also issued as a VTK warning whenever it changes. Empty for the
   * montecarlo solver.
   */
  const char* GetModelRangeWarning() const { return this->ModelRangeWarning.c_str(); }

  /**
   * A note when the mesh is coarse for the material: the tets under more
   * than 1 % of the surface are larger than 3 transport mean free paths
   * 1/(mu_a + mu_s'), so the lit boundary layer is not resolved. Not a VTK
   * warning (small meshes for a first look are common); the CLI prints it.
   */
  const char* GetMeshResolutionNote() const { return this->MeshResolutionNote.c_str(); }
  ///@}

  ///@{
  /// Modulation frequency f (Hz) of the sources and the irradiance: 0 (the
  /// default) solves the continuous-wave equation; f > 0 the frequency-
  /// domain equation with absorption mu_a + i 2 pi f eta / c (divergence and
  /// fem only). A negative or non-finite value makes RequestData fail.
  vtkSetMacro(ModulationFrequency, double);
  vtkGetMacro(ModulationFrequency, double);
  ///@}

  ///@{
  /// Under MPI with more than one process: solve the divergence and fem
  /// systems distributed, each rank assembling its own tets into one hypre
  /// BoomerAMG-PCG system (Documentation/Parallel.md), instead of gathering
  /// the mesh to rank 0. Default on. Off (or the environment variable
  /// TRANSLUCENCY_GATHERED_SOLVE=1) gathers, as do a modulation frequency,
  /// time gates, the other solvers and builds without hypre (point sources,
  /// listed and interactive pencil beams, detectors and the extended
  /// collimated models are distributed). The distributed path always uses hypre's BoomerAMG-PCG
  /// (LinearSolver, IncrementalAssembly and NumberOfThreads' effect on the
  /// solve do not apply). The montecarlo solver, on: the mesh is replicated
  /// on every rank and the photons split over the ranks (the one-process
  /// estimates up to the order of the additions; every rank holds the
  /// one-process memory, so when the ranks of a node would not fit in its
  /// available memory, or TRANSLUCENCY_REPLICATED_MEMORY GiB, rank 0 traces
  /// alone and GetParallelPlan() says why); off: it runs on rank 0 alone.
  vtkSetMacro(DistributedSolve, bool);
  vtkGetMacro(DistributedSolve, bool);
  vtkBooleanMacro(DistributedSolve, bool);
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

  ///@{
  /// Time gates: N gates covering [T0, T1] ns (T0 >= 0, T1 > T0, N in
  /// 1..10000); N = 0 (the default) solves the continuous-wave (or
  /// frequency-domain) equation. Invalid values make RequestData fail.
  void SetTimeGates(double t0, double t1, int n);
  /// The same with N as a double (the ParaView panel's property): a value
  /// that is not a whole number makes RequestData fail naming it.
  void SetTimeGatesFromPanel(double t0, double t1, double n);
  double GetTimeGatesStart() const { return this->TimeGatesStart; }
  double GetTimeGatesEnd() const { return this->TimeGatesEnd; }
  int GetTimeGatesCount() const { return this->TimeGatesCount; }
  ///@}

  ///@{
  /// Time steps per gate, 1..1000, or 0 (the default) for automatic: 4, or
  /// more where mu_a c_m dt would exceed 0.05 (translucency::TimeGates).
  vtkSetClampMacro(TimeStepsPerGate, int, 0, 1000);
  vtkGetMacro(TimeStepsPerGate, int);
  ///@}

  ///@{
  /// Gates (0-based) whose gate-averaged fluence is added as the point array
  /// `FluenceGate<g>`. None by default; a gate >= N is an error.
  void AddTimeSnapshot(int gate);
  void RemoveAllTimeSnapshots();
  /// The plugin's Time Snapshots table (a one-column DoubleVectorProperty:
  /// ParaView 5.11 shows the label of such a table, not of an integer one):
  /// a whole number adds that gate; any other value makes RequestData fail
  /// with an error naming it.
  void AddTimeSnapshotFromPanel(double gate);
  ///@}

  ///@{
  /// Time-resolved results of the last solve: the gate centres (ns), the
  /// steps per gate used, and detector k's gate-averaged fluence and
  /// exitance in gate g, channel c (J/(mm^2 ns) per J of pulse; 0 if out of
  /// range).
  int GetNumberOfTimeGates() const;
  double GetTimeGateCentre(int gate) const;
  int GetTimeStepsPerGateUsed() const;
  double GetDetectorFluenceTPSF(int detector, int gate, int channel) const;
  double GetDetectorExitanceTPSF(int detector, int gate, int channel) const;
  ///@}

  /// How the last vertex solve (divergence, fem) built its system: "full",
  /// "incremental" (the rows of the changed tets) or "right-hand side" (a
  /// relight: same material, only the load rebuilt); the distributed path:
  /// "full" or "unchanged" (matrix
  /// values as in the last solve on every rank, e.g. a relight: the hypre
  /// hierarchies kept); empty for the other solvers and before the first solve.
  const char* GetLastAssembly() const;

  /// What the last serial vertex solve's linear solver set-up did: "rebuilt",
  /// "values", "rows" (a paint: the touched rows) or "kept" (a relight: the
  /// multigrid hierarchy kept); translucency::SolverReport::LinearSetup.
  const char* GetLastLinearSetup() const;

  /// What the last serial vertex solve's extended collimated source did
  /// (translucency::SolverReport::Collimated): "full" (new rays and every
  /// tet integrated: a new light direction or mesh), "loads" (the kept rays,
  /// the changed tets integrated again: a paint) or "kept"; empty without an
  /// extended model.
  const char* GetLastCollimatedUpdate() const;

  /// Tets found changed for the last incremental update (-1 if the filter
  /// did not look: no cached coefficients, new mesh, too many changes, or
  /// IncrementalAssembly off).
  vtkIdType GetNumberOfChangedTets() const;

  /// Executions that copied and validated the coefficient arrays
  /// (AbsorptionCoefficient, ReducedScatteringCoefficient, RefractiveIndex)
  /// since construction (under MPI: of this rank's piece). An execution whose
  /// input carries the same arrays, unmodified (VTK modification time), as
  /// the last successful solve on the same mesh (a relight) reuses the
  /// material kept from it instead; a paint stroke in one process compares
  /// the new arrays with it in place (GetNumberOfMaterialComparisons).
  vtkTypeInt64 GetNumberOfMaterialConversions() const;
  /// Serial solves that compared the material tet by tet with the last one
  /// (to find the tets a paint changed) since construction.
  vtkTypeInt64 GetNumberOfMaterialComparisons() const;
  /// Distributed solves (this rank) that reused the last irradiance without
  /// the directional lights' (the default collimated model) because the
  /// piece, its RefractiveIndex and Irradiance arrays and the lights were
  /// the same on every rank (a paint), since construction.
  vtkTypeInt64 GetNumberOfBeamIrradianceReuses() const;

  ///@{
  /// Statistics of the last solve, per channel c in 0..2 (R, G, B).
  int GetNumberOfIterations(int channel) const;
  double GetFinalResidual(int channel) const;
  bool GetConverged(int channel) const;
  ///@}

  /// The linear solver the last solve used (e.g. "cg-jacobi", "bicgstab",
  /// "relaxation"; "photons" for Monte Carlo). Empty before the first solve.
  const char* GetLinearSolverUsed() const;

  ///@{
  /// Size of the last system: unknowns and nonzeros per channel, memory (bytes).
  vtkTypeInt64 GetNumberOfUnknowns() const;
  vtkTypeInt64 GetNumberOfNonZeros() const;
  vtkTypeInt64 GetMemoryBytes() const;
  ///@}

  ///@{
  /// Wall times of the last execution (ms): topology (0 if reused: the
  /// topology is shared with the other filters of the pipeline through a
  /// cache keyed by the input's points and cells), set-up (assembly), solve.
  double GetTopologyTime() const { return this->TopologyTime; }
  double GetAssemblyTime() const { return this->AssemblyTime; }
  double GetSolveTime() const { return this->SolveTime; }
  ///@}

protected:
  vtkSolveDiffusion();
  ~vtkSolveDiffusion() override;

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
  /// The distributed path (vtkTranslucencyDistributedSolve), on every rank.
  int RequestDistributed(vtkInformationVector** inputVector, vtkInformationVector* outputVector);

  int Solver = SOLVER_DIVERGENCE;
  double RelTol = 1e-2; // translucency::InteractiveRelTol (checked by a test)
  int MaxIter = 2000;
  bool WarmStart = true;
  bool AcceptUnconverged = false;
  double GridSpacing = 0.0;
  vtkTypeInt64 NumberOfPhotons = 1000000;
  int Seed = 1;
  double Anisotropy = 0.0;
  std::string LinearSolver;
  std::string ModelRangeWarning;
  std::string MeshResolutionNote;
  bool MultiLevel = false;
  bool QuadGraphTwoPointFlux = false;
  int NumberOfThreads = 0;
  bool IncrementalAssembly = true;
  double MaximumChangedFraction = 0.05;
  double ModulationFrequency = 0.0;
  bool DistributedSolve = true;
  double TimeGatesStart = 0.0;
  double TimeGatesEnd = 0.0;
  int TimeGatesCount = 0;
  double TimeGatesCountText = 0.0; ///< N as given to SetTimeGatesFromPanel
  int TimeStepsPerGate = 0;
  // The plugin's interactive sources (widgets).
  bool InteractivePointSource = false;
  double InteractivePointSourcePosition[3] = { 0.0, 0.0, 0.0 };
  double InteractivePointSourcePower[3] = { 1.0, 1.0, 1.0 };
  bool InteractivePencilBeam = false;
  int SolvedCollimatedModel = -1;
  double InteractivePencilBeamPoint1[3] = { 0.0, 0.0, 1.0 };
  double InteractivePencilBeamPoint2[3] = { 0.0, 0.0, 0.0 };
  double InteractivePencilBeamPower[3] = { 1.0, 1.0, 1.0 };
  double InteractivePencilBeamEntry[3] = { 0.0, 0.0, 0.0 };
  bool InteractiveDetector = false;
  double InteractiveDetectorPosition[3] = { 0.0, 0.0, 0.0 };
  double InteractiveDetectorRadius = 0.0;
  double InteractiveDetectorSurfacePosition[3] = { 0.0, 0.0, 0.0 };

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
