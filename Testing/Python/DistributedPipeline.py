"""The pvbatch side of TestDistributedSolve.py: the distributed Solve Diffusion.

    pvbatch DistributedPipeline.py <plugin> <work dir> prepare
    mpiexec -n N pvbatch --symmetric DistributedPipeline.py <plugin> <work dir> run

prepare (one process): a sphere meshed by TetGen with a heterogeneous
material (mu_a, sigma_s' and eta vary with the cell centre, so the boundary
eta averaging and the kappa jumps are exercised) and a plain "PointIds"
array numbering the points (mesh.vtu); the same tets in 2 pieces with a
ghost level (mesh2g.pvtu) and in 3 pieces with the point ids as GlobalIds
(mesh3id.pvtu); the serial references (ref_<light>_<solver>.vtu) for the
divergence and fem solvers and two lights, solved to RelTol 1e-13.

run (every rank runs the script, --symmetric): for each case the chain
reader -> Surface Irradiance -> Solve Diffusion (distributed), saved as
<case>.pvtu, and one line per rank in solves_<rank>.txt
    solve <case> rank <r> path <path> assembly <a> iterations <i,i,i> residuals <r,r,r>
Cases: pvtu3 (GlobalIds; 2 ranks read 3 pieces), pvtu2 (ghost cells; 3
ranks on 2 pieces: a rank with an empty piece), redist (Redistribute
DataSet), fem (fem solver on pvtu3), relight (pvtu3 relit: hierarchy kept),
warm (the relit system again: warm start), gathered (pvtu3 with DistributedSolve off, the gathered path in
the same run), an invalid mu_a on rank 1 only (the same error on every rank),
after_error (a solve after it); src_point (a point source on mesh2g, 3
ranks: an empty piece), src_pencil (a pencil beam on mesh3id) and src_aimed
(the interactive pencil beam, aimed by the line widget's points, on mesh3id), each with
a point and a fibre detector (readings per rank in detectors_<rank>.txt;
serial references ref_<kind>_divergence.vtu and ref_detectors.json); a
point source outside the object (its errors, caught by observers, in
outside_<rank>.txt), src_after_error (a solve after it); mc and mc_tpsf
(the Monte Carlo, continuous wave and time-gated, replicated: the photons
split over the ranks) on mesh3id and, as mc_pvtu2 and mc_tpsf_pvtu2, on
mesh2g (3 ranks: an empty piece), with their detector readings per rank in
mc_<rank>.txt (serial references ref_mc.vtu, ref_mc_tpsf.vtu, ref_mc.json).
"""

import os
import sys

from paraview.simple import *  # noqa: F401,F403

PLUGIN, WORK, MODE = sys.argv[1], sys.argv[2], sys.argv[3]
LoadPlugin(PLUGIN, ns=globals())
TOL = 1e-13
LIGHTS = {"a": [0.0, -1.0, -1.0, 1.0], "b": [1.0, 0.2, -0.5, 2.0]}


def on_sphere(x, y, z):
    n = (x * x + y * y + z * z) ** 0.5
    return [4.0 * x / n, 4.0 * y / n, 4.0 * z / n]


# Interior sources and detectors (issue 18 x 19): a point source, a pencil
# beam entering inside a surface triangle, a point detector and a 1.5 mm fibre.
ENTRY = on_sphere(0.3, 0.2, 0.93)
SOURCES = {"point": {"PointSources": [0.5, -0.7, 1.1, 1.0, 2.0, 0.5]},
           "pencil": {"PencilBeams": ENTRY + [-v for v in ENTRY] + [1.0, 1.0, 2.0]},
           # The interactive pencil beam (the line widget's two points): aimed
           # by a ray cast over the whole (all-gathered) surface.
           "aimed": {"InteractivePencilBeam": 1, "InteractivePencilBeamPoint1": [0.6, 0.4, 9.0],
                     "InteractivePencilBeamPoint2": [0.5, 0.5, 0.0],
                     "InteractivePencilBeamPower": [1.0, 2.0, 1.5]}}
DETECTORS = on_sphere(-0.5, 0.3, 0.8) + [0.0] + on_sphere(0.6, -0.6, -0.5) + [1.5]
# Paint (issue 32): a stroke through the middle with the Paint filter's
# default targets (the ketchup-like absorber), and the same stroke with
# mu_a x 1000.
STROKE = [-3.0, -0.5, 0.2, 3.0, 0.6, -0.2]
PAINTS = {"paint": None, "paint_extreme": [61.0, 970.0, 1450.0]}


def painted(source, target):
    """reader -> Surface Irradiance -> Paint (stroke STROKE) -> Solve Diffusion."""
    lit = SurfaceIrradiance(Input=source, DirectionalLights=LIGHTS["a"], CollimatedModel=0)
    paint = PaintScatteringCoefficients(Input=lit, StrokePoints=STROKE, Width=1.0)
    if target:
        paint.TargetAbsorptionCoefficient = target
    return paint, SolveDiffusion(Input=paint, RelTol=TOL, MaxIter=20000)


# The Monte Carlo (issue 32: the photons split over the ranks on a replicated
# mesh): continuous wave with the two detectors, and time-gated (10 gates of
# 0.2 ns: the detectors' TPSFs).
MONTE_CARLO = {"mc": None, "mc_tpsf": [0.0, 2.0, 10]}


def monte_carlo(source, gates):
    lit = SurfaceIrradiance(Input=source, DirectionalLights=LIGHTS["a"], CollimatedModel=0)
    solved = SolveDiffusion(Input=lit, Solver="montecarlo", NumberOfPhotons=20000, Seed=3,
                            Detectors=DETECTORS)
    if gates:
        solved.TimeGates = gates
    return solved


def mc_readings(o, gates):
    """The detectors' readings (CW: fluence and exitance per channel and
    their standard errors; gated: the TPSFs)."""
    values = []
    for k in range(2):
        if gates:
            values += [f(k, g, c) for f in (o.GetDetectorFluenceTPSF, o.GetDetectorExitanceTPSF)
                       for g in range(gates[2]) for c in range(3)]
        else:
            values += [o.GetDetectorFluence(k, c) for c in range(3)]
            values += [o.GetDetectorExitance(k, c) for c in range(3)]
    return values


def path(name):
    return os.path.join(WORK, name)


def balance(algorithm):
    """ComputePowerBalance of a solved vtkSolveDiffusion: injected, absorbed
    and escaped per channel (9 numbers), or None when it is not available."""
    injected, absorbed, escaped = [0.0] * 3, [0.0] * 3, [0.0] * 3
    if not algorithm.ComputePowerBalance(injected, absorbed, escaped):
        return None
    return injected + absorbed + escaped


# CollimatedModel=0 (Surface) throughout: the distributed solve has the
# surface model only; the default by light kind (extended-moments for a
# directional light, DiffuseOptics.md) is solved gathered.
def solve(source, light, solver="divergence", distributed=1):
    lit = SurfaceIrradiance(Input=source, DirectionalLights=LIGHTS[light], CollimatedModel=0)
    return lit, SolveDiffusion(Input=lit, Solver=solver, RelTol=TOL, MaxIter=20000,
                               DistributedSolve=distributed)


if MODE == "prepare":
    import numpy as np
    from vtkmodules.numpy_interface import dataset_adapter as dsa
    from cli_under_test import write_sphere
    from mpi_harness import (add_ids, mark_global_ids, read_mesh, use_float_points, write_mesh,
                             write_pieces)

    write_sphere(path("surface.ply"), 4.0, 20)
    assign = AssignScatteringCoefficients(Input=TetrahedralizeSurface(
        Input=TranslucencySurfaceReader(FileName=path("surface.ply")), TargetNumberOfTets=8000))
    SaveData(path("tets.vtu"), proxy=assign)

    mesh = read_mesh(path("tets.vtu"))
    # Float points (vtkExtractUnstructuredGridPiece writes float points: every
    # case then has the very same coordinates).
    use_float_points(mesh)
    # A heterogeneous material from the cell centres.
    wrapped = dsa.WrapDataObject(mesh)
    x = np.asarray(wrapped.Points, dtype=float)
    cells = np.asarray(wrapped.Cells).reshape(-1, 5)[:, 1:]
    centre = x[cells].mean(axis=1)
    mu = np.column_stack([0.002 + 0.001 * (centre[:, 0] > 0), 0.004 + 0.002 * (centre[:, 1] > 0),
                          0.008 + 0.004 * (centre[:, 2] > 1)])
    sigma = np.column_stack([1.0 + 0.5 * (centre[:, 1] > 0), 1.5 + 0.1 * centre[:, 0],
                             2.0 + 0.5 * (centre[:, 0] > 1)])
    eta = 1.3 + 0.1 * (centre[:, 2] > 0)
    for name, values in (("AbsorptionCoefficient", mu), ("ReducedScatteringCoefficient", sigma),
                         ("RefractiveIndex", eta)):
        mesh.GetCellData().RemoveArray(name)
        wrapped.CellData.append(values, name)
    add_ids(mesh.GetPointData(), "PointIds", mesh.GetNumberOfPoints(), 500, 3)
    write_mesh(mesh, path("mesh.vtu"))
    write_pieces(mesh, path("mesh2g"), 2, 1)
    write_pieces(mesh, path("mesh3id"), 3, 0)
    mark_global_ids(path("mesh3id"), 3, point="PointIds")

    source = XMLUnstructuredGridReader(FileName=[path("mesh.vtu")])
    import json
    import translucency  # noqa: F401  (the getters of the filter)
    readings, balances = {}, {}
    for kind, props in SOURCES.items():
        _, solved = solve(source, "a")
        for key, value in props.items():
            setattr(solved, key, value)
        solved.Detectors = DETECTORS
        SaveData(path("ref_%s_divergence.vtu" % kind), proxy=solved)
        o = solved.GetClientSideObject()
        readings[kind] = [[o.GetDetectorFluence(k, c) for c in range(3)] +
                          [o.GetDetectorExitance(k, c) for c in range(3)] for k in range(2)]
        balances["src_" + kind] = balance(o)
    with open(path("ref_detectors.json"), "w") as f:
        json.dump(readings, f)
    mc = {}
    for name, gates in MONTE_CARLO.items():
        solved = monte_carlo(source, gates)
        SaveData(path("ref_%s.vtu" % name), proxy=solved)
        mc[name] = mc_readings(solved.GetClientSideObject(), gates)
    with open(path("ref_mc.json"), "w") as f:
        json.dump(mc, f)
    for name, target in PAINTS.items():
        _, solved = painted(source, target)
        SaveData(path("ref_%s.vtu" % name), proxy=solved)
    for light in LIGHTS:
        for solver in ("divergence", "fem"):
            _, solved = solve(source, light, solver)
            SaveData(path("ref_%s_%s.vtu" % (light, solver)), proxy=solved)
            balances["%s_%s" % (light, solver)] = balance(solved.GetClientSideObject())
    with open(path("ref_balance.json"), "w") as f:
        json.dump(balances, f)
    print("prepared", flush=True)
elif MODE == "run":
    from vtkmodules.vtkParallelCore import vtkMultiProcessController
    import translucency  # noqa: F401  (the getters of the filter)

    RANK = vtkMultiProcessController.GetGlobalController().GetLocalProcessId()

    def report(case, solved):
        solved.UpdatePipeline()
        o = solved.GetClientSideObject()
        # One file per rank (the ranks' stdout lines interleave).
        with open(path("solves_%d.txt" % RANK), "a") as f:
            f.write("solve %s rank %d path %s assembly %s iterations %s residuals %s\n" % (
                case, RANK, o.GetParallelPath(), o.GetLastAssembly() or "-",
                ",".join(str(o.GetNumberOfIterations(c)) for c in range(3)),
                ",".join("%.6e" % o.GetFinalResidual(c) for c in range(3))))
            # What the solver set up, with its counts so far (issue 32).
            f.write("setup %s rank %d %s\n" % (case, RANK, o.GetLastLinearSetup() or "-"))
            # The coefficient arrays read so far by this filter object (a
            # relight reuses the kept material: issue 31).
            f.write("conversions %s rank %d %d\n" % (case, RANK,
                                                     o.GetNumberOfMaterialConversions()))
            if o.GetParallelPath() == "distributed":
                # The whole object's balance, summed over the ranks in the solve.
                f.write("balance %s rank %d %s\n" % (case, RANK, " ".join(
                    "%.17g" % v for v in balance(o))))

    def case(name, source, light="a", solver="divergence", distributed=1):
        lit, solved = solve(source, light, solver, distributed)
        report(name, solved)
        SaveData(path(name + ".pvtu"), proxy=solved)
        return lit, solved

    pvtu3 = XMLPartitionedUnstructuredGridReader(FileName=[path("mesh3id.pvtu")])
    lit, solved = case("pvtu3", pvtu3)
    # Relight: same mesh and material, another light: the hierarchy is kept
    # and the solve starts from the previous fluence.
    lit.DirectionalLights = LIGHTS["b"]
    report("relight", solved)
    SaveData(path("relight.pvtu"), proxy=solved)
    # Warm start: the same system again (a tolerance change re-executes).
    solved.RelTol = 2 * TOL
    report("warm", solved)
    case("pvtu2", XMLPartitionedUnstructuredGridReader(FileName=[path("mesh2g.pvtu")]))
    case("redist", RedistributeDataSet(Input=XMLUnstructuredGridReader(
        FileName=[path("mesh.vtu")])))
    case("fem", pvtu3, solver="fem")
    case("gathered", pvtu3, distributed=0)
    # An invalid value on rank 1 only: every rank reports rank 1's error and
    # nobody hangs; the next solve works.
    bad = ProgrammableFilter(Input=SurfaceIrradiance(Input=pvtu3, DirectionalLights=LIGHTS["a"], CollimatedModel=0))
    bad.Script = """
from vtkmodules.vtkParallelCore import vtkMultiProcessController
out = self.GetOutput()
out.ShallowCopy(self.GetInput())
if vtkMultiProcessController.GetGlobalController().GetLocalProcessId() == 1:
    a = out.GetCellData().GetArray("AbsorptionCoefficient")
    b = a.NewInstance()
    b.DeepCopy(a)
    b.SetComponent(5, 1, -1.0)
    out.GetCellData().AddArray(b)
"""
    SolveDiffusion(Input=bad, RelTol=TOL).UpdatePipeline()
    report("after_error", solve(pvtu3, "a")[1])

    # Interior sources and detectors, distributed: a point source on the
    # 2-piece .pvtu (3 ranks: one empty piece), a pencil beam on the 3-piece
    # one; each rank writes its detector readings.
    for kind, reader in (("point", XMLPartitionedUnstructuredGridReader(
            FileName=[path("mesh2g.pvtu")])), ("pencil", pvtu3), ("aimed", pvtu3)):
        _, solved = solve(reader, "a")
        for key, value in SOURCES[kind].items():
            setattr(solved, key, value)
        solved.Detectors = DETECTORS
        report("src_" + kind, solved)
        SaveData(path("src_%s.pvtu" % kind), proxy=solved)
        o = solved.GetClientSideObject()
        with open(path("detectors_%d.txt" % RANK), "a") as f:
            f.write("detectors %s rank %d %s\n" % (kind, RANK, " ".join(
                "%.17g" % v for k in range(o.GetNumberOfDetectors()) for v in
                [o.GetDetectorFluence(k, c) for c in range(3)] +
                [o.GetDetectorExitance(k, c) for c in range(3)])))
    # The Monte Carlo: every rank traces its share of the photons on the
    # replicated mesh (path "replicated"); the 2-piece .pvtu gives 3 ranks an
    # empty piece.
    for name, gates in MONTE_CARLO.items():
        for suffix, reader in (("", pvtu3), ("_pvtu2", XMLPartitionedUnstructuredGridReader(
                FileName=[path("mesh2g.pvtu")]))):
            solved = monte_carlo(reader, gates)
            report(name + suffix, solved)
            SaveData(path(name + suffix + ".pvtu"), proxy=solved)
            with open(path("mc_%d.txt" % RANK), "a") as f:
                f.write("mc %s rank %d %s\n" % (name + suffix, RANK, " ".join(
                    "%.17g" % v for v in mc_readings(solved.GetClientSideObject(), gates))))
    # The node's memory too small for a copy per rank (the override
    # TRANSLUCENCY_REPLICATED_MEMORY, in GiB): rank 0 traces alone (path
    # "gathered"), the serial field all the same; an invalid override gathers
    # too, naming it.
    from vtkmodules.util.misc import calldata_type
    from vtkmodules.util.vtkConstants import VTK_STRING
    for name, memory in (("mc_small_memory", "0.000001"), ("mc_bad_memory", "lots")):
        os.environ["TRANSLUCENCY_REPLICATED_MEMORY"] = memory
        solved = monte_carlo(pvtu3, None)
        warnings = []

        @calldata_type(VTK_STRING)
        def on_warning(obj, event, message):
            warnings.append(message)

        solved.GetClientSideObject().AddObserver("WarningEvent", on_warning)
        report(name, solved)
        SaveData(path(name + ".pvtu"), proxy=solved)
        with open(path("mc_%d.txt" % RANK), "a") as f:
            f.write("plan %s rank %d %s\n" % (name, RANK,
                                              solved.GetClientSideObject().GetParallelPlan()))
            for message in warnings:
                f.write("warning %s rank %d %s\n" % (name, RANK, " ".join(message.split())))
    del os.environ["TRANSLUCENCY_REPLICATED_MEMORY"]
    import re
    from vtkmodules.util.misc import calldata_type
    from vtkmodules.util.vtkConstants import VTK_STRING

    def update_catching(proxy, name, header):
        """Update `proxy` with its errors caught by observers (the filter's and
        its executive's) and write them per rank to <name>_<rank>.txt after the
        line header(algorithm), so the run's error log keeps only the one
        expected case."""
        caught = []

        @calldata_type(VTK_STRING)
        def on_error(obj, event, message):
            caught.append(message)

        algorithm = proxy.GetClientSideObject()
        algorithm.AddObserver("ErrorEvent", on_error)
        algorithm.GetExecutive().AddObserver("ErrorEvent", on_error)
        proxy.UpdatePipeline()
        with open(path("%s_%d.txt" % (name, RANK)), "w") as f:
            f.write(header(algorithm) + "\n")
            for message in caught:
                # (the executive's message prints the request, with times that
                # differ per process; the filter's without the object address)
                if "returned failure" in message:
                    message = "executive: returned failure"
                f.write(" ".join(re.sub(r"0x[0-9a-fA-F]+", "0x", message).split()) + "\n")

    # A point source outside the object: the same error on every rank, no
    # hang. Caught by observers (the filter's and its executive's), written
    # per rank, so the run's error log keeps only the case above.
    _, outside = solve(pvtu3, "a")
    outside.PointSources = [20.0, 0.0, 0.0, 1.0, 1.0, 1.0]
    update_catching(outside, "outside", lambda a: "path %s" % a.GetParallelPath())
    report("src_after_error", solve(pvtu3, "a")[1])
    # The replicated Monte Carlo's error (a point source outside the object,
    # found by every rank on the same whole mesh): the same text on every
    # rank, an empty output, no hang.
    outside_mc = monte_carlo(pvtu3, None)
    outside_mc.PointSources = [20.0, 0.0, 0.0, 1.0, 1.0, 1.0]
    update_catching(outside_mc, "mc_outside", lambda a: "path %s points %d" % (
        a.GetParallelPath(), a.GetOutput().GetNumberOfPoints()))

    # Paint (issue 32): the unpainted chain first (Strength 0: the hierarchy
    # is set up), then the stroke, then mu_a x 1000: values-only set-ups
    # under the kept BoomerAMG hierarchies must still give the serial field
    # (a kept hierarchy that does not converge is set up again and re-solved).
    paint, solved = painted(pvtu3, None)
    paint.Strength = 0.0
    report("unpainted", solved)
    paint.Strength = 1.0
    report("paint", solved)
    SaveData(path("paint.pvtu"), proxy=solved)
    paint.TargetAbsorptionCoefficient = PAINTS["paint_extreme"]
    report("paint_extreme", solved)
    SaveData(path("paint_extreme.pvtu"), proxy=solved)
    # A solve that cannot converge (MaxIter 1): an error on every rank and
    # an empty output, never a field (caught by observers, written per rank).
    _, stuck = solve(pvtu3, "a")
    stuck.MaxIter = 1
    update_catching(stuck, "stuck", lambda a: "path %s points %d fluence %s" % (
        a.GetParallelPath(), a.GetOutput().GetNumberOfPoints(),
        a.GetOutput().GetPointData().GetArray("Fluence") is not None))
    print("run done", flush=True)
else:
    sys.exit("mode must be prepare or run, not " + MODE)
