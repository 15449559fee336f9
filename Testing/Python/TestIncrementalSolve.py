#!/usr/bin/env python3
"""Tests of the incremental assembly of vtkSolveDiffusion after a paint.

How to run (from a build tree; ctest sets the variables itself):

    PYTHONPATH=<build>/lib/python3.11/site-packages /usr/bin/python3 TestIncrementalSolve.py

1. Lights -> paint -> solve: the first solve assembles in full; after a paint
   stroke (same mesh, same irradiance) the solve reports "incremental", found
   exactly the tets the paint filter lists in PaintedCellIds, and its fluence
   equals a from-scratch solve by a new filter (both to RelTol 1e-12).
2. Coefficients changed by hand (not by the paint filter) are detected too.
3. Another light (other irradiance, same material): only the right-hand
   side is rebuilt ("right-hand side"), the fluence equals a from-scratch
   solve, and the paint filter did not paint again (its arrays re-used).
4. Falls back to a full assembly: a cut (topology change), too many changed
   tets (beyond MaximumChangedFraction), IncrementalAssembly off.
5. A relight (the input carries the same coefficient arrays, unmodified)
   neither copies, validates nor compares the material (the filter's
   counters stay; issue 31), and its fluence equals a from-scratch solve; a
   paint stroke (new arrays) and an array modified in place are compared
   with the kept material in place (no copy); an invalid painted value is an
   error naming its tet, and the next valid input solves as from scratch.

Exits non-zero on failure (unittest).
"""

import unittest

import numpy as np

import translucency
from TestPaint import ABSORPTION, marble_mesh, plane_cut
from TestPipeline import Messages, array
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkUnstructuredGrid


def run(*algorithms):
    """Update the last algorithm; fail on any error or warning."""
    messages = Messages(*algorithms)
    try:
        algorithms[-1].Update()
    finally:
        messages.remove()
    assert not messages.errors + messages.pipeline_errors + messages.warnings, (
        messages.errors + messages.warnings)


def new_solver():
    solve = translucency.vtkSolveDiffusion()
    solve.SetRelTol(1e-12)
    solve.SetMaxIter(20000)
    return solve


class IncrementalSolveTest(unittest.TestCase):

    def setUp(self):
        self.grid = marble_mesh(3000)
        self.lights = translucency.vtkSurfaceIrradiance()
        self.lights.SetInputData(self.grid)
        self.lights.SetShadows(False)
        self.lights.SetUniformLightIrradiance(0.0)
        self.lights.SetUniformLightSamples(0)
        self.lights.AddDirectionalLight(0.3, -1.0, -0.5, 1.0)
        # The surface model: the extended models' volume source changes with
        # every painted coefficient, so they always assemble in full.
        self.lights.SetCollimatedModel(self.lights.COLLIMATED_SURFACE)
        self.paint = translucency.vtkPaintScatteringCoefficients()
        self.paint.SetInputConnection(self.lights.GetOutputPort())
        self.paint.AddStrokePoint(3.0, 2.0, 0.0)
        self.paint.AddStrokePoint(2.0, 3.5, 1.0)
        self.paint.SetWidth(0.25)
        self.paint.SetStrength(0.0)  # nothing painted yet
        # A paint inside the diffusion model's range (the default target,
        # ketchup, has albedo 0.02 in B and now draws the model-range warning
        # when the wide stroke below paints every tet).
        self.paint.SetTargetAbsorptionCoefficient(0.02, 0.05, 0.1)
        self.paint.SetTargetReducedScatteringCoefficient(1.5, 1.8, 2.0)
        self.solve = new_solver()
        self.solve.SetInputConnection(self.paint.GetOutputPort())

    def reference(self, grid):
        """Fluence of a from-scratch solve by a new filter."""
        copy = vtkUnstructuredGrid()
        copy.ShallowCopy(grid)
        solve = new_solver()
        solve.SetInputData(copy)
        run(solve)
        self.assertEqual(solve.GetLastAssembly(), "full")
        return array(solve.GetOutput(), "Fluence")

    def test_paint_then_solve_is_incremental(self):
        run(self.lights, self.paint, self.solve)
        self.assertEqual(self.solve.GetLastAssembly(), "full")
        cold = self.solve.GetNumberOfIterations(0)
        self.paint.SetStrength(1.0)
        self.paint.SetTargetAbsorptionCoefficient(0.5, 0.5, 0.5)
        run(self.lights, self.paint, self.solve)
        self.assertEqual(self.solve.GetLastAssembly(), "incremental")
        painted = vtk_to_numpy(self.paint.GetOutput().GetFieldData().GetArray("PaintedCellIds"))
        n = self.grid.GetNumberOfCells()
        self.assertGreater(len(painted), 10)
        self.assertLess(len(painted), 0.05 * n)
        self.assertEqual(self.solve.GetNumberOfChangedTets(), len(painted))
        # Warm start from the previous fluence.
        self.assertLess(self.solve.GetNumberOfIterations(0), cold)
        for c in range(3):
            self.assertTrue(self.solve.GetConverged(c))
        phi = array(self.solve.GetOutput(), "Fluence")
        expected = self.reference(self.paint.GetOutput())
        # The painted tets change the fluence by far more than the tolerance.
        before = self.reference(self.lights.GetOutput())
        self.assertGreater(np.max(np.abs(before - expected)), 1e-3 * np.max(expected))
        np.testing.assert_allclose(phi, expected, rtol=1e-7, atol=1e-9 * np.max(expected))

    def test_any_coefficient_change_is_detected(self):
        run(self.lights, self.paint, self.solve)
        edited = vtkUnstructuredGrid()
        edited.ShallowCopy(self.paint.GetOutput())
        a = array(edited, ABSORPTION, cell=True).copy()
        a[[5, 17, 400]] *= 3.0
        vtk_a = numpy_to_vtk(a, deep=True)
        vtk_a.SetName(ABSORPTION)
        edited.GetCellData().AddArray(vtk_a)
        self.solve.SetInputData(edited)
        run(self.solve)
        self.assertEqual(self.solve.GetLastAssembly(), "incremental")
        self.assertEqual(self.solve.GetNumberOfChangedTets(), 3)
        np.testing.assert_allclose(array(self.solve.GetOutput(), "Fluence"),
                                   self.reference(edited), rtol=1e-7)

    def test_relight_reuses_the_material(self):
        run(self.lights, self.paint, self.solve)
        self.assertEqual(self.solve.GetNumberOfMaterialConversions(), 1)
        self.assertEqual(self.solve.GetNumberOfMaterialComparisons(), 0)
        # Relight: the arrays are the same objects, not modified.
        self.lights.AddDirectionalLight(1.0, 0.0, 0.0, 0.5)
        run(self.lights, self.paint, self.solve)
        self.assertEqual(self.solve.GetLastAssembly(), "right-hand side")
        self.assertEqual(self.solve.GetNumberOfMaterialConversions(), 1)
        self.assertEqual(self.solve.GetNumberOfMaterialComparisons(), 0)
        np.testing.assert_allclose(array(self.solve.GetOutput(), "Fluence"),
                                   self.reference(self.paint.GetOutput()), rtol=1e-7)
        # A paint stroke: new arrays, compared with the kept material in
        # place (no copy of the whole material: issue 31).
        self.paint.SetStrength(1.0)
        self.paint.SetTargetAbsorptionCoefficient(0.5, 0.5, 0.5)
        run(self.lights, self.paint, self.solve)
        self.assertEqual(self.solve.GetLastAssembly(), "incremental")
        self.assertEqual(self.solve.GetNumberOfMaterialConversions(), 1)
        self.assertEqual(self.solve.GetNumberOfMaterialComparisons(), 1)
        np.testing.assert_allclose(array(self.solve.GetOutput(), "Fluence"),
                                   self.reference(self.paint.GetOutput()), rtol=1e-7)
        # An array changed in place (and marked modified): compared again.
        absorption = self.paint.GetOutput().GetCellData().GetArray(ABSORPTION)
        absorption.SetComponent(7, 0, 2.0 * absorption.GetComponent(7, 0))
        absorption.Modified()
        self.solve.Modified()
        run(self.solve)
        self.assertEqual(self.solve.GetNumberOfMaterialConversions(), 1)
        self.assertEqual(self.solve.GetNumberOfMaterialComparisons(), 2)
        self.assertEqual(self.solve.GetNumberOfChangedTets(), 1)
        np.testing.assert_allclose(array(self.solve.GetOutput(), "Fluence"),
                                   self.reference(self.paint.GetOutput()), rtol=1e-7)

    def test_invalid_painted_value_is_an_error_and_loses_nothing(self):
        # Issue 31: a paint is compared with the kept material in place; a
        # painted value the model cannot take names its tet, the output is
        # empty, and the next valid input solves as from scratch.
        run(self.lights, self.paint, self.solve)
        edited = vtkUnstructuredGrid()
        edited.ShallowCopy(self.paint.GetOutput())
        good = array(edited, ABSORPTION, cell=True).copy()
        bad = good.copy()
        bad[123, 1] = -0.5
        vtk_bad = numpy_to_vtk(bad, deep=True)
        vtk_bad.SetName(ABSORPTION)
        edited.GetCellData().AddArray(vtk_bad)
        self.solve.SetInputData(edited)
        messages = Messages(self.solve)
        try:
            self.solve.Update()
        finally:
            messages.remove()
        self.assertTrue(any("AbsorptionCoefficient of tet 123, channel G is -0.5" in m
                            for m in messages.errors), messages.errors)
        self.assertEqual(self.solve.GetOutput().GetNumberOfCells(), 0)
        fixed = vtkUnstructuredGrid()
        fixed.ShallowCopy(self.paint.GetOutput())
        painted = good.copy()
        painted[[5, 123]] *= 2.0
        vtk_good = numpy_to_vtk(painted, deep=True)
        vtk_good.SetName(ABSORPTION)
        fixed.GetCellData().AddArray(vtk_good)
        self.solve.SetInputData(fixed)
        run(self.solve)
        np.testing.assert_allclose(array(self.solve.GetOutput(), "Fluence"),
                                   self.reference(fixed), rtol=1e-7)

    def test_falls_back_to_full_assembly(self):
        run(self.lights, self.paint, self.solve)
        # Another light: other irradiance, the same material: only the
        # right-hand side is rebuilt (issue 31), and Paint re-used its arrays.
        painted = self.paint.GetNumberOfPaintings()
        self.lights.AddDirectionalLight(1.0, 0.0, 0.0, 0.5)
        run(self.lights, self.paint, self.solve)
        self.assertEqual(self.solve.GetLastAssembly(), "right-hand side")
        self.assertEqual(self.solve.GetNumberOfChangedTets(), 0)
        self.assertTrue(self.paint.GetLastExecutionReused())
        self.assertEqual(self.paint.GetNumberOfPaintings(), painted)
        np.testing.assert_allclose(array(self.solve.GetOutput(), "Fluence"),
                                   self.reference(self.paint.GetOutput()), rtol=1e-7)
        # Nothing changed: incremental with no changed tet.
        self.solve.Modified()
        run(self.lights, self.paint, self.solve)
        self.assertEqual(self.solve.GetLastAssembly(), "incremental")
        self.assertEqual(self.solve.GetNumberOfChangedTets(), 0)
        # A wide stroke changes most tets: beyond MaximumChangedFraction.
        self.paint.SetStrength(1.0)
        self.paint.SetWidth(20.0)
        run(self.lights, self.paint, self.solve)
        self.assertEqual(self.solve.GetLastAssembly(), "full")
        np.testing.assert_allclose(array(self.solve.GetOutput(), "Fluence"),
                                   self.reference(self.paint.GetOutput()), rtol=1e-7)
        # IncrementalAssembly off.
        self.solve.IncrementalAssemblyOff()
        self.paint.SetWidth(0.5)
        run(self.lights, self.paint, self.solve)
        self.assertEqual(self.solve.GetLastAssembly(), "full")
        # A cut: new topology.
        self.solve.IncrementalAssemblyOn()
        cut = plane_cut(self.paint.GetOutput())
        self.solve.SetInputData(cut)
        run(self.solve)
        self.assertEqual(self.solve.GetLastAssembly(), "full")
        self.assertLess(cut.GetNumberOfCells(), self.grid.GetNumberOfCells())
        np.testing.assert_allclose(array(self.solve.GetOutput(), "Fluence"),
                                   self.reference(cut), rtol=1e-7)


if __name__ == "__main__":
    unittest.main(verbosity=2)
