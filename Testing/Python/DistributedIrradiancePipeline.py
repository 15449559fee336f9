"""The pvbatch side of TestDistributedIrradiance.py: Surface Irradiance
distributed over MPI ranks (the boundary surface all-gathered, no mesh gather).

    pvbatch DistributedIrradiancePipeline.py <plugin> <work dir> prepare
    mpiexec -n N pvbatch --symmetric DistributedIrradiancePipeline.py <plugin> <work dir> run

prepare (one process): a box of 16 x 16 x 14 cubes (6 tets each) with a well
dug from its top (non-convex: the walls shadow the well's floor), about 20k
tets, float points, a heterogeneous material (RefractiveIndex 1.3 to 1.45),
and a "PointIds" array numbering the points 1000 + 7 i (mesh.vtu; meshid.vtu
with it as GlobalIds); the same tets as one piece (mesh1.pvtu), 2 pieces
with a ghost level (mesh2g.pvtu) and 3 pieces with GlobalIds (mesh3id.pvtu);
the serial references ref_<lights>.vtu (Irradiance and Fluence, RelTol 1e-13)
for two lightings, shadows on:
  A: a point light beside the well and a uniform light with 16 occlusion
     samples per point (the samples follow the point's index / global id),
  B: a directional and a point light and the exact uniform light (0 samples);
and boundary.txt, the number of boundary triangles; the serial cuts
ref_cut<kind>.vtu (lit with B and solved; kind: plane, sphere without
relaxation, relax, stroke with it, relax1 the relax cut of mesh1.pvtu) and
their statistics (cutstats.txt).

run (every rank): for each case reader -> Surface Irradiance -> Solve
Diffusion, saved as <case>.pvtu, and per rank one line in irr_<rank>.txt:
    irr <case> rank <r> path <path> triangles <n> bytes <b> ms <t>
an invalid RefractiveIndex on rank 1 only (the same error on every rank),
after_error_B (a run after it), then Assign Scattering Coefficients (a spherical inclusion) on the 3-piece,
1-piece and ghost-cell .pvtu (assign_<case>.pvtu; the serial ref_assign.vtu),
veins on the 3-piece .pvtu and Redistribute DataSet (assignveins_<case>.pvtu;
ref_assignveins.vtu), layers and the Volume mode (a Wavelet image) likewise
(assignlayers_*, assignvolume_*; the Volume mode also gathered by
TRANSLUCENCY_PARALLEL=gathered),
with a line "assign <case> rank <r> path <path>", Stroke Cut (cut_<case>.pvtu,
lines "cut <case> rank <r> path <path> in <cells> out <cells>" and "cutstats
<case> rank <r> movable .. moved .. blocked .. front <tets> <points> bytes .."),
and Paint Scattering
Coefficients per piece (paint_<case>.pvtu; the serial ref_paint.vtu, painted
then lit with B and solved), with a line "paint <case> rank <r> path <path>";
Outgoing Radiance of pvtu3_B, pvtu2_B, redist_B and pvtu1_B per piece and of
pvtu3_B gathered (radiance_<case>.pvtp; the serial ref_radiance.vtp), with a
line "radiance <case> rank <r> path <path> triangles <n> exposure <e>";
a relight of one kept Surface Irradiance (a light moved, then the uniform
light changed: relight_<step>_kept.pvtu, and a fresh filter's full
computation relight_<step>_fresh.pvtu), with a line "relight <step> rank <r>
lights <computed> uniform <0|1> ms <gather ms>"; Outgoing Radiance
re-executed after a relight (radiance_again_kept.pvtp) and a fresh one on the
same solve (radiance_again_fresh.pvtp).
"""

import os
import sys

from paraview.simple import *  # noqa: F401,F403

PLUGIN, WORK, MODE = sys.argv[1], sys.argv[2], sys.argv[3]
LoadPlugin(PLUGIN, ns=globals())
TOL = 1e-13
LIGHTS = {
    "A": dict(PointLights=[14.0, 3.0, 22.0, 400.0], UniformLightIrradiance=0.3,
              UniformLightSamples=16),
    "B": dict(DirectionalLights=[0.4, -0.3, -1.0, 1.0], PointLights=[-4.0, 8.0, 20.0, 300.0],
              UniformLightIrradiance=0.2, UniformLightSamples=0),
}


def path(name):
    return os.path.join(WORK, name)


def chain(source, lights):
    lit = SurfaceIrradiance(Input=source, Shadows=1, **LIGHTS[lights])
    return lit, SolveDiffusion(Input=lit, Solver="divergence", RelTol=TOL, MaxIter=20000)


def cut(source, kind):
    """Stroke Cut per piece under MPI. Relaxation off: plane removes x <
    (the largest x of mesh3x.pvtu's piece 0) + 0.5, so all of that piece's
    tets; sphere keeps the tets touching a ball in the box. Relaxation on (the
    defaults: 10 sweeps, factor 0.1): relax, a tilted plane removing the
    bottom (its cross-section crosses every slab of mesh3x.pvtu); stroke, a
    free-hand polyline across the box seen from above."""
    if kind == "plane":
        with open(path("cutplane.txt")) as f:
            x0 = float(f.read().split()[0])
        result = StrokeCut(Input=source, CutType="Plane", NumberOfRelaxationIterations=0)
        result.CutType.Origin = [x0 + 0.5, 0.0, 0.0]
        result.CutType.Normal = [-1.0, 0.0, 0.0]
    elif kind == "sphere":
        result = StrokeCut(Input=source, CutType="Sphere", NumberOfRelaxationIterations=0)
        result.CutType.Center = [8.0, 7.0, 5.0]
        result.CutType.Radius = 6.5
    elif kind == "relax":
        result = StrokeCut(Input=source, CutType="Plane")
        result.CutType.Origin = [8.0, 8.0, 4.5]
        result.CutType.Normal = [0.35, 0.2, -1.0]
    else:
        stroke = PolyLineSource(Points=[-1.0, 2.2, 30.0, 7.3, 9.1, 30.0, 17.0, 11.4, 30.0])
        result = StrokeCut(Input=source, Stroke=stroke)
    return result


def cut_statistics(cutter):
    # The relaxation's statistics and the front's size (per piece: of the
    # whole relaxation, the same on every rank).
    import translucency  # noqa: F401  (the getters of the filters)
    o = cutter.GetClientSideObject()
    return "movable %d moved %d blocked %d front %d %d bytes %d" % (
        o.GetNumberOfMovableVertices(), o.GetNumberOfMovedVertices(),
        o.GetNumberOfBlockedVertices(), o.GetNumberOfFrontTets(), o.GetNumberOfFrontPoints(),
        o.GetFrontBytes())


def paint(source, original=None):
    # A stroke over the top and down one side (per tet: each piece painted
    # on its rank under MPI); with `original`, the two-port form.
    extra = {} if original is None else dict(OriginalMesh=original)
    return PaintScatteringCoefficients(Input=source, StrokePoints=[2, 2, 14, 12, 3, 14, 15, 12, 8],
                                       StrokeIsPolyline=1, Width=1.5, **extra)


def volume_image():
    # 1 mm voxels over the box and a voxel beyond (the Wavelet's extent):
    # coefficients that vary with the Wavelet's RTData and with x, y, z, so
    # that a tet probed in the wrong part of the image gets other values.
    wavelet = Wavelet(WholeExtent=[-1, 17, -1, 17, -1, 15])
    absorption = Calculator(Input=wavelet, ResultArrayName="AbsorptionCoefficient",
                            ResultArrayType="Double",
                            Function="(0.002 + 0.00005*RTData)*iHat + "
                                     "(0.004 + 0.0001*coordsX*coordsY)*jHat + 0.01*kHat")
    return Calculator(Input=absorption, ResultArrayName="ReducedScatteringCoefficient",
                      ResultArrayType="Double",
                      Function="(1 + 0.005*RTData)*iHat + 1.5*jHat + (2 + 0.1*coordsZ)*kHat")


def assign(source, veins=False, layers=False, volume=False):
    # A spherical inclusion, or veins (per tet: computed on each piece under MPI),
    # or layers by depth (per piece on the all-gathered boundary surface; the
    # thicknesses keep the layer boundaries, 1.1 and 3.7 mm deep, away from the
    # centroids' depths, multiples of 0.25 mm in this box), or probed in an image
    # (per piece: every rank asks for the whole image, which ParaView would
    # otherwise split by extent).
    if volume:
        return AssignScatteringCoefficients(Input=source, MaterialMode="Volume",
                                            Volume=volume_image())
    if layers:
        return AssignScatteringCoefficients(Input=source, MaterialMode="Layers by Depth",
                                            Layers=["1.1", "skin1", "2.6", "ketchup",
                                                    "1", "marble"])
    if veins:
        return AssignScatteringCoefficients(Input=source, MaterialMode=4, VeinFrequency=0.3,
                                            VeinTurbulence=2.0, VeinSeed=3)
    return AssignScatteringCoefficients(Input=source, MaterialMode=2, InclusionCenter=[8, 8, 4],
                                        InclusionRadius=5.0)


if MODE == "prepare":
    import numpy as np
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonCore import vtkPoints
    from vtkmodules.vtkCommonDataModel import VTK_TETRA, vtkCellArray, vtkUnstructuredGrid
    from vtkmodules.util.numpy_support import numpy_to_vtkIdTypeArray
    from mpi_harness import add_ids, mark_global_ids, write_mesh, write_pieces

    nx, ny, nz, h = 16, 16, 14, 1.0
    keep = np.ones((nx, ny, nz), bool)
    keep[5:11, 5:11, 7:] = False  # the well
    px, py, pz = nx + 1, ny + 1, nz + 1

    def pid(i, j, k):
        return i + px * (j + py * k)
    # The 6 Kuhn tets of a cube around its main diagonal (conforming).
    paths = [(0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)]
    tets = []
    for i, j, k in zip(*np.nonzero(keep)):
        for p in paths:
            c = [0, 0, 0]
            tet = [pid(i, j, k)]
            for axis in p:
                c[axis] += 1
                tet.append(pid(i + c[0], j + c[1], k + c[2]))
            tets.append(tet)
    tets = np.array(tets, dtype=np.int64)
    used = np.unique(tets)
    renumber = -np.ones(px * py * pz, np.int64)
    renumber[used] = np.arange(len(used))
    tets = renumber[tets]
    grid = np.stack(np.meshgrid(np.arange(px), np.arange(py), np.arange(pz), indexing="ij"), -1)
    coords = (grid.transpose(2, 1, 0, 3).reshape(-1, 3) * h)[used].astype(np.float32)
    mesh = vtkUnstructuredGrid()
    points = vtkPoints()
    points.SetData(numpy_to_vtk(coords, deep=True))
    mesh.SetPoints(points)
    cells = vtkCellArray()
    cells.SetData(numpy_to_vtkIdTypeArray(np.arange(0, 4 * len(tets) + 1, 4), deep=True),
                  numpy_to_vtkIdTypeArray(tets.ravel(), deep=True))
    mesh.SetCells(VTK_TETRA, cells)
    centre = coords[tets].mean(axis=1)
    mu = np.column_stack([0.002 + 0.001 * (centre[:, 0] > 8), np.full(len(tets), 0.004),
                          0.008 + 0.004 * (centre[:, 2] > 5)])
    sigma = np.column_stack([1.0 + 0.5 * (centre[:, 1] > 8), np.full(len(tets), 1.5),
                             2.0 + 0.5 * (centre[:, 0] > 4)])
    eta = 1.3 + 0.1 * (centre[:, 2] > 7) + 0.05 * (centre[:, 0] > 8)
    for name, values in (("AbsorptionCoefficient", mu), ("ReducedScatteringCoefficient", sigma),
                         ("RefractiveIndex", eta)):
        array = numpy_to_vtk(np.ascontiguousarray(values, dtype=float), deep=True)
        array.SetName(name)
        mesh.GetCellData().AddArray(array)
    tet_ids = numpy_to_vtk(np.arange(len(tets), dtype=np.int64) * 3 + 5, deep=True)
    tet_ids.SetName("TetIds")  # a cell identity that survives partitioning
    mesh.GetCellData().AddArray(tet_ids)
    add_ids(mesh.GetPointData(), "PointIds", mesh.GetNumberOfPoints(), 1000, 7)  # serial order
    # Boundary triangles: faces of one tet only.
    faces = np.sort(np.concatenate([tets[:, [1, 2, 3]], tets[:, [0, 2, 3]], tets[:, [0, 1, 3]],
                                    tets[:, [0, 1, 2]]]), axis=1)
    _, counts = np.unique(faces, axis=0, return_counts=True)
    with open(path("boundary.txt"), "w") as f:
        f.write("%d %d\n" % (int((counts == 1).sum()), len(tets)))

    write_mesh(mesh, path("mesh.vtu"))
    with_ids = mesh.NewInstance()
    with_ids.ShallowCopy(mesh)
    with_ids.GetPointData().SetActiveGlobalIds("PointIds")
    write_mesh(with_ids, path("meshid.vtu"))
    write_pieces(mesh, path("mesh1"), 1, 0)
    write_pieces(mesh, path("mesh2g"), 2, 1)
    write_pieces(mesh, path("mesh3id"), 3, 0)
    mark_global_ids(path("mesh3id"), 3, point="PointIds")

    # 3 slabs in x with GlobalIds (mesh3x.pvtu): piece 0 is x <= x0.
    from vtkmodules.vtkFiltersCore import vtkThreshold
    slab = numpy_to_vtk(np.minimum((centre[:, 0] * 3 // nx).astype(float), 2.0), deep=True)
    slab.SetName("Slab")
    with_ids.GetCellData().AddArray(slab)
    for k in range(3):
        threshold = vtkThreshold()
        threshold.SetInputData(with_ids)
        threshold.SetInputArrayToProcess(0, 0, 0, 1, "Slab")
        threshold.SetLowerThreshold(k - 0.5)
        threshold.SetUpperThreshold(k + 0.5)
        threshold.SetThresholdFunction(vtkThreshold.THRESHOLD_BETWEEN)
        threshold.Update()
        piece = threshold.GetOutput()
        piece.GetCellData().RemoveArray("Slab")
        piece.GetPointData().SetActiveGlobalIds("PointIds")
        if k == 0:
            with open(path("cutplane.txt"), "w") as f:
                f.write("%r\n" % piece.GetBounds()[1])
        write_mesh(piece, path("mesh3x_%d.vtu" % k))
    with_ids.GetCellData().RemoveArray("Slab")
    with open(path("mesh3id.pvtu")) as f:
        text = f.read()
    with open(path("mesh3x.pvtu"), "w") as f:
        f.write(text.replace("mesh3id_", "mesh3x_"))
    source = XMLUnstructuredGridReader(FileName=[path("mesh.vtu")])
    SaveData(path("ref_assign.vtu"), proxy=assign(source))
    SaveData(path("ref_assignveins.vtu"), proxy=assign(source, veins=True))
    SaveData(path("ref_assignlayers.vtu"), proxy=assign(source, layers=True))
    SaveData(path("ref_assignvolume.vtu"), proxy=assign(source, volume=True))
    _, painted = chain(paint(source), "B")
    SaveData(path("ref_paint.vtu"), proxy=painted)
    for kind in ("plane", "sphere", "relax", "stroke"):
        cutter = cut(source, kind)
        _, solved = chain(cutter, "B")
        SaveData(path("ref_cut%s.vtu" % kind), proxy=solved)
        with open(path("cutstats.txt"), "a") as f:
            f.write("cutstats %s %s\n" % (kind, cut_statistics(cutter)))
    # Without ids the relaxation follows the piece's point order: the one-piece
    # .pvtu (vtkExtractUnstructuredGridPiece renumbered its points) cut serially.
    cutter = cut(XMLPartitionedUnstructuredGridReader(FileName=[path("mesh1.pvtu")]), "relax")
    _, solved = chain(cutter, "B")
    SaveData(path("ref_cutrelax1.vtu"), proxy=solved)
    with open(path("cutstats.txt"), "a") as f:
        f.write("cutstats relax1 %s\n" % cut_statistics(cutter))
    for lights in LIGHTS:
        _, solved = chain(source, lights)
        SaveData(path("ref_%s.vtu" % lights), proxy=solved)
        if lights == "B":
            SaveData(path("ref_radiance.vtp"), proxy=OutgoingRadiance(Input=solved))
    print("prepared", flush=True)
elif MODE == "run":
    from vtkmodules.vtkParallelCore import vtkMultiProcessController
    import translucency  # noqa: F401  (the getters of the filters)

    RANK = vtkMultiProcessController.GetGlobalController().GetLocalProcessId()

    def case(name, source, lights, gathered=False):
        if gathered:
            os.environ["TRANSLUCENCY_GATHERED_IRRADIANCE"] = "1"
        lit, solved = chain(source, lights)
        solved.UpdatePipeline()
        os.environ.pop("TRANSLUCENCY_GATHERED_IRRADIANCE", None)
        o = lit.GetClientSideObject()
        with open(path("irr_%d.txt" % RANK), "a") as f:
            f.write("irr %s rank %d path %s triangles %d bytes %d ms %.3f\n" % (
                name, RANK, o.GetParallelPath(), o.GetBoundarySurfaceTriangles(),
                o.GetBoundarySurfaceBytes(), o.GetBoundarySurfaceTime()))
        SaveData(path(name + ".pvtu"), proxy=solved)
        return solved

    def radiance(name, solved, gathered=False):
        # Outgoing Radiance: per piece (each rank its own physical faces), or
        # gathered to rank 0 with TRANSLUCENCY_GATHERED_RADIANCE=1.
        if gathered:
            os.environ["TRANSLUCENCY_GATHERED_RADIANCE"] = "1"
        out = OutgoingRadiance(Input=solved)
        out.UpdatePipeline()
        os.environ.pop("TRANSLUCENCY_GATHERED_RADIANCE", None)
        o = out.GetClientSideObject()
        with open(path("irr_%d.txt" % RANK), "a") as f:
            f.write("radiance %s rank %d path %s triangles %d exposure %.17g\n" % (
                name, RANK, o.GetParallelPath().replace(" ", "-"),
                o.GetNumberOfSurfaceTriangles(), o.GetExposureUsed()))
        SaveData(path("radiance_" + name + ".pvtp"), proxy=out)

    pvtu3 = XMLPartitionedUnstructuredGridReader(FileName=[path("mesh3id.pvtu")])
    case("pvtu3_A", pvtu3, "A")
    solved = case("pvtu3_B", pvtu3, "B")
    radiance("pvtu3_B", solved)
    radiance("gathered_B", solved, gathered=True)
    case("redistid_A", RedistributeDataSet(Input=XMLUnstructuredGridReader(
        FileName=[path("meshid.vtu")])), "A")
    radiance("pvtu2_B", case(
        "pvtu2_B", XMLPartitionedUnstructuredGridReader(FileName=[path("mesh2g.pvtu")]), "B"))
    radiance("redist_B", case("redist_B", RedistributeDataSet(Input=XMLUnstructuredGridReader(
        FileName=[path("mesh.vtu")])), "B"))
    radiance("pvtu1_B", case(
        "pvtu1_B", XMLPartitionedUnstructuredGridReader(FileName=[path("mesh1.pvtu")]), "B"))
    case("gathered_A", pvtu3, "A", gathered=True)
    # Assign Scattering Coefficients per piece (no ghost cells, no cell ids),
    # and gathered (ghost cells: vtkOriginalCellIds need the gathered order).
    for name, source in (("assign_pvtu3", pvtu3), ("assign_pvtu1", XMLPartitionedUnstructuredGridReader(
            FileName=[path("mesh1.pvtu")])), ("assign_pvtu2", XMLPartitionedUnstructuredGridReader(
            FileName=[path("mesh2g.pvtu")])), ("assignveins_pvtu3", pvtu3),
            ("assignveins_redist", RedistributeDataSet(Input=XMLUnstructuredGridReader(
                FileName=[path("mesh.vtu")]))), ("assignlayers_pvtu3", pvtu3),
            ("assignlayers_pvtu1", XMLPartitionedUnstructuredGridReader(
                FileName=[path("mesh1.pvtu")])),
            ("assignlayers_redist", RedistributeDataSet(Input=XMLUnstructuredGridReader(
                FileName=[path("mesh.vtu")]))), ("assignvolume_pvtu3", pvtu3),
            ("assignvolume_pvtu1", XMLPartitionedUnstructuredGridReader(
                FileName=[path("mesh1.pvtu")])),
            ("assignvolume_redist", RedistributeDataSet(Input=XMLUnstructuredGridReader(
                FileName=[path("mesh.vtu")]))), ("assignvolume_gathered", pvtu3)):
        assigned = assign(source, veins=name.startswith("assignveins"),
                          layers=name.startswith("assignlayers"),
                          volume=name.startswith("assignvolume"))
        # The one override: every filter gathers (the image pieces, whole on
        # every rank, merged into one).
        if name.endswith("_gathered"):
            os.environ["TRANSLUCENCY_PARALLEL"] = "gathered"
        assigned.UpdatePipeline()
        os.environ.pop("TRANSLUCENCY_PARALLEL", None)
        with open(path("irr_%d.txt" % RANK), "a") as f:
            f.write("assign %s rank %d path %s\n" % (
                name, RANK, assigned.GetClientSideObject().GetParallelPath().replace(" ", "-")))
        SaveData(path(name + ".pvtu"), proxy=assigned)
    # Paint per piece, then the chain (B): a .pvtu with ids, Redistribute
    # DataSet (coordinate keys), the two-port form (a cut of the .pvtu, gathered
    # on rank 0, as port 0); the paint alone on the ghost-cell .pvtu (3 ranks:
    # an empty piece) and the one-piece .pvtu (empty pieces elsewhere).
    pvtu2 = XMLPartitionedUnstructuredGridReader(FileName=[path("mesh2g.pvtu")])
    pvtu1 = XMLPartitionedUnstructuredGridReader(FileName=[path("mesh1.pvtu")])
    cut_mesh = StrokeCut(Input=pvtu3, CutType="Plane")
    cut_mesh.CutType.Origin = [8.0, 8.0, 3.0]
    cut_mesh.CutType.Normal = [0.2, 0.1, 1.0]
    for name, source, solve in (
            ("paint_pvtu3", paint(pvtu3), True),
            ("paint_redist", paint(RedistributeDataSet(Input=XMLUnstructuredGridReader(
                FileName=[path("mesh.vtu")]))), True),
            ("paint_twoport", paint(cut_mesh, original=pvtu3), True),
            ("paint_pvtu2", paint(pvtu2), False), ("paint_pvtu1", paint(pvtu1), False)):
        proxy = chain(source, "B")[1] if solve else source
        proxy.UpdatePipeline()
        with open(path("irr_%d.txt" % RANK), "a") as f:
            f.write("paint %s rank %d path %s\n" % (
                name, RANK, source.GetClientSideObject().GetParallelPath().replace(" ", "-")))
        SaveData(path(name + ".pvtu"), proxy=proxy)
    # A stroke after a solve of the same chain, painted after the light (the
    # user's order: Irradiance -> Paint -> Solve; issue 32): every rank
    # compares the new arrays with its kept material in place, tells the
    # distributed solver the changed tets, and reuses the irradiance without
    # the beams (the lights and the Irradiance array unchanged). The field
    # must equal the serial painted chain's (ref_paint.vtu).
    repaint = paint(SurfaceIrradiance(Input=pvtu3, Shadows=1, **LIGHTS["B"]))
    repaint.Strength = 0.0
    resolved = SolveDiffusion(Input=repaint, Solver="divergence", RelTol=TOL, MaxIter=20000)
    resolved.UpdatePipeline()
    repaint.Strength = 1.0
    resolved.UpdatePipeline()
    o = resolved.GetClientSideObject()
    with open(path("irr_%d.txt" % RANK), "a") as f:
        f.write("paint repaint_pvtu3 rank %d path %s\n" % (
            RANK, repaint.GetClientSideObject().GetParallelPath().replace(" ", "-")))
        f.write("repaint rank %d path %s beams %d conversions %d\n" % (
            RANK, o.GetParallelPath(), o.GetNumberOfBeamIrradianceReuses(),
            o.GetNumberOfMaterialConversions()))
    SaveData(path("repaint_pvtu3.pvtu"), proxy=resolved)
    # Stroke Cut per piece -> the distributed chain: implicit cutters without
    # relaxation; with the relaxation a tilted plane (3 slabs with ids; one
    # piece, coordinate keys, empty pieces elsewhere) and a stroke (3 pieces
    # with ids); with TRANSLUCENCY_GATHERED_CUT=1 gathered (the cut mesh on rank 0).
    pvtu1 = XMLPartitionedUnstructuredGridReader(FileName=[path("mesh1.pvtu")])
    pvtu3x = XMLPartitionedUnstructuredGridReader(FileName=[path("mesh3x.pvtu")])
    for name, source, kind, gathered in (("cut_plane3", pvtu3x, "plane", False),
                                         ("cut_sphere3", pvtu3, "sphere", False),
                                         ("cut_plane1", pvtu1, "plane", False),
                                         ("cut_gathered3", pvtu3x, "plane", True),
                                         ("cut_relax3", pvtu3x, "relax", False),
                                         ("cut_relax1", pvtu1, "relax", False),
                                         ("cut_stroke3", pvtu3, "stroke", False)):
        if gathered:
            os.environ["TRANSLUCENCY_GATHERED_CUT"] = "1"
        cutter = cut(source, kind)
        _, solved = chain(cutter, "B")
        solved.UpdatePipeline()
        os.environ.pop("TRANSLUCENCY_GATHERED_CUT", None)
        o = cutter.GetClientSideObject()
        with open(path("irr_%d.txt" % RANK), "a") as f:
            f.write("cut %s rank %d path %s in %d out %d\n" % (
                name, RANK, o.GetParallelPath().replace(" ", "-"),
                o.GetInputDataObject(0, 0).GetNumberOfCells(),
                o.GetOutputDataObject(0).GetNumberOfCells()))
            f.write("cutstats %s rank %d %s\n" % (name, RANK, cut_statistics(cutter)))
        SaveData(path(name + ".pvtu"), proxy=solved)
    # A relight of one distributed Surface Irradiance (issue 32): the kept
    # surface and terms; one light moved recomputes that light only (no
    # gather: ms 0), then a new uniform light its term only; each result
    # saved with a fresh filter's full computation of the same lights.
    kept = SurfaceIrradiance(Input=pvtu3, Shadows=1, **LIGHTS["A"])
    kept.UpdatePipeline()
    for step, change in (("light", dict(PointLights=[-3.0, 12.0, 21.0, 350.0])),
                         ("uniform", dict(UniformLightIrradiance=0.25))):
        for name, value in change.items():
            setattr(kept, name, value)
        kept.UpdatePipeline()
        o = kept.GetClientSideObject()
        with open(path("irr_%d.txt" % RANK), "a") as f:
            f.write("relight %s rank %d lights %d uniform %d ms %.3f\n" % (
                step, RANK, o.GetNumberOfLightsComputed(), int(o.GetUniformComputed()),
                o.GetBoundarySurfaceTime()))
        SaveData(path("relight_%s_kept.pvtu" % step), proxy=kept)
        settings = dict(LIGHTS["A"], PointLights=list(kept.PointLights),
                        UniformLightIrradiance=kept.UniformLightIrradiance)
        fresh = SurfaceIrradiance(Input=pvtu3, Shadows=1, **settings)
        SaveData(path("relight_%s_fresh.pvtu" % step), proxy=fresh)
    # Outgoing Radiance re-executed after a relight keeps its boundary
    # (issue 32): saved with a fresh filter's output on the same solve.
    relit, relit_solved = chain(pvtu3, "B")
    again = OutgoingRadiance(Input=relit_solved)
    again.UpdatePipeline()
    relit.PointLights = [-3.0, 12.0, 21.0, 350.0]
    SaveData(path("radiance_again_kept.pvtp"), proxy=again)
    SaveData(path("radiance_again_fresh.pvtp"), proxy=OutgoingRadiance(Input=relit_solved))
    # An invalid RefractiveIndex on rank 1 only: every rank reports rank 1's
    # error and nobody hangs; the next run works.
    bad = ProgrammableFilter(Input=pvtu3)
    bad.Script = """
from vtkmodules.vtkParallelCore import vtkMultiProcessController
out = self.GetOutput()
out.ShallowCopy(self.GetInput())
if vtkMultiProcessController.GetGlobalController().GetLocalProcessId() == 1:
    a = out.GetCellData().GetArray("RefractiveIndex")
    b = a.NewInstance()
    b.DeepCopy(a)
    b.SetValue(5, -1.0)
    out.GetCellData().AddArray(b)
"""
    SurfaceIrradiance(Input=bad, Shadows=1, **LIGHTS["B"]).UpdatePipeline()
    case("after_error_B", pvtu3, "B")
    print("run done", flush=True)
else:
    sys.exit("mode must be prepare or run, not " + MODE)
