#!/usr/bin/env python3
"""Tests of painting (vtkPaintScatteringCoefficients) and of deformation.

How to run (from a build tree; ctest sets the variables itself):

    PYTHONPATH=<build>/lib/python3.11/site-packages /usr/bin/python3 TestPaint.py

1. The PaintWeight array is Strength exp(-d^2 / (2 Width^2)) with d the distance
   from each tet centroid to the nearest stroke point, both computed here, and
   0 beyond the documented cut-off radius R = Width sqrt(2 ln(Strength /
   CutoffWeight)) (CutoffWeight 0: the exact Gaussian everywhere); the
   field-data array PaintedCellIds lists exactly the tets whose coefficients
   changed.
2. SET, MULTIPLY and ADD give the formulas of the class documentation, computed
   here from the weights; SET with strength 1 gives exactly the target at a tet
   whose centroid is the stroke point.
3. The channel mask leaves masked channels bit-identical.
4. Width 0 or Strength 0 change nothing (bit-identical arrays).
5. Bad input (no stroke points, negative width, no coefficient arrays) is an
   error naming the problem. StrokeIsPolyline paints along the line through
   two stroke points (the exact segment distance within Width / 8), not only
   around them.
6. Painting a cut mesh (TransCut, Sec. 5.2): with the cut mesh (translucency
   vtkStrokeCut, plane) on port 0 and the original on port 1 (OriginalMesh),
   the output is bit-identical to painting the original directly; a tet
   removed by the cut but near the stroke is painted; re-cutting the painted
   original gives coefficients equal to the painted ones via
   vtkOriginalCellIds; out-of-range ids are an error naming the first bad id.
7. Deform (Documentation/Pipeline.md, "Interactions"): a rigid rotation + translation of the points
   (vtkTransformFilter) and the same rotation of the light direction give the
   same fluence at every point (rel. 1e-8): the system is re-assembled on the
   moved mesh without re-tetrahedralisation.

Exits non-zero on failure (unittest).
"""

import unittest

import numpy as np

import translucency
from TestPipeline import Messages, array, points_of, sphere_surface, tets_of
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkPlane, vtkUnstructuredGrid
from vtkmodules.vtkCommonTransforms import vtkTransform
from vtkmodules.vtkFiltersGeneral import vtkTransformFilter

ABSORPTION = "AbsorptionCoefficient"
SCATTERING = "ReducedScatteringCoefficient"


def marble_mesh(target_tets=2000):
    """A marble sphere of radius 5 mm, tetrahedralised, with its coefficients."""
    tetra = translucency.vtkTetrahedralizeSurface()
    tetra.SetInputData(sphere_surface())
    tetra.SetTargetNumberOfTets(target_tets)
    assign = translucency.vtkAssignScatteringCoefficients()
    assign.SetInputConnection(tetra.GetOutputPort())
    assign.SetMaterialName("marble")
    assign.Update()
    grid = vtkUnstructuredGrid()
    grid.ShallowCopy(assign.GetOutput())
    return grid


def centroids(grid):
    return points_of(grid)[tets_of(grid)].mean(axis=1)


class PaintTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        cls.grid = marble_mesh()
        cls.centroids = centroids(cls.grid)
        cls.old_a = array(cls.grid, ABSORPTION, cell=True).copy()
        cls.old_s = array(cls.grid, SCATTERING, cell=True).copy()

    def paint(self, stroke, width=1.5, strength=1.0, mode=0, target_a=(0.061, 0.97, 1.45),
              target_s=(0.18, 0.07, 0.03), mask=(1, 1, 1), grid=None, original=None,
              cutoff=None, polyline=False):
        paint = translucency.vtkPaintScatteringCoefficients()
        paint.SetStrokeIsPolyline(polyline)
        paint.SetInputData(grid if grid is not None else self.grid)
        if original is not None:
            paint.SetOriginalMeshData(original)
        for p in stroke:
            paint.AddStrokePoint(*p)
        paint.SetWidth(width)
        paint.SetStrength(strength)
        paint.SetMode(mode)
        paint.SetTargetAbsorptionCoefficient(target_a)
        paint.SetTargetReducedScatteringCoefficient(target_s)
        paint.SetChannelMask(mask)
        if cutoff is not None:
            paint.SetCutoffWeight(cutoff)
        messages = Messages(paint)
        try:
            paint.Update()
        finally:
            messages.remove()
        self.assertEqual(messages.errors + messages.pipeline_errors + messages.warnings, [])
        out = paint.GetOutput()
        return (array(out, "PaintWeight", cell=True), array(out, ABSORPTION, cell=True),
                array(out, SCATTERING, cell=True), out)

    def expected_weights(self, stroke, width, strength, cutoff=1e-6):
        d2 = ((self.centroids[:, None, :] - np.asarray(stroke)[None, :, :]) ** 2).sum(axis=2)
        d2 = d2.min(axis=1)
        w = strength * np.exp(-d2 / (2.0 * width ** 2))
        if cutoff > 0.0:
            # The documented cut-off radius: w(R) = cutoff.
            w[d2 > 2.0 * width ** 2 * np.log(strength / cutoff)] = 0.0
        return w

    def test_weights_follow_the_gaussian(self):
        stroke = [(4.0, 0.0, 0.0), (3.0, 2.5, 0.0), (2.0, 3.5, 1.0)]
        w, a, s, out = self.paint(stroke, width=1.5, strength=0.7)
        expected = self.expected_weights(stroke, 1.5, 0.7)
        np.testing.assert_allclose(w, expected, rtol=1e-12, atol=1e-300)
        self.assertGreater(np.count_nonzero(w > 0.3), 5)
        self.assertGreater(np.count_nonzero(w < 1e-3), len(w) // 4)
        # A narrower stroke: many tets lie beyond the cut-off radius.
        w1, _, _, _ = self.paint(stroke, width=0.8, strength=0.7)
        np.testing.assert_allclose(w1, self.expected_weights(stroke, 0.8, 0.7),
                                   rtol=1e-12, atol=1e-300)
        self.assertGreater(np.count_nonzero(w1 == 0.0), len(w1) // 10)
        changed = np.flatnonzero(np.any((a != self.old_a) | (s != self.old_s), axis=1))
        ids = vtk_to_numpy(out.GetFieldData().GetArray("PaintedCellIds"))
        np.testing.assert_array_equal(ids, changed)
        # CutoffWeight 0: the exact Gaussian at every tet.
        w0, _, _, _ = self.paint(stroke, width=1.5, strength=0.7, cutoff=0.0)
        np.testing.assert_allclose(w0, self.expected_weights(stroke, 1.5, 0.7, cutoff=0.0),
                                   rtol=1e-12, atol=1e-300)
        self.assertEqual(np.count_nonzero(w0 == 0.0), 0)
        # The other arrays pass through (shallow copy).
        self.assertIsNotNone(out.GetCellData().GetArray("RefractiveIndex"))
        self.assertEqual(out.GetNumberOfPoints(), self.grid.GetNumberOfPoints())

    def test_polyline_stroke_paints_along_the_line(self):
        # Two handles 8 mm apart (the ParaView polyline widget): as points they
        # paint only near the ends; as a polyline, along the whole segment,
        # with d_t within Width / 8 of the distance to the segment, so the
        # weight within a factor exp(-1/128) of the exact one, never above it.
        a, b = np.array([-4.0, 0.0, 0.0]), np.array([4.0, 0.0, 0.0])
        width = 0.8
        w_points, _, _, _ = self.paint([a, b], width=width, cutoff=0.0)
        np.testing.assert_allclose(w_points, self.expected_weights([a, b], width, 1.0, 0.0),
                                   rtol=1e-12, atol=1e-300)
        w_line, _, _, _ = self.paint([a, b], width=width, cutoff=0.0, polyline=True)
        t = np.clip((self.centroids - a) @ (b - a) / ((b - a) @ (b - a)), 0.0, 1.0)
        nearest = a + t[:, None] * (b - a)
        exact = np.exp(-((self.centroids - nearest) ** 2).sum(axis=1) / (2.0 * width ** 2))
        self.assertTrue(np.all(w_line <= exact * (1 + 1e-12)))
        self.assertTrue(np.all(w_line >= exact * np.exp(-1.0 / 128.0) * (1 - 1e-12)))
        middle = (np.abs(self.centroids[:, 0]) < 1.0) & (exact > 0.5)  # >= 3 mm from the ends
        self.assertGreater(np.count_nonzero(middle), 3)
        self.assertTrue(np.all(w_line[middle] > 0.49))
        self.assertTrue(np.all(w_points[middle] < 1e-3))  # the points alone miss the middle

    def test_set_multiply_add(self):
        stroke = [(0.0, 0.0, 4.0)]
        ta, ts = np.array([0.05, 0.5, 1.0]), np.array([0.3, 0.2, 0.1])
        wexp = self.expected_weights(stroke, 2.0, 0.9)[:, None]
        w, a, s, _ = self.paint(stroke, width=2.0, strength=0.9, mode=0, target_a=ta, target_s=ts)
        np.testing.assert_allclose(a, (1 - wexp) * self.old_a + wexp * ta, rtol=1e-12)
        np.testing.assert_allclose(s, (1 - wexp) * self.old_s + wexp * ts, rtol=1e-12)
        fa, fs = np.array([10.0, 2.0, 0.5]), np.array([0.5, 1.0, 3.0])
        w, a, s, _ = self.paint(stroke, width=2.0, strength=0.9, mode=1, target_a=fa, target_s=fs)
        np.testing.assert_allclose(a, self.old_a * (1 + wexp * (fa - 1)), rtol=1e-12)
        np.testing.assert_allclose(s, self.old_s * (1 + wexp * (fs - 1)), rtol=1e-12)
        da, ds = np.array([0.01, -0.001, 0.0]), np.array([1.0, -10.0, 0.5])
        w, a, s, _ = self.paint(stroke, width=2.0, strength=0.9, mode=2, target_a=da, target_s=ds)
        np.testing.assert_allclose(a, np.maximum(self.old_a + wexp * da, 0.0), rtol=1e-12)
        np.testing.assert_allclose(s, np.maximum(self.old_s + wexp * ds, 0.0), rtol=1e-12)
        self.assertTrue(np.all(a + s > 0.0))
        self.assertTrue(np.any(s[:, 1] == 0.0), "a large negative ADD is clamped to 0")

    def test_set_at_a_centroid_gives_the_target(self):
        t = 17
        stroke = [tuple(self.centroids[t])]
        ta, ts = (0.061, 0.97, 1.45), (0.18, 0.07, 0.03)
        w, a, s, _ = self.paint(stroke, width=0.5, strength=1.0, mode=0, target_a=ta, target_s=ts)
        d = np.linalg.norm(self.centroids - self.centroids[t], axis=1)
        at = np.nonzero(d == 0.0)[0]
        self.assertIn(t, at)
        for k in at:
            self.assertEqual(w[k], 1.0)
            self.assertEqual(tuple(a[k]), ta)
            self.assertEqual(tuple(s[k]), ts)

    def test_channel_mask(self):
        stroke = [(0.0, 0.0, 0.0)]
        w, a, s, _ = self.paint(stroke, width=3.0, mask=(1, 0, 1))
        np.testing.assert_array_equal(a[:, 1], self.old_a[:, 1])
        np.testing.assert_array_equal(s[:, 1], self.old_s[:, 1])
        self.assertTrue(np.any(a[:, 0] != self.old_a[:, 0]))
        self.assertTrue(np.any(s[:, 2] != self.old_s[:, 2]))

    def test_zero_width_or_strength_changes_nothing(self):
        stroke = [tuple(self.centroids[3]), (0.0, 0.0, 0.0)]
        for width, strength in ((0.0, 1.0), (2.0, 0.0), (0.0, 0.0)):
            for mode in (0, 1, 2):
                w, a, s, _ = self.paint(stroke, width=width, strength=strength, mode=mode)
                np.testing.assert_array_equal(w, 0.0)
                np.testing.assert_array_equal(a, self.old_a)
                np.testing.assert_array_equal(s, self.old_s)

    def update_expecting_error(self, algorithm, *fragments):
        messages = Messages(algorithm)
        try:
            algorithm.Update()
        finally:
            messages.remove()
        self.assertEqual(len(messages.errors), 1, messages.errors)
        for fragment in fragments:
            self.assertIn(fragment.lower(), messages.errors[0].lower())
        self.assertTrue(messages.pipeline_errors)

    def test_bad_input(self):
        paint = translucency.vtkPaintScatteringCoefficients()
        paint.SetInputData(self.grid)
        self.update_expecting_error(paint, "no stroke points")
        paint.AddStrokePoint(0.0, 0.0, 0.0)
        paint.SetWidth(-1.0)
        self.update_expecting_error(paint, "width", "-1")
        paint.SetWidth(1.0)
        bare = vtkUnstructuredGrid()
        bare.ShallowCopy(self.grid)
        bare.GetCellData().RemoveArray(SCATTERING)
        paint.SetInputData(bare)
        self.update_expecting_error(paint, SCATTERING)
        bare.GetCellData().RemoveArray(ABSORPTION)
        bare.Modified()
        self.update_expecting_error(paint, ABSORPTION)


def plane_cut(grid, origin=(0.0, 0.0, 0.0), normal=(1.0, 0.0, 0.0)):
    """Cut away the side of the plane its normal points to (vtkStrokeCut)."""
    function = vtkPlane()
    function.SetOrigin(*origin)
    function.SetNormal(*normal)
    cut = translucency.vtkStrokeCut()
    cut.SetInputData(grid)
    cut.SetCutFunction(function)
    messages = Messages(cut)
    try:
        cut.Update()
    finally:
        messages.remove()
    assert not messages.errors + messages.pipeline_errors, messages.errors
    out = vtkUnstructuredGrid()
    out.ShallowCopy(cut.GetOutput())
    return out


def original_cell_ids(grid):
    return vtk_to_numpy(grid.GetCellData().GetArray("vtkOriginalCellIds")).astype(np.int64)


class PaintCutMeshTest(unittest.TestCase):
    """Painting on the cross-section of a cut mesh changes the original tets."""

    # The helpers of PaintTest, without re-running its tests.
    paint = PaintTest.paint
    update_expecting_error = PaintTest.update_expecting_error

    @classmethod
    def setUpClass(cls):
        PaintTest.setUpClass.__func__(cls)
        cls.cut = plane_cut(cls.grid)
        cls.ids = original_cell_ids(cls.cut)
        assert 0 < cls.cut.GetNumberOfCells() < cls.grid.GetNumberOfCells()
        # A stroke on the cross-section x = 0.
        cls.stroke = [(0.0, -1.0, 0.0), (0.0, 0.5, 1.0), (0.0, 2.0, 1.5)]

    def test_paints_the_original_bit_identically(self):
        for mode, ta, ts in ((0, (0.061, 0.97, 1.45), (0.18, 0.07, 0.03)),
                             (1, (10.0, 2.0, 0.5), (0.5, 1.0, 3.0)),
                             (2, (0.01, -0.001, 0.0), (1.0, -10.0, 0.5))):
            direct = self.paint(self.stroke, width=1.5, strength=0.8, mode=mode,
                                target_a=ta, target_s=ts)
            via = self.paint(self.stroke, width=1.5, strength=0.8, mode=mode, target_a=ta,
                             target_s=ts, grid=self.cut, original=self.grid)
            self.assertEqual(via[3].GetNumberOfCells(), self.grid.GetNumberOfCells())
            self.assertEqual(via[3].GetNumberOfPoints(), self.grid.GetNumberOfPoints())
            for a, b in zip(direct[:3], via[:3]):
                np.testing.assert_array_equal(a, b)
            self.assertIsNotNone(via[3].GetCellData().GetArray("RefractiveIndex"))

    def test_removed_tet_near_the_stroke_is_painted(self):
        w, a, s, _ = self.paint(self.stroke, width=1.5, strength=1.0, grid=self.cut,
                                original=self.grid)
        removed = np.setdiff1d(np.arange(self.grid.GetNumberOfCells()), self.ids)
        self.assertGreater(len(removed), 0)
        self.assertTrue(np.all(self.centroids[removed, 0] > 0.0))
        near = removed[w[removed] > 0.5]
        self.assertGreater(len(near), 0, "no removed tet near the stroke was painted")
        for k in near[:5]:
            self.assertTrue(np.all(a[k] != self.old_a[k]))
            self.assertTrue(np.all(s[k] != self.old_s[k]))

    def test_recut_carries_the_painted_values(self):
        w, a, s, painted = self.paint(self.stroke, width=1.5, strength=1.0, grid=self.cut,
                                      original=self.grid)
        recut = plane_cut(painted)
        ids = original_cell_ids(recut)
        np.testing.assert_array_equal(ids, self.ids)
        np.testing.assert_array_equal(array(recut, ABSORPTION, cell=True), a[ids])
        np.testing.assert_array_equal(array(recut, SCATTERING, cell=True), s[ids])
        self.assertTrue(np.any(array(recut, ABSORPTION, cell=True) != self.old_a[ids]))

    def test_bad_original_cell_ids(self):
        n = self.grid.GetNumberOfCells()
        for bad in (n, -3):
            broken = vtkUnstructuredGrid()
            broken.ShallowCopy(self.cut)
            ids = self.ids.copy()
            ids[7] = bad
            vtk_ids = numpy_to_vtk(ids, deep=True)
            vtk_ids.SetName("vtkOriginalCellIds")
            broken.GetCellData().AddArray(vtk_ids)
            paint = translucency.vtkPaintScatteringCoefficients()
            paint.SetInputData(broken)
            paint.SetOriginalMeshData(self.grid)
            paint.AddStrokePoint(0.0, 0.0, 0.0)
            self.update_expecting_error(paint, "vtkOriginalCellIds", str(bad), "cell 7", str(n))
        # A mesh that is not a cut of the original (no ids, other size).
        bare = vtkUnstructuredGrid()
        bare.ShallowCopy(self.cut)
        bare.GetCellData().RemoveArray("vtkOriginalCellIds")
        paint = translucency.vtkPaintScatteringCoefficients()
        paint.SetInputData(bare)
        paint.SetOriginalMeshData(self.grid)
        paint.AddStrokePoint(0.0, 0.0, 0.0)
        self.update_expecting_error(paint, "vtkOriginalCellIds")
        # Disconnecting port 1 paints port 0 as before.
        paint.SetOriginalMeshData(None)
        w, a, s, out = self.paint(self.stroke, grid=bare)
        self.assertEqual(out.GetNumberOfCells(), bare.GetNumberOfCells())


class DeformTest(unittest.TestCase):

    def solve(self, grid, direction):
        irradiance = translucency.vtkSurfaceIrradiance()
        irradiance.SetInputData(grid)
        irradiance.SetShadows(False)
        irradiance.SetUniformLightIrradiance(0.0)
        irradiance.SetUniformLightSamples(0)
        irradiance.AddDirectionalLight(*direction, 1.0)
        solve = translucency.vtkSolveDiffusion()
        solve.SetInputConnection(irradiance.GetOutputPort())
        solve.SetRelTol(1e-13)
        solve.SetMaxIter(10000)
        messages = Messages(irradiance, solve)
        try:
            solve.Update()
        finally:
            messages.remove()
        self.assertEqual(messages.errors + messages.pipeline_errors + messages.warnings, [])
        for c in range(3):
            self.assertTrue(solve.GetConverged(c))
        return solve.GetOutput()

    def test_rigid_motion_keeps_the_fluence(self):
        grid = marble_mesh(3000)
        direction = np.array([0.3, -1.0, -0.5])
        before = self.solve(grid, direction)
        transform = vtkTransform()
        transform.Translate(3.0, -2.0, 7.5)
        transform.RotateWXYZ(37.0, 1.0, 2.0, 0.5)
        move = vtkTransformFilter()
        move.SetInputData(grid)
        move.SetTransform(transform)
        move.Update()
        moved = move.GetOutput()
        # Same topology, moved points: no re-tetrahedralisation.
        np.testing.assert_array_equal(tets_of(moved), tets_of(grid))
        self.assertGreater(np.max(np.abs(points_of(moved) - points_of(grid))), 1.0)
        rotation = np.array([[transform.GetMatrix().GetElement(i, j) for j in range(3)]
                             for i in range(3)])
        after = self.solve(moved, rotation @ direction)
        phi0 = array(before, "Fluence")
        phi1 = array(after, "Fluence")
        self.assertGreater(np.min(phi0), 0.0)
        np.testing.assert_allclose(phi1, phi0, rtol=1e-8, atol=0.0)


if __name__ == "__main__":
    unittest.main(verbosity=2)
