"""The issue-31 chain under `mpiexec -n N pvbatch` against serial pvbatch on
the same tets (issues 31 and 32; Documentation/Performance.md and Scaling.md).

    OMP_NUM_THREADS=2 pvbatch scripts/pvbatch_mpi_chain_timing.py PLUGIN bunny1m.vtu out.json
    mpiexec --allow-run-as-root -n 2 pvbatch scripts/pvbatch_mpi_chain_timing.py \\
        PLUGIN bunny1m.vtu out2.json
    /usr/bin/python3 scripts/pvbatch_mpi_chain_timing.py --table out.json out2.json

1. The mesh: serial pvbatch reads the .vtu itself. Under N ranks the N-piece
   bunny1m-N.pvtu next to it is read (XML partitioned reader: one piece per
   rank); if it does not exist it is made first, once: the .vtu read on rank
   0, Redistribute DataSet (N pieces, each cell on one rank) and written as
   .pvtu (never overwritten). Both runs hold the same tets.
2. The chain, each filter's UpdatePipeline timed (on rank 0, a collective
   update): Assign (marble) -> Surface Irradiance (directional (0,-1,-1) +
   the uniform light 0.1) -> Paint Scattering Coefficients (a stroke outside
   the object) -> Solve Diffusion (defaults) -> Outgoing Radiance, as
   *cold*; then *relight* (the directional light turned 15 degrees about x)
   and *paint* (the stroke moved onto the top of the object, width 2.4 % of
   the diagonal), each timed the same way. Repeated RUNS times (default 3,
   env TRANSLUCENCY_MPI_RUNS) on a new chain; medians.
   With the build's Python package on PYTHONPATH (build/lib/python3.11/
   site-packages), Solve Diffusion's own set-up and PCG times (rank 0's
   GetAssemblyTime, GetSolveTime) are recorded too ("solve setup", "solve
   pcg") and its PCG iterations (R/G/B) and what its beam and linear set-up
   did are printed. "cpu" is this process's CPU seconds over the step (every
   thread; under MPI rank 0's only), "cpu irradiance" and "cpu solve" those
   two filters': CPU / wall of serial pvbatch is how many of the machine's
   cores one process already keeps busy, which bounds what N ranks on the
   same cores can gain.
3. Writes the medians (seconds, per step and filter), the ranks and the tets
   to the JSON file. --table prints the Markdown
   table of two or more such files (the first is the baseline).

TRANSLUCENCY_MPI_DISTRIBUTED_SOLVE=0 (env) sets Solve Diffusion's
DistributedSolve off: under MPI its gathered path (the extended collimated
models' path before issue 32's distributed beam), for a before/after in one
build.
"""

import json
import math
import os
import statistics
import sys
import time

STEPS = ("cold", "relight", "paint")
FILTERS = ("assign", "irradiance", "paint", "solve", "radiance")
CPU_FILTERS = ("irradiance", "solve")
CPU = ("cpu",) + tuple("cpu " + f for f in CPU_FILTERS)


def table(paths):
    runs = [json.load(open(p)) for p in paths]
    base = runs[0]
    print("| step | filter | " + " | ".join("%d rank%s (s)" % (r["ranks"], "s" if r["ranks"] > 1 else "")
                                        for r in runs) + " | ratio |")
    print("|---|---|" + "---|" * len(runs) + "---|")
    for step in STEPS:
        for f in FILTERS + ("total",) + CPU + ("solve setup", "solve pcg"):
            values = [r["medians"][step].get(f) for r in runs]
            if any(v is None for v in values):
                continue
            ratio = values[-1] / values[0] if values[0] > 0 else float("nan")
            print("| %s | %s | %s | %.2f |" % (step, f, " | ".join("%.3f" % v for v in values),
                                               ratio))


def main():
    from paraview.simple import (LoadPlugin, XMLUnstructuredGridReader, RedistributeDataSet,
                                 SaveData, XMLPartitionedUnstructuredGridReader, Delete)
    from paraview import servermanager
    plugin, vtu, out = sys.argv[1:4]
    runs = int(os.environ.get("TRANSLUCENCY_MPI_RUNS", "3"))
    distributed = int(os.environ.get("TRANSLUCENCY_MPI_DISTRIBUTED_SOLVE", "1"))
    LoadPlugin(plugin, ns=globals())
    try:
        import translucency  # noqa: F401  (the getters of Solve Diffusion)
        wrapped = True
    except ImportError:
        wrapped = False
    pm = servermanager.vtkProcessModule.GetProcessModule()
    ranks = pm.GetNumberOfLocalPartitions()
    if ranks > 1:
        pvtu = os.path.splitext(vtu)[0] + "-%d.pvtu" % ranks
        if not os.path.exists(pvtu):
            whole = XMLUnstructuredGridReader(FileName=[vtu])
            parts = RedistributeDataSet(Input=whole)
            SaveData(pvtu, proxy=parts)
            Delete(parts)
            Delete(whole)
        reader = XMLPartitionedUnstructuredGridReader(FileName=[pvtu])
    else:
        reader = XMLUnstructuredGridReader(FileName=[vtu])
    reader.UpdatePipeline()
    info = reader.GetDataInformation()
    bounds = info.GetBounds()
    centre = [0.5 * (bounds[2 * k] + bounds[2 * k + 1]) for k in range(3)]
    diag = math.sqrt(sum((bounds[2 * k + 1] - bounds[2 * k]) ** 2 for k in range(3)))

    def key_light(degrees):
        t = math.radians(degrees)
        return [0.0, -math.cos(t) + math.sin(t), -math.sin(t) - math.cos(t), 1.0]

    times = {s: {f: [] for f in FILTERS + ("total",) + CPU + ("solve setup", "solve pcg")} for s in STEPS}
    for run in range(runs):
        assign = AssignScatteringCoefficients(Input=reader, MaterialName="marble")  # noqa: F821
        light = SurfaceIrradiance(Input=assign, DirectionalLights=key_light(0.0),  # noqa: F821
                                  UniformLightIrradiance=0.1)
        paint = PaintScatteringCoefficients(Input=light)  # noqa: F821
        paint.StrokePoints = [bounds[1] + diag, centre[1], centre[2]]
        paint.Width = 0.01 * diag
        solve = SolveDiffusion(Input=paint, DistributedSolve=distributed)  # noqa: F821
        radiance = OutgoingRadiance(Input=solve)  # noqa: F821
        proxies = dict(zip(FILTERS, (assign, light, paint, solve, radiance)))
        for step in STEPS:
            if step == "relight":
                light.DirectionalLights = key_light(15.0)
            if step == "paint":
                paint.StrokePoints = [centre[0], bounds[3], centre[2]]
                paint.Width = 0.024 * diag
            total = 0.0
            cpu = 0.0
            for f in FILTERS:
                start = time.perf_counter()
                cpuStart = time.process_time()
                proxies[f].UpdatePipeline()
                seconds = time.perf_counter() - start
                cpuSeconds = time.process_time() - cpuStart
                cpu += cpuSeconds
                if f in CPU_FILTERS:
                    times[step]["cpu " + f].append(cpuSeconds)
                times[step][f].append(seconds)
                total += seconds
            times[step]["total"].append(total)
            # This process's CPU seconds (every thread; under MPI rank 0's):
            # CPU / wall of one process is how many cores it kept busy.
            times[step]["cpu"].append(cpu)
            # Solve Diffusion's own account (rank 0's filter): set-up
            # (numbering, assembly with the beam, hierarchy) and PCG, and
            # what its beam and linear set-up did.
            # (Needs the build's Python package on PYTHONPATH for the getters.)
            account = ""
            core = solve.GetClientSideObject()
            if wrapped and hasattr(core, "GetAssemblyTime"):
                times[step]["solve setup"].append(core.GetAssemblyTime() / 1000.0)
                times[step]["solve pcg"].append(core.GetSolveTime() / 1000.0)
                account = " (solve: set-up %.3f, pcg %.3f, iterations %s, beam %s, %s)" % (
                    times[step]["solve setup"][-1], times[step]["solve pcg"][-1],
                    "/".join(str(core.GetNumberOfIterations(c)) for c in range(3)),
                    core.GetLastCollimatedUpdate() or "-", core.GetLastLinearSetup() or "-")
            print("run %d %-8s %s total %.3f cpu %.3f%s" % (
                run + 1, step, " ".join("%s %.3f" % (f, times[step][f][-1]) for f in FILTERS),
                total, cpu, account), flush=True)
        for proxy in (radiance, solve, paint, light, assign):
            Delete(proxy)
    for s in STEPS:
        for f in ("solve setup", "solve pcg"):
            if not times[s][f]:
                del times[s][f]
    result = {"ranks": ranks, "tets": info.GetNumberOfCells(), "runs": runs,
              "distributed_solve": distributed,
              "threads": os.environ.get("OMP_NUM_THREADS", ""),
              "medians": {s: {f: statistics.median(v) for f, v in times[s].items()}
                          for s in STEPS}}
    with open(out, "w") as f:
        json.dump(result, f, indent=1)
    print(json.dumps(result["medians"]))


if len(sys.argv) > 1 and sys.argv[1] == "--table":
    table(sys.argv[2:])
else:
    main()
