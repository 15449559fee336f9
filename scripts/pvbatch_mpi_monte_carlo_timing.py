"""Solve Diffusion's Monte Carlo under `mpiexec -n N pvbatch --symmetric` (the
photons split over the ranks on a replicated mesh) against one pvbatch
process on the same tets (issue 32; Documentation/Parallel.md, "The Monte
Carlo over the ranks", and Scaling.md).

    OMP_NUM_THREADS=2 pvbatch --symmetric scripts/pvbatch_mpi_monte_carlo_timing.py \\
        PLUGIN MESH PHOTONS out1.json
    mpiexec --allow-run-as-root -n 2 pvbatch --symmetric \\
        scripts/pvbatch_mpi_monte_carlo_timing.py PLUGIN MESH PHOTONS out2.json

The build's Python package must be on PYTHONPATH (build/lib/python3.11/
site-packages). MESH: a .vtu (one process) or a .pvtu of N pieces (one per rank). The chain:
reader -> Assign (marble) -> Surface Irradiance (the default lights) ->
Solve Diffusion (montecarlo, PHOTONS per channel, seed 1). The upstream
filters are updated first; then the Solve is timed RUNS times (env
TRANSLUCENCY_MPI_RUNS, default 3; a new seed each time, so each run traces
again) as one collective UpdatePipeline, between barriers. Every rank writes
its own peak resident memory (getrusage) to out.json.rank<r>; rank 0 writes
the wall times, their median, the plan and path, and the photons traced.
TRANSLUCENCY_MPI_DISTRIBUTED_SOLVE=0 (env): DistributedSolve off, the Monte
Carlo gathered to rank 0 (the path before), for a before/after in one build.
"""

import json
import os
import resource
import statistics
import sys
import time


def main():
    from paraview.simple import (LoadPlugin, XMLUnstructuredGridReader,
                                 XMLPartitionedUnstructuredGridReader)
    from vtkmodules.vtkParallelCore import vtkMultiProcessController
    plugin, mesh, photons, out = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
    runs = int(os.environ.get("TRANSLUCENCY_MPI_RUNS", "3"))
    LoadPlugin(plugin, ns=globals())
    import translucency  # noqa: F401  (the getters of Solve Diffusion: PYTHONPATH)
    controller = vtkMultiProcessController.GetGlobalController()
    rank, ranks = controller.GetLocalProcessId(), controller.GetNumberOfProcesses()
    if mesh.endswith(".pvtu"):
        reader = XMLPartitionedUnstructuredGridReader(FileName=[mesh])
    else:
        reader = XMLUnstructuredGridReader(FileName=[mesh])
    assign = AssignScatteringCoefficients(Input=reader, MaterialName="marble")  # noqa: F821
    lit = SurfaceIrradiance(Input=assign)  # noqa: F821
    solve = SolveDiffusion(Input=lit, Solver="montecarlo",  # noqa: F821
                           NumberOfPhotons=photons, Seed=1,
                           DistributedSolve=int(os.environ.get("TRANSLUCENCY_MPI_DISTRIBUTED_SOLVE",
                                                               "1")))
    lit.UpdatePipeline()
    walls = []
    for run in range(runs):
        solve.Seed = run + 1
        controller.Barrier()
        start = time.perf_counter()
        solve.UpdatePipeline()
        controller.Barrier()
        walls.append(time.perf_counter() - start)
    o = solve.GetClientSideObject()
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    # The last run's stages on this rank (s): the mesh conversion, the Monte
    # Carlo's set-up (walk structure, lights, launch tables) and its tracing.
    with open("%s.rank%d" % (out, rank), "w") as f:
        json.dump({"rank": rank, "peak_rss_mb": peak_mb,
                   "points": o.GetOutput().GetNumberOfPoints(),
                   "topology": o.GetTopologyTime(), "setup": o.GetAssemblyTime(),
                   "trace": o.GetSolveTime()}, f)
    if rank == 0:
        with open(out, "w") as f:
            json.dump({"ranks": ranks, "photons": photons, "walls": walls,
                       "median": statistics.median(walls), "plan": o.GetParallelPlan(),
                       "path": o.GetParallelPath()}, f, indent=1)
        print("ranks %d median %.3f s walls %s path %s" % (
            ranks, statistics.median(walls), " ".join("%.3f" % w for w in walls),
            o.GetParallelPath()), flush=True)


main()
