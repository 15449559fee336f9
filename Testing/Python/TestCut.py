#!/usr/bin/env python3
"""Tests of vtkStrokeCut (TransCut Sec. 5.1: cut, drop orphans, relax the cross-section).

How to run (from a build tree; ctest sets the variables itself):

    PYTHONPATH=<build>/lib/python3.11/site-packages /usr/bin/python3 TestCut.py

Every check is computed here from the input mesh and the cut function, not by
the filter:
1. after a cut (plane, box, sphere cutters) every output tet has positive
   volume and a minimum dihedral angle >= min(bound, its angle before the cut);
   only points of the removed side moved, and none crossed the surface; no
   output tet has its four ORIGINAL vertices on the removed side; every tet of
   the input not entirely on the removed side is kept; no orphan point;
   vtkOriginalCellIds / vtkOriginalPointIds map every output tet to an
   original tet with the same vertices, and the cell arrays follow;
2. a cut of a cut keeps the ids pointing at the original mesh;
3. InsideOut keeps the other side;
4. the pipeline still solves after a cut (irradiance -> diffusion, no message);
5. changing the cut function re-executes the filter (GetMTime);
6. bad input gives an error naming the problem; a cut that removes
   everything gives an empty output and a warning;
7. a seeded soak: 20 random plane cuts of a small mesh, the invariants after each;
8. a stroke (polyline + view direction): a straight stroke cuts like the plane
   through it, the removed side is the left of the stroke as the viewer sees
   it, a bent stroke at an oblique view keeps the invariants with the side
   computed here, and bad strokes (one point, zero view direction, a stroke
   along the view direction) are errors.

Exits non-zero on failure (unittest). Runs in a few seconds on 2 cores.
"""

import functools
import sys
import os
import math
import random
import unittest

import numpy as np

import translucency
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkPoints
from vtkmodules.vtkCommonDataModel import (
    VTK_HEXAHEDRON,
    VTK_POLY_LINE,
    vtkPolyData,
    vtkBox,
    vtkPlane,
    vtkSphere,
    vtkUnstructuredGrid,
)
from vtkmodules.vtkFiltersCore import vtkCleanPolyData, vtkTriangleFilter
from vtkmodules.vtkFiltersSources import vtkCubeSource, vtkSphereSource

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import vtk_chain  # noqa: E402

# The executive's "returned failure" error counts among the errors.
Messages = functools.partial(vtk_chain.Messages, executive="errors")

BOUND = 0.5  # default MinimumDihedralAngle (degrees)


def update(test, *algorithms):
    """Update the last algorithm, failing on any error or warning."""
    messages = Messages(*algorithms)
    try:
        algorithms[-1].Update()
    finally:
        messages.remove()
    test.assertEqual(messages.errors, [], "unexpected errors")
    test.assertEqual(messages.warnings, [], "unexpected warnings")
    return algorithms[-1].GetOutput()


def tet_mesh(surface, target, material=True):
    """A tet mesh of `surface` (with the marble coefficients as cell arrays)."""
    tetra = translucency.vtkTetrahedralizeSurface()
    tetra.SetInputConnection(surface.GetOutputPort())
    tetra.SetTargetNumberOfTets(target)
    last = tetra
    if material:
        assign = translucency.vtkAssignScatteringCoefficients()
        assign.SetInputConnection(tetra.GetOutputPort())
        assign.SetMaterialName("marble")
        last = assign
    last.Update()
    grid = vtkUnstructuredGrid()
    grid.DeepCopy(last.GetOutput())
    return grid


def sphere_surface(radius=10.0, resolution=20):
    source = vtkSphereSource()
    source.SetRadius(radius)
    source.SetThetaResolution(resolution)
    source.SetPhiResolution(resolution)
    return source


def box_surface(size=(20.0, 16.0, 12.0)):
    cube = vtkCubeSource()
    cube.SetXLength(size[0])
    cube.SetYLength(size[1])
    cube.SetZLength(size[2])
    triangles = vtkTriangleFilter()
    triangles.SetInputConnection(cube.GetOutputPort())
    clean = vtkCleanPolyData()
    clean.SetInputConnection(triangles.GetOutputPort())
    return clean


def points_of(grid):
    return vtk_to_numpy(grid.GetPoints().GetData()).astype(float).reshape(-1, 3)


def tets_of(grid):
    return vtk_to_numpy(grid.GetCells().GetConnectivityArray()).astype(np.int64).reshape(-1, 4)


def side_values(function, points, inside_out=False):
    """F at every point (F > 0: removed side), evaluated here point by point."""
    sign = -1.0 if inside_out else 1.0
    return np.array([sign * function.FunctionValue(tuple(p)) for p in points])


def signed_volumes(points, tets):
    a, b, c, d = (points[tets[:, k]] for k in range(4))
    return np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) / 6.0


def min_dihedral(points, tets):
    """Smallest of the six dihedral angles of every tet (degrees)."""
    p = [points[tets[:, k]] for k in range(4)]
    normals = []
    for k in range(4):
        q0, q1, q2 = p[(k + 1) % 4], p[(k + 2) % 4], p[(k + 3) % 4]
        n = np.cross(q1 - q0, q2 - q0)
        outward = np.where(np.einsum("ij,ij->i", n, p[k] - q0) > 0, -1.0, 1.0)
        n = n * (outward / np.linalg.norm(n, axis=1))[:, None]
        normals.append(n)
    angles = []
    for k in range(4):
        for l in range(k + 1, 4):
            cosine = np.clip(-np.einsum("ij,ij->i", normals[k], normals[l]), -1.0, 1.0)
            angles.append(np.degrees(np.arccos(cosine)))
    return np.min(np.array(angles), axis=0)


class StrokeSide:
    """The stroke's side function written here: project along d, signed 2D
    distance to the nearest segment (end segments extended), > 0 on the left
    as the viewer looking along d sees it (screen axes u, v with u x v = -d)."""

    def __init__(self, points, view_direction):
        d = np.asarray(view_direction, float)
        d /= np.linalg.norm(d)
        up = np.array([0.3, 1.0, 0.1])
        v = up - up.dot(d) * d
        v /= np.linalg.norm(v)
        u = np.cross(d, v)
        assert np.allclose(np.cross(u, v), -d)
        self.basis = np.array([u, v])
        self.stroke = np.asarray(points, float) @ self.basis.T

    def FunctionValue(self, x):
        q = self.basis @ np.asarray(x, float)
        best, side = math.inf, 0.0
        segments = len(self.stroke) - 1
        for s in range(segments):
            a, e = self.stroke[s], self.stroke[s + 1] - self.stroke[s]
            w = q - a
            t = w.dot(e) / e.dot(e)
            if s != 0:
                t = max(t, 0.0)
            if s + 1 != segments:
                t = min(t, 1.0)
            dist = np.linalg.norm(w - t * e)
            if dist < best:
                best, side = dist, e[0] * w[1] - e[1] * w[0]
        return best if side > 0 else -best


def polyline(points):
    data = vtkPolyData()
    pts = vtkPoints()
    for p in points:
        pts.InsertNextPoint(*p)
    data.SetPoints(pts)
    data.Allocate(1)
    data.InsertNextCell(VTK_POLY_LINE, len(points), list(range(len(points))))
    return data


def make_cut(grid, function, inside_out=False):
    cut = translucency.vtkStrokeCut()
    cut.SetInputData(grid)
    cut.SetCutFunction(function)
    cut.SetInsideOut(inside_out)
    return cut


def plane(origin, normal):
    p = vtkPlane()
    p.SetOrigin(*origin)
    p.SetNormal(*normal)
    return p


class CutTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        cls.sphere = tet_mesh(sphere_surface(), 4000)
        cls.box = tet_mesh(box_surface(), 3000)

    def check_invariants(self, original, output, function, inside_out=False, bound=BOUND):
        """The invariants of a cut of `original` (the uncut mesh) by `function`."""
        p0 = points_of(original)
        t0 = tets_of(original)
        f0 = side_values(function, p0, inside_out)
        removed = np.all(f0[t0] > 0, axis=1)
        p = points_of(output)
        t = tets_of(output)
        cids = vtk_to_numpy(output.GetCellData().GetArray("vtkOriginalCellIds")).astype(np.int64)
        pids = vtk_to_numpy(output.GetPointData().GetArray("vtkOriginalPointIds")).astype(np.int64)
        self.assertEqual(len(cids), len(t))
        self.assertEqual(len(pids), len(p))
        # Ids: every output tet is an original tet with the same vertices.
        self.assertTrue(np.array_equal(np.sort(pids[t], axis=1), np.sort(t0[cids], axis=1)),
                        "vtkOriginalCellIds / vtkOriginalPointIds disagree with the original tets")
        self.assertEqual(len(np.unique(cids)), len(cids), "a tet appears twice")
        # Exactly the tets not entirely on the removed side (of a direct cut).
        self.assertFalse(np.any(removed[cids]), "an output tet lies on the removed side")
        # No orphan point.
        self.assertEqual(len(np.unique(t)), len(p), "orphan points in the output")
        # Geometry after relaxation.
        volumes = signed_volumes(p, t)
        self.assertTrue(np.all(volumes > 0), "non-positive tet volume %g" % volumes.min())
        before = min_dihedral(p0, t0[cids])
        after = min_dihedral(p, t)
        worst = np.argmin(after - np.minimum(bound, before))
        self.assertTrue(np.all(after >= np.minimum(bound, before) - 1e-9),
                        "min dihedral %g below bound %g (was %g)"
                        % (after[worst], bound, before[worst]))
        # Only removed-side points moved, and none crossed the surface.
        moved = np.any(p != p0[pids], axis=1)
        self.assertTrue(np.all(f0[pids][moved] > 0), "a point of the kept side moved")
        f = side_values(function, p, inside_out)
        self.assertTrue(np.all(f[moved] >= 0), "a moved point crossed the cutting surface")
        return removed, cids, pids, moved

    def test_plane_cut_of_sphere(self):
        function = plane((1.0, 0.5, 0.0), (1.0, 0.3, -0.2))
        cut = make_cut(self.sphere, function)
        output = update(self, cut)
        removed, cids, pids, moved = self.check_invariants(self.sphere, output, function)
        self.assertEqual(len(cids), np.count_nonzero(~removed), "kept tets")
        self.assertGreater(np.count_nonzero(removed), 0)
        self.assertGreater(np.count_nonzero(moved), 0, "the relaxation moved nothing")
        self.assertEqual(cut.GetNumberOfMovedVertices(), np.count_nonzero(moved))
        self.assertLessEqual(cut.GetNumberOfBlockedVertices(), cut.GetNumberOfMovableVertices())
        self.assertGreaterEqual(cut.GetNumberOfBlockedVertices(), 0)
        # The cell arrays follow the tets.
        for name in ("AbsorptionCoefficient", "ReducedScatteringCoefficient", "RefractiveIndex"):
            original = vtk_to_numpy(self.sphere.GetCellData().GetArray(name))
            carried = vtk_to_numpy(output.GetCellData().GetArray(name))
            self.assertTrue(np.array_equal(carried, original[cids]), name)
        # Relaxation brings the cross-section closer to the plane.
        p0 = points_of(self.sphere)
        f_before = side_values(function, p0[pids][moved])
        f_after = side_values(function, points_of(output)[moved])
        self.assertLess(f_after.sum(), f_before.sum())

    def test_no_relaxation_keeps_points(self):
        function = plane((0.0, 0.0, 0.0), (0.0, 0.0, 1.0))
        cut = make_cut(self.sphere, function)
        cut.SetNumberOfRelaxationIterations(0)
        output = update(self, cut)
        _, _, pids, moved = self.check_invariants(self.sphere, output, function)
        self.assertFalse(np.any(moved))
        self.assertEqual(cut.GetNumberOfMovedVertices(), 0)

    def test_box_and_sphere_cutters(self):
        box = vtkBox()
        box.SetBounds(0.0, 20.0, 0.0, 20.0, -20.0, 20.0)
        ball = vtkSphere()
        ball.SetCenter(5.0, -3.0, 2.0)
        ball.SetRadius(6.0)
        for function in (box, ball):
            for inside_out in (False, True):
                with self.subTest(function=function.GetClassName(), inside_out=inside_out):
                    output = update(self, make_cut(self.box, function, inside_out))
                    removed, cids, _, _ = self.check_invariants(
                        self.box, output, function, inside_out)
                    self.assertEqual(len(cids), np.count_nonzero(~removed))

    def test_inside_out_flips(self):
        function = plane((0.5, 0.0, 0.0), (1.0, 0.0, 0.0))
        x = points_of(self.sphere)[:, 0] - 0.5
        t0 = tets_of(self.sphere)
        outputs = []
        for inside_out in (False, True):
            output = update(self, make_cut(self.sphere, function, inside_out))
            self.check_invariants(self.sphere, output, function, inside_out)
            outputs.append(output)
        kept = np.count_nonzero(~np.all(x[t0] > 0, axis=1))
        kept_inside_out = np.count_nonzero(~np.all(x[t0] < 0, axis=1))
        self.assertEqual(outputs[0].GetNumberOfCells(), kept)
        self.assertEqual(outputs[1].GetNumberOfCells(), kept_inside_out)
        # The kept halves lie on opposite sides.
        self.assertLess(points_of(outputs[0])[:, 0].mean(), 0.5)
        self.assertGreater(points_of(outputs[1])[:, 0].mean(), 0.5)

    def test_cut_of_cut_keeps_original_ids(self):
        first = plane((2.0, 0.0, 0.0), (1.0, 0.0, 0.0))
        second = plane((0.0, -1.0, 0.0), (0.2, -1.0, 0.0))
        cut1 = make_cut(self.sphere, first)
        cut1.SetNumberOfRelaxationIterations(0)
        cut2 = translucency.vtkStrokeCut()
        cut2.SetInputConnection(cut1.GetOutputPort())
        cut2.SetCutFunction(second)
        cut2.SetNumberOfRelaxationIterations(0)
        output = update(self, cut1, cut2)
        p0 = points_of(self.sphere)
        t0 = tets_of(self.sphere)
        cids = vtk_to_numpy(output.GetCellData().GetArray("vtkOriginalCellIds")).astype(np.int64)
        pids = vtk_to_numpy(output.GetPointData().GetArray("vtkOriginalPointIds")).astype(np.int64)
        t = tets_of(output)
        self.assertTrue(np.array_equal(np.sort(pids[t], axis=1), np.sort(t0[cids], axis=1)))
        self.assertTrue(np.array_equal(points_of(output), p0[pids]))
        # Kept: the tets removed by neither cut.
        f1 = side_values(first, p0)
        f2 = side_values(second, p0)
        expected = ~np.all(f1[t0] > 0, axis=1) & ~np.all(f2[t0] > 0, axis=1)
        self.assertTrue(np.array_equal(np.sort(cids), np.flatnonzero(expected)))
        # With relaxation, the second cut's invariants hold against its own input.
        cut2.SetNumberOfRelaxationIterations(10)
        cut1.SetNumberOfRelaxationIterations(10)
        output = update(self, cut1, cut2)
        pids = vtk_to_numpy(output.GetPointData().GetArray("vtkOriginalPointIds")).astype(np.int64)
        cids = vtk_to_numpy(output.GetCellData().GetArray("vtkOriginalCellIds")).astype(np.int64)
        self.assertTrue(np.array_equal(np.sort(pids[tets_of(output)], axis=1),
                                       np.sort(t0[cids], axis=1)))
        self.assertTrue(np.all(signed_volumes(points_of(output), tets_of(output)) > 0))

    def test_pipeline_solves_after_cut(self):
        function = plane((0.0, 0.0, 1.0), (0.3, 0.2, 1.0))
        cut = make_cut(self.sphere, function)
        irradiance = translucency.vtkSurfaceIrradiance()
        irradiance.SetInputConnection(cut.GetOutputPort())
        irradiance.SetUniformLightIrradiance(0.1)
        irradiance.AddDirectionalLight(0.0, 0.0, -1.0, 1.0)  # onto the cross-section
        solve = translucency.vtkSolveDiffusion()
        solve.SetInputConnection(irradiance.GetOutputPort())
        output = update(self, cut, irradiance, solve)
        fluence = vtk_to_numpy(output.GetPointData().GetArray("Fluence"))
        self.assertEqual(fluence.shape, (output.GetNumberOfPoints(), 3))
        self.assertTrue(np.all(np.isfinite(fluence)))
        self.assertGreater(fluence.min(), 0.0)
        self.assertTrue(all(solve.GetConverged(c) for c in range(3)))

    def test_function_change_reexecutes(self):
        function = plane((0.0, 0.0, 0.0), (1.0, 0.0, 0.0))
        cut = make_cut(self.sphere, function)
        n1 = update(self, cut).GetNumberOfCells()
        function.SetOrigin(5.0, 0.0, 0.0)  # only the function changes
        n2 = update(self, cut).GetNumberOfCells()
        self.assertGreater(n2, n1)
        self.assertGreaterEqual(cut.GetMTime(), function.GetMTime())

    def update_expecting(self, algorithm, kind, *fragments):
        messages = Messages(algorithm)
        try:
            algorithm.Update()
        finally:
            messages.remove()
        found = messages.errors if kind == "error" else messages.warnings
        text = "\n".join(found)
        self.assertTrue(found, "no %s reported" % kind)
        for fragment in fragments:
            self.assertIn(fragment, text)
        return algorithm.GetOutput()

    def test_bad_input(self):
        cut = translucency.vtkStrokeCut()
        cut.SetInputData(self.sphere)
        self.update_expecting(cut, "error", "no cut function",
                              "SetCutFunction or a stroke is required")
        # Not a tet mesh: one hexahedron.
        hexa = vtkUnstructuredGrid()
        points = vtkPoints()
        for z in (0, 1):
            for y, x in ((0, 0), (0, 1), (1, 1), (1, 0)):
                points.InsertNextPoint(x, y, z)
        hexa.SetPoints(points)
        hexa.InsertNextCell(VTK_HEXAHEDRON, 8, list(range(8)))
        cut = make_cut(hexa, plane((0, 0, 0), (1, 0, 0)))
        self.update_expecting(cut, "error", "not a tet mesh")
        # Everything removed: an empty output and a warning.
        cut = make_cut(self.sphere, plane((-100.0, 0.0, 0.0), (1.0, 0.0, 0.0)))
        output = self.update_expecting(cut, "warning", "removed the whole mesh")
        self.assertEqual(output.GetNumberOfCells(), 0)
        self.assertEqual(output.GetNumberOfPoints(), 0)
        # Nothing removed: the mesh comes back whole with identity ids.
        cut = make_cut(self.sphere, plane((100.0, 0.0, 0.0), (1.0, 0.0, 0.0)))
        output = update(self, cut)
        self.assertEqual(output.GetNumberOfCells(), self.sphere.GetNumberOfCells())
        self.assertTrue(np.array_equal(
            vtk_to_numpy(output.GetCellData().GetArray("vtkOriginalCellIds")),
            np.arange(self.sphere.GetNumberOfCells())))

    def test_soak_random_planes(self):
        mesh = tet_mesh(sphere_surface(8.0, 12), 1200, material=False)
        rng = random.Random(20261121)
        for k in range(20):
            normal = [rng.gauss(0.0, 1.0) for _ in range(3)]
            origin = [rng.uniform(-6.0, 6.0) for _ in range(3)]
            function = plane(origin, normal)
            cut = make_cut(mesh, function, inside_out=rng.random() < 0.5)
            cut.SetRelaxationFactor(rng.choice((0.1, 0.3, 0.5)))
            messages = Messages(cut)
            try:
                cut.Update()
            finally:
                messages.remove()
            self.assertEqual(messages.errors, [], "cut %d" % k)
            output = cut.GetOutput()
            with self.subTest(cut=k, origin=origin, normal=normal):
                if output.GetNumberOfCells() == 0:
                    self.assertTrue(messages.warnings)
                    continue
                self.assertEqual(messages.warnings, [])
                self.check_invariants(mesh, output, function, cut.GetInsideOut())

    def test_straight_stroke_is_a_plane(self):
        # Looking along -z (x right, y up), a stroke drawn left to right
        # removes what is above it: y > 0.
        stroke = polyline([(-20.0, 0.5, 3.0), (20.0, 0.5, 3.0)])
        for inside_out in (False, True):
            with self.subTest(inside_out=inside_out):
                by_stroke = make_cut(self.sphere, None, inside_out)
                by_stroke.SetStrokeData(stroke)
                by_stroke.SetViewDirection(0.0, 0.0, -1.0)
                by_stroke.SetNumberOfRelaxationIterations(0)
                by_plane = make_cut(self.sphere, plane((0.0, 0.5, 0.0), (0.0, 1.0, 0.0)),
                                    inside_out)
                by_plane.SetNumberOfRelaxationIterations(0)
                a = update(self, by_stroke)
                b = update(self, by_plane)
                self.assertTrue(np.array_equal(
                    vtk_to_numpy(a.GetCellData().GetArray("vtkOriginalCellIds")),
                    vtk_to_numpy(b.GetCellData().GetArray("vtkOriginalCellIds"))))
                mean_y = points_of(a)[:, 1].mean()
                if inside_out:
                    self.assertGreater(mean_y, 0.5)
                else:
                    self.assertLess(mean_y, 0.5)

    def test_bent_stroke_oblique_view(self):
        points = [(-15.0, -8.0, 2.0), (0.0, 3.0, 0.0), (2.0, 4.0, -1.0), (15.0, -6.0, 1.0)]
        view = (0.3, -0.2, -1.0)
        side = StrokeSide(points, view)
        for inside_out in (False, True):
            with self.subTest(inside_out=inside_out):
                cut = make_cut(self.sphere, None, inside_out)
                cut.SetStrokeData(polyline(points))
                cut.SetViewDirection(*view)
                output = update(self, cut)
                removed, cids, _, moved = self.check_invariants(
                    self.sphere, output, side, inside_out)
                self.assertEqual(len(cids), np.count_nonzero(~removed))
                self.assertGreater(np.count_nonzero(removed), 0)
                self.assertGreater(np.count_nonzero(moved), 0)
        # A stroke takes precedence over the cut function.
        cut = make_cut(self.sphere, plane((100.0, 0.0, 0.0), (1.0, 0.0, 0.0)))
        cut.SetStrokeData(polyline(points))
        cut.SetViewDirection(*view)
        self.check_invariants(self.sphere, update(self, cut), side)

    def test_bad_strokes(self):
        cases = (
            ([(0.0, 0.0, 0.0)], (0.0, 0.0, -1.0), "at least 2"),
            ([(0.0, 0.0, 0.0), (1.0, 0.0, 0.0)], (0.0, 0.0, 0.0), "view direction"),
            ([(0.0, 0.0, 0.0), (0.0, 0.0, 5.0)], (0.0, 0.0, -1.0), "single point"),
        )
        for points, view, fragment in cases:
            with self.subTest(fragment=fragment):
                cut = make_cut(self.sphere, None)
                cut.SetStrokeData(polyline(points))
                cut.SetViewDirection(*view)
                self.update_expecting(cut, "error", "bad stroke", fragment)


if __name__ == "__main__":
    unittest.main()
