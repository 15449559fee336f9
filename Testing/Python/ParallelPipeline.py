"""The pvbatch side of TestParallel.py: the plugin's filters on distributed data.

    pvbatch ParallelPipeline.py <Translucency plugin> <work dir> prepare
    mpiexec -n N pvbatch ParallelPipeline.py <Translucency plugin> <work dir> run

prepare (one process): writes a closed sphere surface (surface.ply), meshes
it and assigns the material (mesh.vtu), writes two partitioned copies of the
same tets (mesh2g.pvtu: 2 pieces with one level of ghost cells; mesh3id.pvtu:
3 pieces with point and cell GlobalIds) and the serial references of every case
(ref_*.vtu: Fluence; ref_*_surface.vtp: Outgoing Radiance).

run (under mpiexec): the same chains on distributed data, each result saved
as .pvtu / .pvtp (one piece per rank) for TestParallel.py to compare:
  ply       PLY reader (rank 0 only) -> Tetrahedralize -> Assign -> ... -> Radiance
  pvtu2     mesh2g.pvtu (ghost cells; with 3 ranks one rank has no piece)
  pvtu3     mesh3id.pvtu (GlobalIds; with 2 ranks a rank reads 2 pieces)
  sp3       mesh2g.pvtu with Solver sp3 (gathered solve, radiance per piece)
  redist    mesh.vtu (on rank 0) -> Redistribute DataSet -> ...
  cut       mesh.vtu (on rank 0) -> Stroke Cut (plane) -> Redistribute DataSet -> ...
  paint     Redistribute DataSet -> Paint -> ...
  cutids    mesh3id.pvtu (point and cell GlobalIds) -> Stroke Cut -> ..., with
            the uniform light's occlusion sampling on
  fracture, radiosity, volume: mesh.vtu (on rank 0) -> Fracture Tet Mesh,
            Translucent Radiosity with a floor, Assign from a Wavelet image
            (split by extent): totals printed as "summary" lines
  overlap   mesh2o.pvtu (mesh2g's pieces without their ghost marks: one layer of
            tets in both pieces), every stage gathered (TRANSLUCENCY_PARALLEL)
  error     Solve Diffusion without Irradiance: the same error on every rank
  detectors Redistribute DataSet -> ... -> Solve Diffusion with two detectors ->
            Detector Readings: a "detectors" line with the rows of all ranks'
            tables (the serial count: rows only on rank 0) and the values
Every line "case <name> done" on stdout marks a finished case.
"""

import os
import sys

from paraview.simple import *  # noqa: F401,F403
from paraview import servermanager

PLUGIN, WORK, MODE = sys.argv[1], sys.argv[2], sys.argv[3]
LoadPlugin(PLUGIN, ns=globals())


def path(name):
    return os.path.join(WORK, name)


def light(source, samples=0):
    # Shadows on; by default no occlusion sampling of the uniform light (its
    # per-point sample rotation follows the point order, see Parallel.md).
    return SurfaceIrradiance(Input=source, UniformLightSamples=samples)


def solve(source, solver="divergence"):
    return SolveDiffusion(Input=source, RelTol=1e-12, MaxIter=20000, Solver=solver)


def plane_cut(source):
    cut = StrokeCut(Input=source, CutType="Plane")
    cut.CutType.Origin = [0.5, 0.0, 0.0]
    cut.CutType.Normal = [1.0, 0.3, 0.0]
    return cut


def paint(source):
    return PaintScatteringCoefficients(Input=source, StrokePoints=[3.5, 0.0, 0.0, 2.0, 2.5, 0.0],
                                       Width=1.0)


def summary(name, proxy, array):
    """One line of totals over all ranks, compared by TestParallel.py."""
    proxy.UpdatePipeline()
    info = proxy.GetDataInformation()
    ranges = [proxy.CellData[array].GetRange(c) for c in range(3)]
    print("summary %s: %d cells, %d points, %s %s" % (
        name, info.GetNumberOfCells(), info.GetNumberOfPoints(), array,
        " ".join("%.12g %.12g" % r for r in ranges)), flush=True)


def serial_stages(mesh_source):
    """Fracture and radiosity: computed on rank 0, the result stays there; a
    Volume material from an image that ParaView splits by extent over the ranks."""
    absorption = Calculator(Input=Wavelet(), ResultArrayName="AbsorptionCoefficient",
                            ResultArrayType="Double",
                            Function="(0.01 + 0.001*(coordsX+10))*iHat + "
                                     "(0.02 + 0.002*(coordsY+10))*jHat + 0.03*kHat")
    scattering = Calculator(Input=absorption, ResultArrayName="ReducedScatteringCoefficient",
                            ResultArrayType="Double", Function="2*iHat + 2*jHat + 3*kHat")
    summary("volume", AssignScatteringCoefficients(Input=mesh_source, MaterialMode="Volume",
                                                   Volume=scattering), "AbsorptionCoefficient")
    summary("fracture", FractureTetMesh(Input=mesh_source, RandomSeeds=[4, 1]),
            "AbsorptionCoefficient")
    plane = Plane(Origin=[-10, -10, -5], Point1=[10, -10, -5], Point2=[-10, 10, -5],
                  XResolution=4, YResolution=4)
    floor = Calculator(Input=Triangulate(Input=plane), AttributeType="Cell Data",
                       ResultArrayName="Albedo", Function="0.6*iHat+0.6*jHat+0.6*kHat")
    summary("radiosity", TranslucentRadiosity(
        Input=GroupDatasets(Input=[floor, mesh_source]), LightPosition=[0, 0, 20],
        LightPower=[500, 500, 500], RaysPerPatch=16), "Radiosity")


def detector_table(source):
    """Detector Readings appended over the ranks: the serial rows, once."""
    solved = SolveDiffusion(Input=light(source), RelTol=1e-12, MaxIter=20000,
                            Detectors=[0.0, 0.0, 4.0, 0.0, 0.0, 0.0, -4.0, 1.0])
    readings = DetectorReadings(Input=solved)
    readings.UpdatePipeline()
    # The data information sums the ranks' rows (as the spreadsheet view
    # appends them); Fetch would bring one rank's table only.
    rows = readings.GetDataInformation().GetNumberOfRows()
    table = servermanager.Fetch(readings)
    fluence = table.GetColumnByName("FluenceR")
    values = [fluence.GetValue(k) for k in range(table.GetNumberOfRows())] if fluence else []
    print("detectors: %d rows, FluenceR %s" % (rows, " ".join("%.4g" % v for v in values)),
          flush=True)


def chain(name, source, surface=True, samples=0, solver="divergence"):
    solved = solve(light(source, samples), solver)
    SaveData(path(name + ".pvtu"), proxy=solved)
    if surface:
        SaveData(path(name + "_surface.pvtp"), proxy=OutgoingRadiance(Input=solved))
    print("case %s done" % name.split("_")[-1], flush=True)


if MODE == "prepare":
    from cli_under_test import write_sphere
    from mpi_harness import (add_ids, mark_global_ids, read_mesh, use_float_points, write_mesh,
                             write_pieces)

    write_sphere(path("surface.ply"), 4.0, 16)
    reader = TranslucencySurfaceReader(FileName=path("surface.ply"))
    assign = AssignScatteringCoefficients(
        Input=TetrahedralizeSurface(Input=reader, TargetNumberOfTets=3000))
    SaveData(path("mesh.vtu"), proxy=assign)
    chain("ref_ply", assign)

    # The same tets in pieces, written here with plain VTK (one process).
    # vtkExtractUnstructuredGridPiece makes float points: mesh.vtu gets float
    # points too, so that every case has the very same coordinates.
    mesh = read_mesh(path("mesh.vtu"))
    use_float_points(mesh)
    write_mesh(mesh, path("mesh.vtu"))
    # mesh3id: point and cell ids in the serial order (plain arrays through
    # vtkExtractUnstructuredGridPiece, which drops the GlobalIds attribute,
    # marked as GlobalIds in the written files afterwards).
    with_ids = mesh.NewInstance()
    with_ids.ShallowCopy(mesh)
    add_ids(with_ids.GetPointData(), "PointIds", mesh.GetNumberOfPoints(), 1000, 7)
    add_ids(with_ids.GetCellData(), "CellIds", mesh.GetNumberOfCells(), 1000, 3)
    write_pieces(mesh, path("mesh2g"), 2, 1)
    # mesh2o: mesh2g's pieces without their ghost marks (vtkGhostType
    # removed): the two pieces overlap by one layer of unmarked tets, which a
    # gather must take once.
    import re
    for k in range(2):
        piece = read_mesh(path("mesh2g_%d.vtu" % k))
        for data in (piece.GetCellData(), piece.GetPointData()):
            data.RemoveArray("vtkGhostType")
        write_mesh(piece, path("mesh2o_%d.vtu" % k))
    with open(path("mesh2g.pvtu")) as f:
        text = f.read().replace("mesh2g_", "mesh2o_").replace('GhostLevel="1"', 'GhostLevel="0"')
    with open(path("mesh2o.pvtu"), "w") as f:
        f.write(re.sub(r"\s*<PDataArray[^>]*vtkGhostType[^>]*/>", "", text))
    write_pieces(with_ids, path("mesh3id"), 3, 0)
    mark_global_ids(path("mesh3id"), 3, point="PointIds", cell="CellIds")

    mesh_source = XMLUnstructuredGridReader(FileName=[path("mesh.vtu")])
    chain("ref_mesh", mesh_source)
    chain("ref_sp3", mesh_source, solver="sp3")
    chain("ref_cut", plane_cut(mesh_source), surface=False)
    chain("ref_paint", paint(mesh_source), surface=False)
    chain("ref_cutids", plane_cut(mesh_source), surface=False, samples=32)
    serial_stages(mesh_source)
    detector_table(mesh_source)
elif MODE == "run":
    reader = TranslucencySurfaceReader(FileName=path("surface.ply"))
    chain("par_ply", AssignScatteringCoefficients(
        Input=TetrahedralizeSurface(Input=reader, TargetNumberOfTets=3000)))
    chain("par_pvtu2", XMLPartitionedUnstructuredGridReader(FileName=[path("mesh2g.pvtu")]))
    chain("par_pvtu3", XMLPartitionedUnstructuredGridReader(FileName=[path("mesh3id.pvtu")]))
    # sp3: solved gathered, its SP3Phi1/SP3Phi2 back on each piece, the P3
    # radiance read per piece.
    chain("par_sp3", XMLPartitionedUnstructuredGridReader(FileName=[path("mesh2g.pvtu")]),
          solver="sp3")
    redistributed = RedistributeDataSet(
        Input=XMLUnstructuredGridReader(FileName=[path("mesh.vtu")]))
    chain("par_redist", redistributed)
    # The cut's relaxation visits the vertices in order: cut the mesh in its
    # serial order (read by rank 0), then spread the result over the ranks.
    chain("par_cut", RedistributeDataSet(
        Input=plane_cut(XMLUnstructuredGridReader(FileName=[path("mesh.vtu")]))), surface=False)
    chain("par_paint", paint(redistributed), surface=False)
    detector_table(redistributed)
    # With point and cell GlobalIds (made in the serial order) the
    # order-dependent cut relaxation (per piece: the cut front in id order) and
    # uniform-light sampling give the serial result.
    chain("par_cutids", plane_cut(
        XMLPartitionedUnstructuredGridReader(FileName=[path("mesh3id.pvtu")])),
        surface=False, samples=32)
    serial_stages(XMLUnstructuredGridReader(FileName=[path("mesh.vtu")]))
    # Overlapping pieces without ghost marks, every stage gathered (the
    # override): the merge takes each overlapping tet once, so the serial
    # Fluence comes back on every piece (a tet taken twice would be assembled
    # twice).
    os.environ["TRANSLUCENCY_PARALLEL"] = "gathered"
    chain("par_overlap", XMLPartitionedUnstructuredGridReader(FileName=[path("mesh2o.pvtu")]),
          surface=False)
    del os.environ["TRANSLUCENCY_PARALLEL"]
    # No Irradiance array: every rank reports Solve Diffusion's error, none hangs.
    unlit = solve(XMLUnstructuredGridReader(FileName=[path("mesh.vtu")]))
    unlit.UpdatePipeline()
    print("case error done", flush=True)
else:
    sys.exit("mode must be prepare or run, not " + MODE)
