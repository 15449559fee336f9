#!/usr/bin/env python3
"""The plugin's filters under MPI give the serial fields (Documentation/Parallel.md).

How to run (ctest does this, with 2 and with 3 ranks):

    /usr/bin/python3 TestParallel.py <Translucency plugin> <number of ranks>

1. `pvbatch ParallelPipeline.py ... prepare` (one process) writes the meshes,
   their partitioned copies and the serial results (the references).
2. `mpiexec --allow-run-as-root --oversubscribe -n N pvbatch ParallelPipeline.py
   ... run` runs the same chains on distributed data: a PLY surface read by
   rank 0 only (the other ranks have empty pieces in every filter), a .pvtu
   in 2 pieces with ghost cells (with 3 ranks, one rank has no piece), a .pvtu
   in 3 pieces with point and cell GlobalIds (also cut, with the
   order-dependent uniform-light sampling on), the output of Redistribute DataSet, and a
   plane cut of the mesh read by rank 0, redistributed after the cut, and a
   paint after Redistribute DataSet.
3. Here: at every point of every rank's piece (shared points included, each
   rank's copy checked), Fluence equals the serial Fluence at the same
   coordinates to a relative 1e-6; the Outgoing Radiance surface has the serial
   number of faces and area and the serial Radiance at every point; the pieces
   stay distributed (more than one non-empty piece where the input was split);
   Solve Diffusion without Irradiance fails with the same message on every
   rank; Fracture Tet Mesh and Translucent Radiosity (results on rank 0) and a
   Volume material from an image split by extent give the serial totals;
   Detector Readings after a redistributed Solve Diffusion gives the serial
   table once (rows on rank 0 only), not once per rank;
   nothing hangs (each run has a time limit) and no other error is logged.

Exits non-zero on failure (unittest).
"""

import os
import sys

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkFiltersVerdict import vtkCellSizeFilter

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mpi_harness import RANKS, MpiSuite, main, pieces_of  # noqa: E402


def by_point(pieces, name):
    """{coordinates: values} over every point of every piece. The coordinates
    are rounded to float: the partitioned files (vtkExtractUnstructuredGridPiece)
    store float points, the others double; the sphere's points are far apart."""
    table = {}
    for piece in pieces:
        if piece.GetNumberOfPoints() == 0:
            continue
        x = vtk_to_numpy(piece.GetPoints().GetData()).astype(np.float32)
        values = vtk_to_numpy(piece.GetPointData().GetArray(name))
        for xi, vi in zip(map(tuple, x), values):
            table.setdefault(xi, []).append(vi)
    return table


def surface_area(pieces):
    area = 0.0
    for piece in pieces:
        if piece.GetNumberOfCells() == 0:
            continue
        sizes = vtkCellSizeFilter()
        sizes.SetInputData(piece)
        sizes.Update()
        area += vtk_to_numpy(sizes.GetOutput().GetCellData().GetArray("Area")).sum()
    return area


class ParallelTest(MpiSuite):
    SCRIPT = "ParallelPipeline.py"
    PREPARED = "summary radiosity"
    SYMMETRIC = False
    # Ceilings that tell a hang from a slow run: idle, prepare takes ~10 s and
    # run ~15 s; at a load average of 15 on 2 cores prepare alone took over 60 s.
    TIME_LIMIT = {"prepare": 150, "run": 200}

    def path(self, name):
        return os.path.join(self.work, name)

    def check_fluence(self, case, reference, split):
        pieces = pieces_of(self.path("par_%s.pvtu" % case))
        ref_pieces = pieces_of(self.path("ref_%s.pvtu" % reference))
        ref = {x: v[0] for x, v in by_point(ref_pieces, "Fluence").items()}
        self.assertEqual(len(ref), sum(p.GetNumberOfPoints() for p in ref_pieces))
        got = by_point(pieces, "Fluence")
        self.assertEqual(set(got), set(ref), "the points of the serial mesh, no other")
        worst = 0.0
        for x, values in got.items():
            for v in values:  # each rank's copy of a shared point
                worst = max(worst, np.max(np.abs(v - ref[x]) / np.abs(ref[x])))
        self.assertLessEqual(worst, 1e-6, "max relative Fluence difference, case " + case)
        nonempty = sum(1 for p in pieces if p.GetNumberOfCells() > 0)
        if split:
            self.assertGreater(nonempty, 1, "the pieces stay on their ranks")
        return worst

    def check_surface(self, case, reference):
        got = pieces_of(self.path("par_%s_surface.pvtp" % case))
        ref = pieces_of(self.path("ref_%s_surface.pvtp" % reference))
        faces = lambda pieces: sum(p.GetNumberOfCells() for p in pieces)  # noqa: E731
        self.assertEqual(faces(got), faces(ref), "boundary faces, case " + case)
        self.assertAlmostEqual(surface_area(got) / surface_area(ref), 1.0, delta=1e-6)
        ref_radiance = {x: v[0] for x, v in by_point(ref, "Radiance").items()}
        for x, values in by_point(got, "Radiance").items():
            for v in values:
                np.testing.assert_allclose(v, ref_radiance[x], rtol=1e-6, atol=1e-12)

    def test_0_runs(self):
        self.assertEqual(self.result.returncode, 0, self.result.stderr[-3000:])
        for case in ("ply", "pvtu2", "pvtu3", "sp3", "redist", "cut", "paint", "cutids",
                     "overlap", "error"):
            self.assertIn("case %s done" % case, self.result.stdout)

    def test_surface_read_by_one_rank(self):
        self.check_fluence("ply", "ply", split=False)
        self.check_surface("ply", "ply")

    def test_pvtu_with_ghost_cells(self):
        self.check_fluence("pvtu2", "mesh", split=True)
        self.check_surface("pvtu2", "mesh")

    def test_sp3_and_its_radiance(self):
        # sp3 (solved gathered) gives the serial Fluence on every piece, and
        # Outgoing Radiance per piece reads its moments (SP3Phi1, SP3Phi2)
        # into the serial P3 radiance.
        self.check_fluence("sp3", "sp3", split=True)
        self.check_surface("sp3", "sp3")
        pieces = pieces_of(self.path("par_sp3.pvtu"))
        self.assertTrue(all(p.GetPointData().GetArray("SP3Phi1") is not None
                            for p in pieces if p.GetNumberOfPoints() > 0))

    def test_overlapping_pieces_without_ghost_marks(self):
        # The gather takes a tet that two pieces both bring once (only the
        # cells on points of more than one piece are matched).
        pieces = pieces_of(self.path("par_overlap.pvtu"))
        ref = pieces_of(self.path("ref_mesh.pvtu"))
        self.assertGreater(sum(p.GetNumberOfCells() for p in pieces),
                           sum(p.GetNumberOfCells() for p in ref), "the pieces overlap")
        self.check_fluence("overlap", "mesh", split=True)

    def test_pvtu_with_global_ids(self):
        self.check_fluence("pvtu3", "mesh", split=True)
        self.check_surface("pvtu3", "mesh")

    def test_redistribute(self):
        self.check_fluence("redist", "mesh", split=True)
        self.check_surface("redist", "mesh")

    def test_cut_and_paint(self):
        self.check_fluence("cut", "cut", split=True)
        self.check_fluence("paint", "paint", split=True)

    def test_global_ids_give_the_serial_order(self):
        # Cut relaxation and uniform-light sampling follow the point order.
        self.check_fluence("cutids", "cutids", split=False)

    def test_fracture_radiosity_volume(self):
        # Computed on rank 0 in the serial order: the serial totals and ranges;
        # the Volume image arrives in extents from every rank.
        def summaries(text):
            return sorted(line for line in text.splitlines() if line.startswith("summary "))
        serial = summaries(self.prepare.stdout)
        self.assertEqual(len(serial), 3, self.prepare.stdout)
        self.assertEqual(summaries(self.result.stdout), serial)

    def test_detector_table_once(self):
        # Detector Readings fills its table on rank 0 only: fetched (appended
        # over the ranks) it has the serial rows, not one copy per rank.
        def lines(text):
            return [line for line in text.splitlines() if line.startswith("detectors: ")]
        serial = lines(self.prepare.stdout)
        self.assertEqual(len(serial), 1, self.prepare.stdout)
        self.assertTrue(serial[0].startswith("detectors: 2 rows"), serial[0])
        self.assertEqual(lines(self.result.stdout), serial)

    def test_errors(self):
        # The one expected error, once per rank with the same text; no other.
        self.assert_error_on_every_rank("the input has no point array 'Irradiance'",
                                        failures=RANKS)


if __name__ == "__main__":
    main()
