#!/usr/bin/env python3
"""Tests of vtkFractureTetMesh (Documentation/Pipeline.md, "Interactions", Fracture:
Voronoi pieces of seed points).

How to run (from a build tree; ctest sets the variables itself):

    PYTHONPATH=<build>/lib/python3.11/site-packages /usr/bin/python3 TestFracture.py

Every check is computed here from the input mesh and the seeds, not by the filter:
1. the pieces partition the original tets exactly once (the union of
   vtkOriginalCellIds is every id, no duplicate), and every tet is in the
   piece of the seed nearest its centroid (computed here);
2. every piece has compact points (no orphan), its tets have the original
   vertices (through vtkOriginalPointIds) and the original coordinates, its
   surface has no boundary edge (vtkDataSetSurfaceFilter + vtkFeatureEdges),
   and it solves alone (vtkSurfaceIrradiance -> vtkSolveDiffusion, no message);
3. recombination (vtkAppendFilter over the blocks, then vtkOriginalPointIds) gives back the
   original tets as sets of original point ids and the coefficients per
   original cell;
4. ids compose: a fracture of a stroke cut points at the uncut mesh;
5. random seeds are reproducible and give the requested number of seeds;
6. bad input (no seed, not a tet mesh, empty input) gives an error naming it.

Exits non-zero on failure (unittest). Runs in a few seconds on 2 cores.
"""

import unittest

import numpy as np

import translucency
from TestCut import Messages, plane, points_of, sphere_surface, tet_mesh, tets_of, update
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkPoints
from vtkmodules.vtkCommonDataModel import (
    VTK_HEXAHEDRON,
    vtkCompositeDataSet,
    vtkUnstructuredGrid,
)
from vtkmodules.vtkFiltersCore import vtkAppendFilter, vtkFeatureEdges
from vtkmodules.vtkFiltersGeometry import vtkDataSetSurfaceFilter

COEFFICIENTS = ("AbsorptionCoefficient", "ReducedScatteringCoefficient")
SEEDS = [(-5.0, -3.0, 0.0), (4.0, -2.0, 2.0), (0.5, 5.0, -3.0), (1.0, 0.0, 6.0)]


def fracture(grid, seeds=SEEDS):
    f = translucency.vtkFractureTetMesh()
    f.SetInputData(grid)
    for s in seeds:
        f.AddSeedPoint(*s)
    return f


def pieces_of(output):
    return [output.GetBlock(k) for k in range(output.GetNumberOfBlocks())]


def ids(data, name):
    return vtk_to_numpy(data.GetArray(name)).astype(np.int64)


def local_ids(data, name, count, values):
    """Positions in a data set of the original ids `values`, through its own
    map `name` (identity if it has none)."""
    if data.GetArray(name) is None:
        return values
    inverse = np.full(int(ids(data, name).max()) + 1, -1, dtype=np.int64)
    inverse[ids(data, name)] = np.arange(count)
    return inverse[values]


def centroids(grid):
    return points_of(grid)[tets_of(grid)].mean(axis=1)


def nearest_seed(points, seeds):
    d = ((points[:, None, :] - np.asarray(seeds, float)[None, :, :]) ** 2).sum(axis=2)
    return np.argmin(d, axis=1)


class TestFracture(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.sphere = tet_mesh(sphere_surface(10.0, 16), 3000)

    def check_pieces(self, original, output, seeds):
        pieces = pieces_of(output)
        t0 = tets_of(original)
        p0 = points_of(original)
        owner = nearest_seed(centroids(original), seeds)
        self.assertEqual(len(pieces), len(np.unique(owner)))
        all_cells = []
        for k, piece in enumerate(pieces):
            self.assertEqual(output.GetMetaData(k).Get(vtkCompositeDataSet.NAME()), "piece_%d" % k)
            self.assertEqual(piece.GetFieldData().GetArray("FracturePiece").GetValue(0), k)
            seed = piece.GetFieldData().GetArray("FractureSeed").GetValue(0)
            # Ids local to `original` (the pieces' ids point at its origin).
            cids = local_ids(original.GetCellData(), "vtkOriginalCellIds",
                             original.GetNumberOfCells(),
                             ids(piece.GetCellData(), "vtkOriginalCellIds"))
            pids = local_ids(original.GetPointData(), "vtkOriginalPointIds",
                             original.GetNumberOfPoints(),
                             ids(piece.GetPointData(), "vtkOriginalPointIds"))
            self.assertTrue(np.all(cids >= 0) and np.all(pids >= 0))
            # Every tet of the piece belongs to this seed's Voronoi cell.
            self.assertTrue(np.all(owner[cids] == seed))
            # Compact points, original vertices, original coordinates.
            tets = tets_of(piece)
            self.assertEqual(len(np.unique(tets)), piece.GetNumberOfPoints())
            self.assertTrue(np.array_equal(np.sort(pids[tets], axis=1), np.sort(t0[cids], axis=1)))
            self.assertTrue(np.allclose(points_of(piece), p0[pids]))
            all_cells.append(cids)
            # Closed surface: no boundary edge.
            surface = vtkDataSetSurfaceFilter()
            surface.SetInputData(piece)
            edges = vtkFeatureEdges()
            edges.SetInputConnection(surface.GetOutputPort())
            edges.BoundaryEdgesOn()
            edges.FeatureEdgesOff()
            edges.NonManifoldEdgesOff()
            edges.ManifoldEdgesOff()
            edges.Update()
            self.assertGreater(surface.GetOutput().GetNumberOfCells(), 0)
            self.assertEqual(edges.GetOutput().GetNumberOfLines(), 0, "piece %d not closed" % k)
        # Exactly once.
        all_cells = np.concatenate(all_cells)
        self.assertEqual(len(all_cells), original.GetNumberOfCells())
        self.assertTrue(np.array_equal(np.sort(all_cells), np.arange(original.GetNumberOfCells())))
        return pieces

    def test_voronoi_partition(self):
        f = fracture(self.sphere)
        output = update(self, f)
        self.check_pieces(self.sphere, output, SEEDS)
        self.assertEqual(f.GetNumberOfPieces(), 4)

    def test_empty_cells_skipped(self):
        seeds = SEEDS + [(500.0, 0.0, 0.0)]  # far away: owns nothing
        output = update(self, fracture(self.sphere, seeds))
        self.assertEqual(output.GetNumberOfBlocks(), 4)
        self.check_pieces(self.sphere, output, seeds)

    def test_pieces_solve(self):
        output = update(self, fracture(self.sphere))
        for piece in pieces_of(output):
            irradiance = translucency.vtkSurfaceIrradiance()
            irradiance.SetInputData(piece)
            irradiance.SetUniformLightIrradiance(0.1)
            irradiance.AddDirectionalLight(0.0, 0.0, -1.0, 1.0)
            solve = translucency.vtkSolveDiffusion()
            solve.SetInputConnection(irradiance.GetOutputPort())
            result = update(self, irradiance, solve)
            fluence = vtk_to_numpy(result.GetPointData().GetArray("Fluence"))
            self.assertEqual(fluence.shape, (piece.GetNumberOfPoints(), 3))
            self.assertTrue(np.all(np.isfinite(fluence)))
            self.assertGreater(fluence.min(), 0.0)

    def test_recombination(self):
        f = fracture(self.sphere)
        output = update(self, f)
        merge = vtkAppendFilter()
        merge.MergePointsOff()
        for piece in pieces_of(output):
            merge.AddInputData(piece)
        merged = update(self, merge)
        self.assertEqual(merged.GetNumberOfCells(), self.sphere.GetNumberOfCells())
        pids = ids(merged.GetPointData(), "vtkOriginalPointIds")
        cids = ids(merged.GetCellData(), "vtkOriginalCellIds")
        order = np.argsort(cids)
        self.assertTrue(np.array_equal(cids[order], np.arange(self.sphere.GetNumberOfCells())))
        # Same tets as sets of original point ids.
        recombined = np.sort(pids[tets_of(merged)][order], axis=1)
        self.assertTrue(np.array_equal(recombined, np.sort(tets_of(self.sphere), axis=1)))
        # Same points: every original point, at its coordinates.
        self.assertTrue(np.array_equal(np.unique(pids), np.arange(self.sphere.GetNumberOfPoints())))
        self.assertTrue(np.allclose(points_of(merged), points_of(self.sphere)[pids]))
        # Same coefficients per original cell.
        for name in COEFFICIENTS:
            a = vtk_to_numpy(merged.GetCellData().GetArray(name))[order]
            b = vtk_to_numpy(self.sphere.GetCellData().GetArray(name))
            self.assertTrue(np.array_equal(a, b), name)

    def test_fracture_of_cut_composes_ids(self):
        cut = translucency.vtkStrokeCut()
        cut.SetInputData(self.sphere)
        cut.SetCutFunction(plane((3.0, 0.0, 0.0), (1.0, 0.0, 0.0)))
        f = translucency.vtkFractureTetMesh()
        f.SetInputConnection(cut.GetOutputPort())
        for s in SEEDS:
            f.AddSeedPoint(*s)
        output = update(self, cut, f)
        cutout = cut.GetOutput()
        self.check_pieces(cutout, output, SEEDS)  # no duplicate, full coverage of the cut
        t0 = tets_of(self.sphere)
        for piece in pieces_of(output):
            cids = ids(piece.GetCellData(), "vtkOriginalCellIds")
            pids = ids(piece.GetPointData(), "vtkOriginalPointIds")
            self.assertTrue(np.array_equal(np.sort(pids[tets_of(piece)], axis=1),
                                           np.sort(t0[cids], axis=1)))
        # The union is the cut's set of original cells.
        union = np.sort(np.concatenate([ids(p.GetCellData(), "vtkOriginalCellIds")
                                        for p in pieces_of(output)]))
        self.assertTrue(np.array_equal(union, np.sort(ids(cutout.GetCellData(), "vtkOriginalCellIds"))))

    def test_random_seeds(self):
        def run(count, seed):
            f = translucency.vtkFractureTetMesh()
            f.SetInputData(self.sphere)
            f.SetRandomSeeds(count, seed)
            output = update(self, f)
            return [ids(p.GetCellData(), "vtkOriginalCellIds") for p in pieces_of(output)]

        a, b, c = run(6, 7), run(6, 7), run(6, 8)
        self.assertEqual(len(a), 6)  # seeds are centroids: no cell is empty
        self.assertTrue(all(np.array_equal(x, y) for x, y in zip(a, b)))
        self.assertFalse(len(a) == len(c) and all(np.array_equal(x, y) for x, y in zip(a, c)))
        self.assertTrue(np.array_equal(np.sort(np.concatenate(a)),
                                       np.arange(self.sphere.GetNumberOfCells())))

    def update_expecting(self, algorithm, *fragments):
        messages = Messages(algorithm)
        try:
            algorithm.Update()
        finally:
            messages.remove()
        text = "\n".join(messages.errors)
        self.assertTrue(messages.errors, "no error reported")
        for fragment in fragments:
            self.assertIn(fragment, text)

    def test_bad_input(self):
        f = fracture(self.sphere, [])
        self.update_expecting(f, "no seed points", "AddSeedPoint")
        hexa = vtkUnstructuredGrid()
        points = vtkPoints()
        for z in (0, 1):
            for y, x in ((0, 0), (0, 1), (1, 1), (1, 0)):
                points.InsertNextPoint(x, y, z)
        hexa.SetPoints(points)
        hexa.InsertNextCell(VTK_HEXAHEDRON, 8, list(range(8)))
        self.update_expecting(fracture(hexa), "not a tet mesh")
        self.update_expecting(fracture(vtkUnstructuredGrid()), "empty input")
        # RemoveAllSeedPoints empties the list again.
        f = fracture(self.sphere)
        f.RemoveAllSeedPoints()
        self.assertEqual(f.GetNumberOfSeedPoints(), 0)
        self.update_expecting(f, "no seed points")


if __name__ == "__main__":
    unittest.main()
