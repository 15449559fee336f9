#!/usr/bin/env python3
"""A relight or a paint under the extended collimated models rebuilds only
the right-hand side (issues 33 and 32).

How to run (from a build tree; ctest sets the environment):

    PYTHONPATH=<build>/lib/python3.11/site-packages /usr/bin/python3 TestCollimatedRelight.py

For the extended-moments and extended models chosen by name, and for the
default choice (the core table's model for a directional light), through
Surface Irradiance -> Solve Diffusion (divergence, multigrid-agg, so there is
a hierarchy to keep):

1. The first solve assembles in full and builds the hierarchy.
2. A relight (the directional light turned; a point light added) keeps the
   matrices and the hierarchy: GetLastAssembly() "right-hand side",
   GetLastLinearSetup() "kept", the material neither read nor compared
   again; Fluence and CollimatedFluence equal a fresh filter's solve of the
   same input (a full assembly: the independent reference) to 1e-8 of the
   largest value (both solve to RelTol 1e-12).
3. A paint (Paint Scattering Coefficients: the stroke's tets only) rebuilds
   the touched rows ("incremental", set-up "rows") with the beam's new
   volume source, and equals a fresh solve the same way.

Exits non-zero on failure (unittest).
"""

import os
import sys
import unittest

import numpy as np
import translucency
from vtkmodules.util.numpy_support import vtk_to_numpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from TestCollimatedDefaults import box  # noqa: E402

S = translucency.vtkSurfaceIrradiance


def point_array(data, name):
    return vtk_to_numpy(data.GetPointData().GetArray(name)).copy()


def new_solve(source):
    solve = translucency.vtkSolveDiffusion()
    solve.SetInputConnection(source.GetOutputPort())
    solve.SetRelTol(1e-12)
    solve.SetMaxIter(20000)
    solve.SetLinearSolver("multigrid-agg")
    return solve


class CollimatedRelightTest(unittest.TestCase):

    def chain(self, model):
        grid = box()
        lights = S()
        lights.SetInputData(grid)
        lights.SetShadows(True)
        lights.SetUniformLightIrradiance(0.0)
        lights.AddDirectionalLight(0.2, 0.1, -1.0, 1.0)
        lights.SetCollimatedModel(model)
        paint = translucency.vtkPaintScatteringCoefficients()
        paint.SetInputConnection(lights.GetOutputPort())
        paint.AddStrokePoint(3.0, 4.0, 4.5)
        paint.SetWidth(0.25)
        paint.SetStrength(0.0)  # nothing painted yet
        paint.SetTargetAbsorptionCoefficient(0.05, 0.05, 0.05)
        paint.SetTargetReducedScatteringCoefficient(2.0, 2.0, 2.0)
        solve = new_solve(paint)
        return lights, paint, solve

    def same_as_fresh(self, solve, upstream, step):
        fresh = new_solve(upstream)
        fresh.Update()
        self.assertEqual(fresh.GetLastAssembly(), "full")
        self.assertEqual(fresh.GetSolvedCollimatedModel(), solve.GetSolvedCollimatedModel())
        for name in ("Fluence", "CollimatedFluence"):
            expected = point_array(fresh.GetOutput(), name)
            got = point_array(solve.GetOutput(), name)
            scale = float(np.abs(expected).max())
            self.assertGreater(scale, 0.0, name)
            self.assertLessEqual(float(np.abs(got - expected).max()), 1e-8 * scale,
                                 "%s: %s against a fresh solve" % (step, name))

    def check(self, model, solved):
        lights, paint, solve = self.chain(model)
        solve.Update()
        self.assertEqual(solve.GetSolvedCollimatedModel(), solved)
        self.assertEqual(solve.GetLastAssembly(), "full")
        self.assertEqual(solve.GetLastLinearSetup(), "rebuilt")
        conversions = solve.GetNumberOfMaterialConversions()

        # Relight: the beam turned, and a point light (its q) added.
        lights.RemoveAllDirectionalLights()
        lights.AddDirectionalLight(-0.3, 0.2, -1.0, 1.5)
        lights.AddPointLight(4.0, 4.0, 12.0, 50.0)
        solve.Update()
        self.assertEqual(solve.GetSolvedCollimatedModel(), solved)
        self.assertEqual(solve.GetLastAssembly(), "right-hand side")
        self.assertEqual(solve.GetLastLinearSetup(), "kept")
        self.assertEqual(solve.GetNumberOfMaterialConversions(), conversions)
        self.same_as_fresh(solve, paint, "relight")

        # Paint: the stroke's tets change mu_a and mu_s' (the beam's source too).
        paint.SetStrength(1.0)
        solve.Update()
        self.assertGreater(solve.GetNumberOfChangedTets(), 0)
        self.assertEqual(solve.GetLastAssembly(), "incremental")
        self.assertEqual(solve.GetLastLinearSetup(), "rows")
        self.same_as_fresh(solve, paint, "paint")

    def test_extended_moments(self):
        self.check(S.COLLIMATED_EXTENDED_MOMENTS, S.COLLIMATED_EXTENDED_MOMENTS)

    def test_extended(self):
        self.check(S.COLLIMATED_EXTENDED, S.COLLIMATED_EXTENDED)

    def test_default_choice(self):
        # A directional light's default (the core table) is an extended model.
        expected = ["surface", "extended", "extended-moments"].index(
            S.GetDefaultCollimatedModelName("directional"))
        self.assertNotEqual(expected, S.COLLIMATED_SURFACE)
        self.check(S.COLLIMATED_DEFAULT, expected)


if __name__ == "__main__":
    unittest.main()
