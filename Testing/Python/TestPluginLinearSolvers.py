"""Solve Diffusion's Linear Solver drop-down in the ParaView plugin, run by pvpython.

How to run (ctest does this):

    pvpython --force-offscreen-rendering TestPluginLinearSolvers.py <Translucency plugin>

Issue 20: Linear Solver was free text, and an unknown name ended in a crash
downstream. It is now a StringListDomain fed by the information property
LinearSolverNames (vtkSolveDiffusion::GetAvailableLinearSolvers, which
TestFilters compares with the core's registry).

1. The drop-down lists exactly the filter's names, "default" first, and the
   property's default value is "default".
2. Every entry runs: a symmetric solver's name with the divergence and fem
   solvers, a non-symmetric one's with quadgraph, "default" with all four;
   no error (translucency.raise_on_error), a Fluence array, and the filter
   reports the linear solver it used (the entry, or the solver's default).

Exits non-zero on failure (unittest). No rendering.
"""

import os
import sys
import unittest

from paraview.simple import *  # noqa: F401,F403
from paraview import servermanager

if len(sys.argv) < 2 or not os.path.isfile(sys.argv[1]):
    sys.exit("usage: pvpython TestPluginLinearSolvers.py <Translucency plugin>")
PLUGIN = sys.argv.pop(1)
LoadPlugin(PLUGIN, ns=globals())

import translucency  # noqa: E402

VERTEX_SOLVERS = ["divergence", "fem"]
NON_SYMMETRIC = {"bicgstab", "relaxation"}
DEFAULTS = {"divergence": "cg-jacobi", "fem": "cg-jacobi", "quadgraph": "bicgstab",
            "grid": "bicgstab"}


class PluginLinearSolversTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        sphere = Sphere(Radius=4.0, ThetaResolution=12, PhiResolution=12)
        tetra = TetrahedralizeSurface(Input=Triangulate(Input=sphere), TargetNumberOfTets=800)
        lit = SurfaceIrradiance(Input=AssignScatteringCoefficients(Input=tetra))
        cls.solve = SolveDiffusion(Input=lit)

    def drop_down(self):
        domain = self.solve.GetProperty("LinearSolver").GetDomain("list")
        self.assertIsNotNone(domain, "Linear Solver has no StringListDomain")
        return [domain.GetString(i) for i in range(domain.GetNumberOfStrings())]

    def test_drop_down_lists_the_filters_names(self):
        names = translucency.vtkSolveDiffusion().GetAvailableLinearSolvers()
        expected = [names.GetValue(i) for i in range(names.GetNumberOfValues())]
        self.assertEqual(self.drop_down(), expected)
        self.assertEqual(expected[0], "default")
        self.assertIn("cg-jacobi", expected)
        self.assertIn("bicgstab", expected)
        self.assertEqual(self.solve.LinearSolver, "default")

    def test_every_entry_runs(self):
        filter_object = self.solve.GetClientSideObject()
        runs = 0
        for name in self.drop_down():
            if name == "default":
                solvers = VERTEX_SOLVERS + ["quadgraph", "grid"]
            elif name in NON_SYMMETRIC:
                solvers = ["quadgraph"]
            else:
                solvers = VERTEX_SOLVERS
            for solver in solvers:
                with self.subTest(linear_solver=name, solver=solver):
                    self.solve.Solver = solver
                    self.solve.LinearSolver = name
                    with translucency.raise_on_error():
                        self.solve.UpdatePipeline()
                    data = servermanager.Fetch(self.solve)
                    self.assertIsNotNone(data.GetPointData().GetArray("Fluence"))
                    used = filter_object.GetLinearSolverUsed()
                    self.assertEqual(used, DEFAULTS[solver] if name == "default" else name)
                    runs += 1
        self.assertGreaterEqual(runs, 12)
        self.solve.Solver = "divergence"
        self.solve.LinearSolver = "default"


if __name__ == "__main__":
    unittest.main(verbosity=2)
