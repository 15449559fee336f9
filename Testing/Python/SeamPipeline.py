"""The pvbatch side of TestParallelSeam.py: every filter's plan under MPI, the
gathered Solve Diffusion that deadlocked (issue 32 item 2), and every
filter's and reader's failure modes (issue 32 item 3).

    mpiexec -n N pvbatch --symmetric SeamPipeline.py <plugin> <work dir> run
    mpiexec -n N pvbatch --symmetric SeamPipeline.py <plugin> <work dir> failures

<work dir>/sphere.ply is the surface (written by TestParallelSeam.py). Each
rank writes <mode>_<rank>.txt, one line per case:

run:
    plan <filter> path=<path>|plan=<plan>
        for the 11 public filters (Surface Reader -> Tetrahedralize Surface ->
        Redistribute DataSet -> Assign -> Surface Irradiance -> Solve Diffusion
        -> Outgoing Radiance, Detector Readings; Paint, Stroke Cut, Fracture,
        Translucent Radiosity and Inverse Diffusion on that chain);
    solve <case> path=<path>|plan=<plan>|diff=<max relative Fluence difference
        from the distributed solve on this rank's piece>|points=<n>
        for TRANSLUCENCY_PARALLEL=gathered, the deprecated
        TRANSLUCENCY_GATHERED_SOLVE=1 (gathered, against the distributed
        solve), and the extended collimated model with DistributedSolve on
        (distributed, against DistributedSolve off: gathered);
failures:
    fail <case> <the filter's last error on this rank, or NONE>
        each filter's failure mode, a missing file for the Surface Reader and
        an unknown TRANSLUCENCY_PARALLEL; every rank must end and agree.
Each file ends with "done".
"""

import os
import re
import sys

from paraview.simple import *  # noqa: F401,F403

PLUGIN, WORK, MODE = sys.argv[1], sys.argv[2], sys.argv[3]
LoadPlugin(PLUGIN, ns=globals())

import numpy as np  # noqa: E402
import translucency  # noqa: E402,F401  (the getters of the filters)
from vtkmodules.util.misc import calldata_type  # noqa: E402
from vtkmodules.util.numpy_support import vtk_to_numpy  # noqa: E402
from vtkmodules.util.vtkConstants import VTK_STRING  # noqa: E402
from vtkmodules.vtkParallelCore import vtkMultiProcessController  # noqa: E402

RANK = vtkMultiProcessController.GetGlobalController().GetLocalProcessId()
LOG = open(os.path.join(WORK, "%s_%d.txt" % (MODE, RANK)), "w")
LIGHT = [0.0, -1.0, -1.0, 1.0]


def line(*words):
    LOG.write(" ".join(str(w) for w in words) + "\n")
    LOG.flush()


def watch(proxy):
    """The filter's error messages (bodies), collected by an observer."""
    caught = []

    @calldata_type(VTK_STRING)
    def on_error(obj, event, message):
        if "returned failure" in message:
            return  # the executive's note, with per-process request times
        body = message.split("): ", 1)[-1]
        caught.append(" ".join(re.sub(r"0x[0-9a-fA-F]+", "0x", body).split()))

    algorithm = proxy.GetClientSideObject()
    algorithm.AddObserver("ErrorEvent", on_error)
    algorithm.GetExecutive().AddObserver("ErrorEvent", on_error)
    return caught


def mesh_chain():
    reader = TranslucencySurfaceReader(FileName=os.path.join(WORK, "sphere.ply"))
    # 3,000 tets (the proxy's default is 200,000): the plans, the agreed errors
    # and the gathered-vs-distributed equality do not depend on the size.
    tets = TetrahedralizeSurface(Input=reader, TargetNumberOfTets=3000)
    spread = RedistributeDataSet(Input=tets)
    return reader, tets, spread


def fluence(proxy):
    data = proxy.GetClientSideObject().GetOutput()
    array = data.GetPointData().GetArray("Fluence")
    return None if array is None else vtk_to_numpy(array).copy()


def difference(a, b):
    if a is None or b is None or a.shape != b.shape:
        return "missing"
    if a.size == 0:
        return "0"
    scale = max(np.abs(b).max(), 1e-300)
    return "%.3g" % (np.abs(a - b).max() / scale)


if MODE == "run":
    reader, tets, spread = mesh_chain()
    assigned = AssignScatteringCoefficients(Input=spread)
    # The surface model (CollimatedModel=0); the extended model below.
    lit = SurfaceIrradiance(Input=assigned, DirectionalLights=LIGHT, CollimatedModel=0)
    solved = SolveDiffusion(Input=lit, RelTol=1e-10, MaxIter=20000)
    radiance = OutgoingRadiance(Input=solved)
    detected = SolveDiffusion(Input=lit, RelTol=1e-10, MaxIter=20000,
                              Detectors=[0.0, 0.0, 4.0, 0.0])
    readings = DetectorReadings(Input=detected)
    painted = PaintScatteringCoefficients(Input=assigned, StrokePoints=[0.0, 0.0, 0.0])
    cut = StrokeCut(Input=assigned, CutType="Plane")
    cut.CutType.Origin = [0.0, 0.0, 0.0]
    cut.CutType.Normal = [1.0, 0.0, 0.0]
    fractured = FractureTetMesh(Input=assigned, SeedPoints=[1.0, 0.0, 0.0, -1.0, 0.0, 0.0])
    scene = GroupDatasets(Input=[solved])
    radiosity = TranslucentRadiosity(Input=scene)
    inverse = InverseDiffusion(Input=solved)
    filters = [("TetrahedralizeSurface", tets), ("AssignScatteringCoefficients", assigned),
               ("SurfaceIrradiance", lit), ("SolveDiffusion", solved),
               ("OutgoingRadiance", radiance), ("DetectorReadings", readings),
               ("PaintScatteringCoefficients", painted), ("StrokeCut", cut),
               ("FractureTetMesh", fractured), ("TranslucentRadiosity", radiosity),
               ("InverseDiffusion", inverse)]
    for name, proxy in filters:
        caught = watch(proxy)  # the filters that cannot run on this input fail quietly
        proxy.UpdatePipeline()
        o = proxy.GetClientSideObject()
        line("plan", name, "path=%s|plan=%s" % (o.GetParallelPath(), o.GetParallelPlan()))
        print("rank %d %s: %s (%s)" % (RANK, name, o.GetParallelPath(), o.GetParallelPlan()),
              flush=True)
    reference = fluence(solved)

    def gathered_case(case, variable, value):
        os.environ[variable] = value
        try:
            g = SolveDiffusion(Input=lit, RelTol=1e-10, MaxIter=20000)
            g.UpdatePipeline()
        finally:
            os.environ.pop(variable, None)
        o = g.GetClientSideObject()
        f = fluence(g)
        line("solve", case, "path=%s|plan=%s|diff=%s|points=%d" % (
            o.GetParallelPath(), o.GetParallelPlan(), difference(f, reference),
            0 if f is None else f.shape[0]))

    gathered_case("override", "TRANSLUCENCY_PARALLEL", "gathered")
    gathered_case("deprecated", "TRANSLUCENCY_GATHERED_SOLVE", "1")
    # The extended collimated model: distributed with DistributedSolve on
    # (the beam cast against the all-gathered boundary), gathered with it off
    # (which once hung: a collective on rank 0 alone inside the gathered run).
    extended = SurfaceIrradiance(Input=assigned, DirectionalLights=LIGHT, CollimatedModel=1)
    on = SolveDiffusion(Input=extended, RelTol=1e-10, MaxIter=20000, DistributedSolve=1)
    off = SolveDiffusion(Input=extended, RelTol=1e-10, MaxIter=20000, DistributedSolve=0)
    on.UpdatePipeline()
    off.UpdatePipeline()
    o = on.GetClientSideObject()
    f = fluence(on)
    line("solve", "collimated", "path=%s|plan=%s|diff=%s|points=%d" % (
        o.GetParallelPath(), o.GetParallelPlan(), difference(f, fluence(off)),
        0 if f is None else f.shape[0]))
elif MODE == "failures":
    reader, tets, spread = mesh_chain()
    assigned = AssignScatteringCoefficients(Input=spread)
    lit = SurfaceIrradiance(Input=assigned, DirectionalLights=LIGHT)
    removed = StrokeCut(Input=assigned, CutType="Plane")
    removed.CutType.Origin = [100.0, 0.0, 0.0]  # everything on the removed side
    removed.CutType.Normal = [-1.0, 0.0, 0.0]
    cases = [
        ("reader_missing", TranslucencySurfaceReader(FileName=os.path.join(WORK, "missing.ply")),
         None),
        ("tetrahedralize_mesher", TetrahedralizeSurface(Input=reader, Mesher="nosuch"), None),
        ("assign_material", AssignScatteringCoefficients(Input=spread, MaterialName="nosuch"),
         None),
        ("paint_no_material", PaintScatteringCoefficients(Input=spread, StrokePoints=[0, 0, 0]),
         None),
        ("irradiance_no_eta", SurfaceIrradiance(Input=spread, DirectionalLights=LIGHT), None),
        ("solve_no_irradiance", SolveDiffusion(Input=assigned), None),
        ("radiance_no_fluence", OutgoingRadiance(Input=lit), None),
        ("cut_empty", StrokeCut(Input=removed), None),
        ("fracture_no_seeds", FractureTetMesh(Input=assigned), None),
        ("radiosity_no_material", TranslucentRadiosity(Input=GroupDatasets(Input=[spread])), None),
        ("inverse_no_measurements", InverseDiffusion(Input=assigned), None),
        ("detectors_no_readings", DetectorReadings(Input=assigned), None),
        ("override_unknown", AssignScatteringCoefficients(Input=spread),
         ("TRANSLUCENCY_PARALLEL", "sometimes")),
    ]
    for case, proxy, environment in cases:
        if environment:
            os.environ[environment[0]] = environment[1]
        caught = watch(proxy)
        try:
            proxy.UpdatePipeline()
        finally:
            if environment:
                os.environ.pop(environment[0], None)
        line("fail", case, caught[-1] if caught else "NONE")
        print("rank %d %s: %s" % (RANK, case, caught[-1] if caught else "NONE"), flush=True)
else:
    sys.exit("mode must be run or failures, not " + MODE)
line("done")
