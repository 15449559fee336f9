/**
 * @file   vtkTranslucencyDistributedSolve.h
 * @brief  vtkSolveDiffusion's distributed path under MPI: each rank's piece
 *         is solved in place by the core's front end (DiffusionFrontEnd) with
 *         the registry's distributed variant of the solver (trait Distributed:
 *         translucency::DistributedVertexSolver, hypre BoomerAMG-PCG on the
 *         global controller's communicator), instead of
 *         being gathered to rank 0 (vtkTranslucencyParallel::RunGathered).
 *
 * Used for the divergence and fem solvers in continuous wave (point
 * sources, listed pencil beams, detectors and the extended collimated models
 * included: the beam's rays cast against the all-gathered physical boundary,
 * translucency::DistributedCollimatedSource; no modulation or time gates;
 * the interactive pencil beam is aimed by
 * vtkSolveDiffusion on the all-gathered surface and arrives as a listed beam), when vtkSolveDiffusion's plan says
 * "distributed" (vtkTranslucencyDispatch: every rank takes part, a rank with
 * an empty piece too). A build without hypre or without VTK's ParallelMPI
 * module has no distributed path (vtkTranslucency::CanDistribute).
 *
 * The piece: its owned cells (cells flagged vtkGhostType DUPLICATECELL are
 * left out) must be linear tets; points are identified across ranks by the
 * point GlobalIds when every rank with points has them, else by exactly
 * equal coordinates (as the gathered path).
 */
#ifndef vtkTranslucencyDistributedSolve_h
#define vtkTranslucencyDistributedSolve_h

#include "Detectors.h"       // for translucency::Detector, DetectorReading, Sources
#include "DiffusionSolver.h" // for translucency::SolverReport, DiffusionProblem

#include <memory>
#include <string>
#include <vector>

class vtkUnstructuredGrid;

class vtkTranslucencyDistributedSolve
{
public:
  vtkTranslucencyDistributedSolve();
  ~vtkTranslucencyDistributedSolve();

  /**
   * Collective: the lights, uniform irradiance, shadow flag and collimated
   * model of `problem` and `flag` as the lowest rank with cells has them
   * (translucency::AgreeOnLights: an empty piece may carry no field data), on
   * every rank. Nothing to agree with one process.
   */
  static void AgreeOnLights(
    vtkUnstructuredGrid* input, translucency::DiffusionProblem& problem, int& flag);

  /**
   * Collective. Solve on this rank's piece `input` with the registry's
   * distributed variant of `solver` (trait Distributed: "divergence" or
   * "fem"), through translucency::DiffusionFrontEnd on the controller's
   * communicator, with relTol and the change rule's changeTol
   * (DiffusionSolver::SetChangeTol: vtkSolveDiffusion's interactive rule, as
   * the serial solve gets it); fluence gets 3 values per input point. `sources` (may be
   * null) are the interior sources, `detectors` read into `readings` (the
   * same on every rank). A solve that does not converge, also after a full
   * set-up, fails unless `acceptUnconverged`. `lights` (AgreeOnLights:
   * the same on every rank): Lights, Shadows and Collimated of the solve; with
   * an extended model the directional lights enter as the beam's volume
   * source. `takeOutBeams` (the default model's choice, vtkSolveDiffusion):
   * the input's Irradiance holds every light, and the directional lights'
   * projected irradiance (vtkTranslucencyDistributedIrradiance, the serial
   * ComputeProjectedIrradiance at this rank's points) is taken out of it
   * before the solve, as the serial filter does; `solvedIrradiance` then gets
   * the irradiance solved with (3 per input point; else left empty). Returns
   * false with `error` (the same on every rank) on failure.
   */
  bool Solve(vtkUnstructuredGrid* input, const std::string& solver, double relTol,
    double changeTol, int maxIter, bool warmStart, int threads, bool acceptUnconverged,
    const translucency::Sources* sources,
    const std::vector<translucency::Detector>& detectors,
    const translucency::DiffusionProblem& lights, bool takeOutBeams, std::vector<double>& fluence,
    std::vector<double>& solvedIrradiance, std::vector<translucency::DetectorReading>& readings,
    translucency::SolverReport& report, std::string& error);

  /**
   * The power balance of the last successful Solve over the whole
   * distributed mesh (W per channel, the same on every rank; computed
   * collectively inside Solve, so this call communicates nothing):
   * injected = boundary irradiance of the physical faces + interior
   * sources. False before a successful Solve.
   */
  bool GetPowerBalance(double injected[3], double absorbed[3], double escaped[3]) const;

  /// Solves that read this rank's coefficient arrays since construction (a
  /// relight on the same piece with the same arrays, unmodified, solves the
  /// front end's kept material instead).
  long long GetNumberOfMaterialConversions() const;
  /// Solves that took the directional lights' irradiance out of the default
  /// model's Irradiance by reusing the last result (a paint: the same
  /// piece, RefractiveIndex and Irradiance arrays and lights on every rank).
  long long GetNumberOfBeamIrradianceReuses() const;

private:
  struct Impl;
  std::unique_ptr<Impl> Internal;
};

#endif
