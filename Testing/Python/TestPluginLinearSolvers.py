"""Solve Diffusion's Linear Solver drop-down in the ParaView plugin, run by pvpython.

How to run (ctest does this):

    pvpython --force-offscreen-rendering TestPluginLinearSolvers.py <Translucency plugin>

Issue 20: Linear Solver was free text, and an unknown name ended in a crash
downstream. It is now a StringListDomain fed by the information property
LinearSolverNames (vtkSolveDiffusion::GetAvailableLinearSolvers, which
TestFilters compares with the core's registry).

1. The drop-down lists exactly the filter's names, "default" first, and the
   property's default value is "default".
2. The information property LinearSolverTable (pairs solver, linear
   solver: what the GUI's decorator lists for the chosen Solver) is the
   filter's table and covers the drop-down; sp3 takes bicgstab and
   multigrid-agg, quadgraph and grid bicgstab and relaxation.
3. Every solver with every name of the drop-down: the names of its row run
   (no error, a Fluence array, the filter reports the linear solver it
   used), every other name fails with an error naming what it accepts
   (issue 33: the list offered solvers the chosen Solver could not use).

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

    def table(self):
        """The proxy's LinearSolverTable (pairs solver, linear solver) as a
        dict solver -> names: what the GUI's drop-down lists per Solver."""
        self.solve.UpdatePropertyInformation()
        values = list(self.solve.GetProperty("LinearSolverTable"))
        self.assertEqual(len(values) % 2, 0)
        table = {}
        for solver, name in zip(values[0::2], values[1::2]):
            table.setdefault(solver, []).append(name)
        return table

    def test_table_is_the_filters_and_covers_the_drop_down(self):
        table = self.table()
        array = translucency.vtkSolveDiffusion().GetLinearSolverTable()
        expected = {}
        for i in range(0, array.GetNumberOfValues(), 2):
            expected.setdefault(array.GetValue(i), []).append(array.GetValue(i + 1))
        self.assertEqual(table, expected)
        self.assertEqual(sorted(table), sorted(VERTEX_SOLVERS + ["quadgraph", "grid", "sp3"]))
        self.assertNotIn("montecarlo", table)  # no choice: the widget is hidden
        listed = set(name for names in table.values() for name in names)
        self.assertEqual(listed, set(self.drop_down()) - {"default"})
        self.assertEqual(table["sp3"], ["bicgstab", "multigrid-agg"])
        for solver in ("quadgraph", "grid"):
            self.assertEqual(table[solver], ["bicgstab", "relaxation"])

    def test_every_entry_runs_and_the_others_are_refused(self):
        # Each solver with each name of the drop-down: the ones its row of the
        # table lists run (no error, a Fluence array, the entry reported as
        # used), every other fails with an error naming what it accepts.
        filter_object = self.solve.GetClientSideObject()
        table = self.table()
        runs = refusals = 0
        for solver in sorted(table):
            for name in self.drop_down():
                with self.subTest(linear_solver=name, solver=solver):
                    self.solve.Solver = solver
                    self.solve.LinearSolver = name
                    if name != "default" and name not in table[solver]:
                        with self.assertRaises(translucency.PipelineError) as raised:
                            with translucency.raise_on_error():
                                self.solve.UpdatePipeline()
                        message = str(raised.exception)
                        self.assertIn("the %s solver does not accept the linear solver '%s'"
                                      % (solver, name), message)
                        self.assertIn("it accepts: " + ", ".join(table[solver]), message)
                        refusals += 1
                        continue
                    with translucency.raise_on_error():
                        self.solve.UpdatePipeline()
                    data = servermanager.Fetch(self.solve)
                    self.assertIsNotNone(data.GetPointData().GetArray("Fluence"))
                    used = filter_object.GetLinearSolverUsed()
                    if solver == "sp3":
                        block = {"default": "jacobi", "bicgstab": "jacobi",
                                 "multigrid-agg": "multigrid-agg"}[name]
                        self.assertEqual(used, "bicgstab-block-" + block)
                    else:
                        self.assertEqual(used, DEFAULTS[solver] if name == "default" else name)
                    runs += 1
        self.assertGreaterEqual(runs, 15)
        self.assertGreaterEqual(refusals, 10)
        self.solve.Solver = "divergence"
        self.solve.LinearSolver = "default"


if __name__ == "__main__":
    unittest.main(verbosity=2)
