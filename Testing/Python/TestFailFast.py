#!/usr/bin/env python3
"""Fail fast from Python: translucency.update() and translucency.raise_on_error()
turn the filters' logged errors into a PipelineError carrying the message
(issue 20: an unknown material or SetSolverByName("femm") only logged and the
script found `Fluence = None` later).

How to run (from a build tree):

    PYTHONPATH=<build>/lib/python3.11/site-packages /usr/bin/python3 TestFailFast.py

1. A valid chain (sphere -> tets -> marble -> light -> solve): update()
   returns the output data object with Fluence, and raises nothing.
2. An unknown material: update() of the solver downstream raises
   PipelineError whose message names the filter and the material; repaired,
   update() returns Fluence again.
3. An unknown linear solver: the message names LinearSolver and lists the
   known ones.
4. SetSolverByName("femm") inside raise_on_error() raises at the end of the
   block, naming 'femm'; the solver is unchanged.
5. The observer is removed after the block: a later error does not reach it,
   and a block without errors raises nothing. An error from a non-zero output
   port is caught too (InverseDiffusion's objective table, port 1).

Exits non-zero on failure (unittest).
"""

import unittest

import translucency
from vtkmodules.vtkFiltersSources import vtkSphereSource


class FailFastTest(unittest.TestCase):

    def setUp(self):
        self.sphere = vtkSphereSource()
        self.sphere.SetRadius(4.0)
        self.sphere.SetThetaResolution(12)
        self.sphere.SetPhiResolution(12)
        self.tetra = translucency.vtkTetrahedralizeSurface()
        self.tetra.SetInputConnection(self.sphere.GetOutputPort())
        self.tetra.SetTargetNumberOfTets(1000)
        self.material = translucency.vtkAssignScatteringCoefficients()
        self.material.SetInputConnection(self.tetra.GetOutputPort())
        self.material.SetMaterialName("marble")
        self.light = translucency.vtkSurfaceIrradiance()
        self.light.SetInputConnection(self.material.GetOutputPort())
        self.light.AddDirectionalLight(0.0, -1.0, -1.0, 1.0)
        self.solve = translucency.vtkSolveDiffusion()
        self.solve.SetInputConnection(self.light.GetOutputPort())

    def test_valid_chain(self):
        output = translucency.update(self.solve)
        self.assertIs(output, self.solve.GetOutput())
        fluence = output.GetPointData().GetArray("Fluence")
        self.assertIsNotNone(fluence)
        self.assertGreater(fluence.GetRange(0)[1], 0.0)

    def test_unknown_material(self):
        self.material.SetMaterialName("marbel")
        with self.assertRaises(translucency.PipelineError) as raised:
            translucency.update(self.solve)
        message = str(raised.exception)
        self.assertIn("vtkAssignScatteringCoefficients", message)
        self.assertIn("'marbel'", message)
        self.assertIn("marble", message)  # the known presets are listed
        self.assertNotIn("0x", message)  # no object address
        self.assertEqual(raised.exception.messages[0], message)
        self.assertTrue(isinstance(raised.exception, RuntimeError))

        self.material.SetMaterialName("marble")
        output = translucency.update(self.solve)
        self.assertIsNotNone(output.GetPointData().GetArray("Fluence"))

    def test_unknown_linear_solver(self):
        self.solve.SetLinearSolver("nosuchsolver")
        with self.assertRaises(translucency.PipelineError) as raised:
            translucency.update(self.solve)
        message = str(raised.exception)
        self.assertIn("vtkSolveDiffusion", message)
        self.assertIn("unknown linear solver 'nosuchsolver'", message)
        self.assertIn("cg-jacobi", message)
        self.assertEqual(self.solve.GetOutput().GetNumberOfPoints(), 0)

    def test_unknown_solver_name(self):
        before = self.solve.GetSolverName()
        with self.assertRaises(translucency.PipelineError) as raised:
            with translucency.raise_on_error():
                self.solve.SetSolverByName("femm")
        self.assertIn("unknown solver 'femm'", str(raised.exception))
        self.assertEqual(self.solve.GetSolverName(), before)

    def test_no_error_no_exception(self):
        with translucency.raise_on_error() as messages:
            self.assertTrue(self.solve.SetSolverByName("fem"))
        self.assertEqual(messages, [])
        # Outside a block nothing is recorded nor raised (the error is only logged).
        self.assertFalse(self.solve.SetSolverByName("femm"))

    def test_other_port(self):
        inverse = translucency.vtkInverseDiffusion()
        inverse.SetInputConnection(self.light.GetOutputPort())  # no measurements
        with self.assertRaises(translucency.PipelineError) as raised:
            translucency.update(inverse, 1)
        self.assertIn("vtkInverseDiffusion", str(raised.exception))


if __name__ == "__main__":
    unittest.main(verbosity=2)
