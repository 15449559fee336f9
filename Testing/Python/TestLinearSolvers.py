#!/usr/bin/env python3
"""vtkSolveDiffusion with every linear solver of the vertex discretisations.

How to run (from a build tree; ctest sets the variables itself):

    PYTHONPATH=<build>/lib/python3.11/site-packages /usr/bin/python3 TestLinearSolvers.py

1. For "divergence" and "fem", every name of the LinearSolver property
   (cg-jacobi, transcut-multires, multigrid-cg, and whatever else the build
   lists in its error message) gives the same fluence as the default ("")
   to the solve tolerance, and reports the name it used.
2. The default of the LinearSolver property is "" (the solver's default),
   and "" also works for the QuadGraph and grid solvers (bicgstab).
3. An unknown name is an error that lists the known names.
4. A relight (new light, same mesh and material) with multigrid-cg warm-
   starts and needs fewer iterations than the cold solve.
5. A Krylov x preconditioner composition (cg/jacobi, ...) names the
   registry entry it composes: the same solver and fluence as its name.
"""

import os
import re
import sys
import unittest

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from TestPipeline import Messages, Pipeline, array, sphere_surface  # noqa: E402

import translucency  # noqa: E402

BASE_NAMES = ("cg-jacobi", "transcut-multires", "multigrid-cg", "multigrid-agg")


class LinearSolverTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        cls.pipe = Pipeline(sphere_surface(), target_tets=6000)
        cls.pipe.irradiance.AddDirectionalLight(0.3, -1.0, -1.0, 1.0)
        cls.pipe.irradiance.Update()

    def solve(self, solver, linear, rel_tol=1e-9, warm=False):
        solve = translucency.vtkSolveDiffusion()
        solve.SetInputConnection(self.pipe.irradiance.GetOutputPort())
        solve.SetSolverByName(solver)
        solve.SetLinearSolver(linear)
        solve.SetRelTol(rel_tol)
        solve.SetWarmStart(warm)
        messages = Messages(solve)
        try:
            solve.Update()
        finally:
            messages.remove()
        return solve, messages

    def known_names(self):
        """The names this build lists in its error for an unknown name."""
        solve, messages = self.solve("divergence", "no-such-solver")
        self.assertEqual(len(messages.errors), 1, messages.errors)
        message = messages.errors[0]
        self.assertIn("no-such-solver", message)
        match = re.search(r"it accepts: ([^;)]*)", message)
        self.assertIsNotNone(match, message)
        names = [n.strip() for n in match.group(1).split(",")]
        for name in BASE_NAMES:
            self.assertIn(name, names, message)
        return names

    def test_default_is_empty(self):
        self.assertEqual(translucency.vtkSolveDiffusion().GetLinearSolver(), "")
        for solver, used in (("divergence", "cg-jacobi"), ("fem", "cg-jacobi"),
                             ("quadgraph", "bicgstab"), ("grid", "bicgstab")):
            solve, messages = self.solve(solver, "", rel_tol=1e-6)
            self.assertEqual(messages.errors + messages.pipeline_errors, [], solver)
            self.assertEqual(solve.GetLinearSolverUsed(), used, solver)

    def test_every_name_gives_the_same_fluence(self):
        names = self.known_names()
        for solver in ("divergence", "fem"):
            reference, messages = self.solve(solver, "")
            self.assertEqual(messages.errors, [])
            phi_ref = array(reference.GetOutput(), "Fluence").copy()
            self.assertGreater(np.max(phi_ref), 0.0)
            for name in names:
                with self.subTest(solver=solver, linear=name):
                    solve, messages = self.solve(solver, name.upper())  # case-insensitive
                    self.assertEqual(messages.errors + messages.pipeline_errors, [])
                    self.assertEqual(solve.GetLinearSolverUsed(), name)
                    for c in range(3):
                        self.assertTrue(solve.GetConverged(c))
                    phi = array(solve.GetOutput(), "Fluence")
                    # Both solves reach a relative residual of 1e-9; the
                    # matrices are well conditioned at this size, so the
                    # fluence agrees to far better than 1e-6.
                    err = np.max(np.abs(phi - phi_ref)) / np.max(phi_ref)
                    self.assertLess(err, 1e-6, "%s/%s: %g" % (solver, name, err))

    def test_a_composition_names_its_entry(self):
        # KRYLOV/PRECONDITIONER (the registry's composition) is the same solver
        # as the entry's name: the same name used and the same fluence, bit for bit.
        for composition, name in (("cg/jacobi", "cg-jacobi"), ("CG/Aggregation", "multigrid-agg"),
                                  ("cg/multires", "multigrid-cg")):
            with self.subTest(composition=composition):
                by_name, messages = self.solve("divergence", name)
                self.assertEqual(messages.errors + messages.pipeline_errors, [])
                solve, messages = self.solve("divergence", composition)
                self.assertEqual(messages.errors + messages.pipeline_errors, [])
                self.assertEqual(solve.GetLinearSolverUsed(), name)
                np.testing.assert_array_equal(array(solve.GetOutput(), "Fluence"),
                                              array(by_name.GetOutput(), "Fluence"))

    def test_unknown_name_is_a_clear_error(self):
        for solver in ("divergence", "fem"):
            solve, messages = self.solve(solver, "multigrid")
            self.assertEqual(len(messages.errors), 1, messages.errors)
            for fragment in ("multigrid'", "cg-jacobi", "transcut-multires", "multigrid-cg"):
                self.assertIn(fragment, messages.errors[0])
        solve, messages = self.solve("quadgraph", "multigrid-cg")
        self.assertEqual(len(messages.errors), 1, messages.errors)
        self.assertIn("bicgstab", messages.errors[0])

    def test_relight_warm_start(self):
        pipe = Pipeline(sphere_surface(), target_tets=6000)
        pipe.irradiance.AddDirectionalLight(0.0, -1.0, -1.0, 1.0)
        pipe.solve.SetLinearSolver("multigrid-cg")
        pipe.solve.SetRelTol(1e-8)
        pipe.update(self, pipe.solve)
        cold = [pipe.solve.GetNumberOfIterations(c) for c in range(3)]
        pipe.irradiance.RemoveAllDirectionalLights()
        pipe.irradiance.AddDirectionalLight(0.0, -1.0, -0.9, 1.0)
        pipe.update(self, pipe.solve)
        warm = [pipe.solve.GetNumberOfIterations(c) for c in range(3)]
        for c in range(3):
            self.assertTrue(pipe.solve.GetConverged(c))
            self.assertLess(warm[c], cold[c], "warm %r vs cold %r" % (warm, cold))


if __name__ == "__main__":
    unittest.main()
