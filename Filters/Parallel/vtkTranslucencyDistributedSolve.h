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
 * sources, listed pencil beams and detectors included; no modulation, time
 * gates or extended collimated model; the interactive pencil beam is aimed by
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
#include "DiffusionSolver.h" // for translucency::SolverReport

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
   * Collective. Solve on this rank's piece `input` with the registry's
   * distributed variant of `solver` (trait Distributed: "divergence" or
   * "fem"), through translucency::DiffusionFrontEnd on the controller's
   * communicator; fluence gets 3 values per input point. `sources` (may be
   * null) are the interior sources, `detectors` read into `readings` (the
   * same on every rank). A solve that does not converge, also after a full
   * set-up, fails unless `acceptUnconverged`. Returns false with `error`
   * (the same on every rank) on failure.
   */
  bool Solve(vtkUnstructuredGrid* input, const std::string& solver, double relTol,
    int maxIter, bool warmStart, int threads, bool acceptUnconverged,
    const translucency::Sources* sources,
    const std::vector<translucency::Detector>& detectors, std::vector<double>& fluence,
    std::vector<translucency::DetectorReading>& readings, translucency::SolverReport& report,
    std::string& error);

  /**
   * The power balance of the last successful Solve over the whole
   * distributed mesh (W per channel, the same on every rank; computed
   * collectively inside Solve, so this call communicates nothing):
   * injected = boundary irradiance of the physical faces + interior
   * sources. False before a successful Solve.
   */
  bool GetPowerBalance(double injected[3], double absorbed[3], double escaped[3]) const;

private:
  struct Impl;
  std::unique_ptr<Impl> Internal;
};

#endif
