"""The pvbatch side of TestPartitionIndependence.py: the documented chains on
partitions without global ids give the serial fields (issue 32).

    pvbatch PartitionPipeline.py <Translucency plugin> <work dir> prepare
    mpiexec -n N pvbatch --symmetric PartitionPipeline.py <Translucency plugin> <work dir> run

prepare (one process): writes a box with a well (non-convex, ~2,300 tets, a
heterogeneous material, float points, no id array: mesh.vtu), its partitioned
copies (mesh3.pvtu: 3 pieces; mesh2.pvtu: 2 pieces, so that with 3 ranks one
rank has an empty piece) and a renumbered copy (shuffled.vtu: the same tets,
points and tets in another order, no ids); then runs every chain on mesh.vtu
(the references, ref_<chain>.pvtu) and on shuffled.vtu (ser_<chain>.pvtu: the
serial code on another point order).

run (under mpiexec): every chain on every source, saved as
par_<source>_<chain>.pvtu (one piece per rank):
  sources  pvtu3     mesh3.pvtu (with 2 ranks one rank reads 2 pieces)
           redist    mesh.vtu (read by rank 0) -> Redistribute DataSet
           pvtu2     mesh2.pvtu (with 3 ranks: one empty rank)
           shuffled  shuffled.vtu read by rank 0 (every other rank empty)
  chains   lit       Surface Irradiance with the default lights (the uniform
                     light's 32 occlusion samples) -> Solve Diffusion
           relit     the same Solve Diffusion after another directional light
           paint     Paint (the filter's default targets) after an unpainted
                     solve of the same Solve Diffusion (kept set-up)
           extreme   the same paint with mu_a x 1000 (Multiply)
           cut       Stroke Cut (a plane, relaxation on) -> lit -> solve
           extended  a directional light as the extended collimated model (its
                     direction off the grid's diagonals)
           gated     time gates (4 gates in [0, 0.2] ns)
           moments   Assign (a spherical inclusion) -> Surface Irradiance with
                     the default lights (the key light along the grid's
                     diagonal (0, -1, -1)) as the extended-moments model ->
                     Solve Diffusion -> Outgoing Radiance (moments_radiance)
           default   the same chain with the default collimated model (the
                     table's model for the default lights: extended-moments)
           defrelit  the default chain's Solve Diffusion after another
                     directional light
           interactive  lit, solved with the default RelTol (the interactive
                     stopping rule; every other chain solves to RelTol 1e-12)
Every rank writes "<source> <chain> <path>" lines (Solve Diffusion's
GetParallelPath) for the collimated-model chains (extended, moments, default,
defrelit) to paths_<rank>.txt, and prints "case <source> done" after each
source.
"""

import os
import sys

from paraview.simple import *  # noqa: F401,F403

PLUGIN, WORK, MODE = sys.argv[1], sys.argv[2], sys.argv[3]
LoadPlugin(PLUGIN, ns=globals())
import translucency  # noqa: E402,F401  (the filters' getters: GetParallelPath)
CHAINS = ("lit", "relit", "paint", "extreme", "cut", "extended", "gated", "moments", "default",
          "defrelit")


def path(name):
    return os.path.join(WORK, name)


def solve(source, **extra):
    return SolveDiffusion(Input=source, RelTol=1e-12, MaxIter=20000, **extra)


def save(name, proxy, extension=".pvtu"):
    SaveData(path(name + extension), proxy=proxy)


def report_path(prefix, chain, solved):
    """Writes Solve Diffusion's path of the last execution on this rank to
    paths_<rank>.txt (a file per rank: the ranks' stdout lines interleave)."""
    if MODE != "run":
        return
    from vtkmodules.vtkParallelCore import vtkMultiProcessController
    rank = vtkMultiProcessController.GetGlobalController().GetLocalProcessId()
    with open(path("paths_%d.txt" % rank), "a") as log:
        log.write("%s %s %s\n" % (prefix.split("_")[-1], chain,
                                  solved.GetClientSideObject().GetParallelPath()))


def chains(prefix, source):
    """Every chain of the docstring on `source`, saved as <prefix>_<chain>."""
    # CollimatedModel=0 (Surface) in every chain but the explicit extended
    # one: a default choice is the surface model under MPI and the table's
    # model in one process (DiffuseOptics.md), so the serial reference and
    # the partitions solve the same model only when it is explicit.
    lit = SurfaceIrradiance(Input=source, CollimatedModel=0)
    solved = solve(lit)
    save(prefix + "_lit", solved)
    lit.DirectionalLights = [0.3, -1.0, 0.5, 1.0]
    save(prefix + "_relit", solved)

    painted = PaintScatteringCoefficients(Input=source, StrokePoints=[1.0, 1.0, 2.0, 7.0, 4.0, 2.0],
                                          Width=1.0, Strength=0.0)
    painted_solve = solve(SurfaceIrradiance(Input=painted, CollimatedModel=0))
    painted_solve.UpdatePipeline()
    painted.Strength = 1.0
    save(prefix + "_paint", painted_solve)
    painted.Mode = "Multiply"
    painted.TargetAbsorptionCoefficient = [1000.0, 1000.0, 1000.0]
    painted.TargetReducedScatteringCoefficient = [1.0, 1.0, 1.0]
    save(prefix + "_extreme", painted_solve)

    cut = StrokeCut(Input=source, CutType="Plane")
    cut.CutType.Origin = [4.5, 0.0, 0.0]
    cut.CutType.Normal = [1.0, 0.3, 0.0]
    save(prefix + "_cut", solve(SurfaceIrradiance(Input=cut, CollimatedModel=0)))

    # Not along the grid's diagonals: a beam ray from a grid point in (0, 1, 1)
    # runs exactly through mesh edges and the well's rim, where the entry
    # triangle is a tie that the triangle order decides (Parallel.md).
    extended = SurfaceIrradiance(Input=source, DirectionalLights=[0.13, -1.0, -0.77, 1.0],
                                 CollimatedModel=1)
    extended_solve = solve(extended)
    save(prefix + "_extended", extended_solve)
    report_path(prefix, "extended", extended_solve)
    save(prefix + "_gated", solve(SurfaceIrradiance(Input=source, CollimatedModel=0), TimeGates=[0.0, 0.2, 4]))
    # The extended-moments model, named and by default, with the default
    # lights: their key light (0, -1, -1) runs along the grid's diagonals, so
    # rays from grid points run through mesh edges (CollimatedSource.cxx).
    assigned = AssignScatteringCoefficients(Input=source, MaterialMode=2,
                                            InclusionCenter=[4.0, 4.0, 3.0], InclusionRadius=3.0)
    moments = solve(SurfaceIrradiance(Input=assigned, CollimatedModel=2))
    save(prefix + "_moments", moments)
    report_path(prefix, "moments", moments)
    save(prefix + "_moments_radiance", OutgoingRadiance(Input=moments), ".pvtp")
    lit_default = SurfaceIrradiance(Input=assigned)
    by_default = solve(lit_default)
    save(prefix + "_default", by_default)
    report_path(prefix, "default", by_default)
    save(prefix + "_default_radiance", OutgoingRadiance(Input=by_default), ".pvtp")
    lit_default.DirectionalLights = [0.3, -1.0, 0.5, 1.0]
    save(prefix + "_defrelit", by_default)
    report_path(prefix, "defrelit", by_default)
    # The interactive stopping rule: Solve Diffusion's default RelTol.
    save(prefix + "_interactive", SolveDiffusion(Input=SurfaceIrradiance(Input=source, CollimatedModel=0)))
    print("case %s done" % prefix.split("_")[-1], flush=True)


def box_with_well(shuffle):
    """A box of 8 x 8 x 7 unit cubes (6 Kuhn tets each) with a 4 x 4 x 4 well
    dug from its top (non-convex: its walls occlude the uniform light's
    samples on the well's floor), float points, a heterogeneous material and
    no id array; with `shuffle`, points and tets in a random order."""
    import numpy as np
    from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray
    from vtkmodules.vtkCommonCore import vtkPoints
    from vtkmodules.vtkCommonDataModel import VTK_TETRA, vtkCellArray, vtkUnstructuredGrid

    nx, ny, nz = 8, 8, 7
    keep = np.ones((nx, ny, nz), bool)
    keep[2:6, 2:6, 3:] = False
    px, py = nx + 1, ny + 1
    paths = [(0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)]
    tets = []
    for i, j, k in zip(*np.nonzero(keep)):
        for order in paths:
            c = [0, 0, 0]
            tet = [i + px * (j + py * k)]
            for axis in order:
                c[axis] += 1
                tet.append(i + c[0] + px * (j + c[1] + py * (k + c[2])))
            tets.append(tet)
    tets = np.array(tets, dtype=np.int64)
    used = np.unique(tets)
    renumber = -np.ones(px * py * (nz + 1), np.int64)
    renumber[used] = np.arange(len(used))
    tets = renumber[tets]
    grid = np.stack(np.meshgrid(np.arange(px), np.arange(py), np.arange(nz + 1), indexing="ij"),
                    -1)
    coords = grid.transpose(2, 1, 0, 3).reshape(-1, 3)[used].astype(np.float32)
    if shuffle:
        rng = np.random.default_rng(7)
        point_order = rng.permutation(len(coords))  # new point k is old point_order[k]
        new_id = np.empty_like(point_order)
        new_id[point_order] = np.arange(len(coords))
        coords = coords[point_order]
        tets = new_id[tets][rng.permutation(len(tets))]
    mesh = vtkUnstructuredGrid()
    points = vtkPoints()
    points.SetData(numpy_to_vtk(coords, deep=True))
    mesh.SetPoints(points)
    cells = vtkCellArray()
    cells.SetData(numpy_to_vtkIdTypeArray(np.arange(0, 4 * len(tets) + 1, 4), deep=True),
                  numpy_to_vtkIdTypeArray(tets.ravel(), deep=True))
    mesh.SetCells(VTK_TETRA, cells)
    centre = coords[tets].astype(float).mean(axis=1)
    mu = np.column_stack([0.01 + 0.01 * (centre[:, 0] > 4), np.full(len(tets), 0.02),
                          0.03 + 0.02 * (centre[:, 2] > 2)])
    sigma = np.column_stack([1.0 + 0.5 * (centre[:, 1] > 4), np.full(len(tets), 1.5),
                             2.0 + 0.5 * (centre[:, 0] > 2)])
    eta = 1.3 + 0.1 * (centre[:, 2] > 4) + 0.05 * (centre[:, 0] > 4)
    for name, values in (("AbsorptionCoefficient", mu), ("ReducedScatteringCoefficient", sigma),
                         ("RefractiveIndex", eta)):
        array = numpy_to_vtk(np.ascontiguousarray(values, dtype=float), deep=True)
        array.SetName(name)
        mesh.GetCellData().AddArray(array)
    return mesh


if MODE == "prepare":
    from mpi_harness import write_mesh, write_pieces

    mesh = box_with_well(False)
    write_mesh(mesh, path("mesh.vtu"))
    write_pieces(mesh, path("mesh3"), 3, 0)
    write_pieces(mesh, path("mesh2"), 2, 0)
    write_mesh(box_with_well(True), path("shuffled.vtu"))

    chains("ref", XMLUnstructuredGridReader(FileName=[path("mesh.vtu")]))
    chains("ser_shuffled", XMLUnstructuredGridReader(FileName=[path("shuffled.vtu")]))
    print("prepared", flush=True)
elif MODE == "run":
    chains("par_pvtu3", XMLPartitionedUnstructuredGridReader(FileName=[path("mesh3.pvtu")]))
    chains("par_redist", RedistributeDataSet(
        Input=XMLUnstructuredGridReader(FileName=[path("mesh.vtu")])))
    chains("par_pvtu2", XMLPartitionedUnstructuredGridReader(FileName=[path("mesh2.pvtu")]))
    chains("par_shuffled", XMLUnstructuredGridReader(FileName=[path("shuffled.vtu")]))
else:
    sys.exit("mode must be prepare or run, not " + MODE)
