#!/usr/bin/env python3
"""Tests of painting (vtkPaintScatteringCoefficients) and of deformation.

How to run (from a build tree; ctest sets the variables itself):

    PYTHONPATH=<build>/lib/python3.11/site-packages /usr/bin/python3 TestPaint.py

1. The PaintWeight array is Strength exp(-d^2 / (2 Width^2)) with d the distance
   from each tet centroid to the nearest stroke point, both computed here.
2. SET, MULTIPLY and ADD give the formulas of the class documentation, computed
   here from the weights; SET with strength 1 gives exactly the target at a tet
   whose centroid is the stroke point.
3. The channel mask leaves masked channels bit-identical.
4. Width 0 or Strength 0 change nothing (bit-identical arrays).
5. Bad input (no stroke points, negative width, no coefficient arrays) is an
   error naming the problem.
6. Deform (SPEC "Interactions"): a rigid rotation + translation of the points
   (vtkTransformFilter) and the same rotation of the light direction give the
   same fluence at every point (rel. 1e-8): the system is re-assembled on the
   moved mesh without re-tetrahedralisation.

Exits non-zero on failure (unittest).
"""

import unittest

import numpy as np

import translucency
from TestPipeline import Messages, array, points_of, sphere_surface, tets_of
from vtkmodules.vtkCommonDataModel import vtkUnstructuredGrid
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
              target_s=(0.18, 0.07, 0.03), mask=(1, 1, 1), grid=None):
        paint = translucency.vtkPaintScatteringCoefficients()
        paint.SetInputData(grid if grid is not None else self.grid)
        for p in stroke:
            paint.AddStrokePoint(*p)
        paint.SetWidth(width)
        paint.SetStrength(strength)
        paint.SetMode(mode)
        paint.SetTargetAbsorptionCoefficient(target_a)
        paint.SetTargetReducedScatteringCoefficient(target_s)
        paint.SetChannelMask(mask)
        messages = Messages(paint)
        try:
            paint.Update()
        finally:
            messages.remove()
        self.assertEqual(messages.errors + messages.pipeline_errors + messages.warnings, [])
        out = paint.GetOutput()
        return (array(out, "PaintWeight", cell=True), array(out, ABSORPTION, cell=True),
                array(out, SCATTERING, cell=True), out)

    def expected_weights(self, stroke, width, strength):
        d2 = ((self.centroids[:, None, :] - np.asarray(stroke)[None, :, :]) ** 2).sum(axis=2)
        return strength * np.exp(-d2.min(axis=1) / (2.0 * width ** 2))

    def test_weights_follow_the_gaussian(self):
        stroke = [(4.0, 0.0, 0.0), (3.0, 2.5, 0.0), (2.0, 3.5, 1.0)]
        w, a, s, out = self.paint(stroke, width=1.5, strength=0.7)
        expected = self.expected_weights(stroke, 1.5, 0.7)
        np.testing.assert_allclose(w, expected, rtol=1e-12, atol=1e-300)
        self.assertGreater(np.count_nonzero(w > 0.3), 5)
        self.assertGreater(np.count_nonzero(w < 1e-3), len(w) // 4)
        # The other arrays pass through (shallow copy).
        self.assertIsNotNone(out.GetCellData().GetArray("RefractiveIndex"))
        self.assertEqual(out.GetNumberOfPoints(), self.grid.GetNumberOfPoints())

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
