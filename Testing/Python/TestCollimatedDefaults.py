#!/usr/bin/env python3
"""The default collimated model per light kind, from one core table (issue 33).

How to run (from a build tree; ctest sets the environment):

    PYTHONPATH=<build>/lib/python3.11/site-packages TRANSLUCENCY_CLI=<build>/bin/translucency \\
        /usr/bin/python3 TestCollimatedDefaults.py

The table (translucency::GetCollimatedDefaultTable, Solvers/Physics/
CollimatedModels.cxx) was measured against Monte Carlo
(scripts/collimated_model_table.py, Documentation/DiffuseOptics.md); the
plugin XML is checked against it by PluginEnumerations.* (C++). Here:

1. vtkSurfaceIrradiance's default is COLLIMATED_DEFAULT, and its Irradiance
   then holds every light: bit for bit the surface model's.
2. Solve Diffusion decides a default choice from the table: a directional
   light, a coloured one, a spot light and a pencil beam alone each give the
   table's model for that kind (GetSolvedCollimatedModel, the output's field
   data), and the same Fluence, to 1e-9, as that model chosen explicitly
   upstream; the output's Irradiance is the explicit model's (what Outgoing
   Radiance reads). quadgraph solves a default choice with the surface model
   (the same Fluence as an explicit surface model), where an explicit
   extended model is an error.
3. The command line follows the same table: `translucency help render`
   lists every kind's default as the table gives it, and `render` without
   --collimated gives the Fluence of `--collimated <the directional
   default>` (a directional light) to 1e-9.

Exits non-zero on failure (unittest).
"""

import os
import subprocess
import sys
import tempfile
import unittest

import numpy as np
import translucency
from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray, vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkPoints
from vtkmodules.vtkCommonDataModel import VTK_TETRA, vtkCellArray, vtkUnstructuredGrid
from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader, vtkXMLUnstructuredGridWriter

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_under_test import find_cli  # noqa: E402

CLI = find_cli("TestCollimatedDefaults")
MODELS = ["surface", "extended", "extended-moments"]
S = translucency.vtkSurfaceIrradiance


def box(n=(8, 8, 5), size=(8.0, 8.0, 5.0)):
    """A box of Kuhn tets (6 per cell) with mu_a 0.01, mu_s' 1, eta 1.3."""
    axes = [np.linspace(0.0, l, k + 1) for l, k in zip(size, n)]
    z, y, x = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")
    points = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    px, py = n[0] + 1, n[1] + 1
    i, j, k = (a.ravel() for a in np.meshgrid(*(np.arange(m) for m in n), indexing="ij"))
    tets = []
    for perm in ((0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)):
        corner = [np.zeros_like(i)] * 3
        tet = [i + px * (j + py * k)]
        for axis in perm:
            corner = list(corner)
            corner[axis] = corner[axis] + 1
            tet.append(i + corner[0] + px * (j + corner[1] + py * (k + corner[2])))
        tets.append(np.column_stack(tet))
    tets = np.vstack(tets)
    grid = vtkUnstructuredGrid()
    vtk_points = vtkPoints()
    vtk_points.SetData(numpy_to_vtk(points, deep=True))
    grid.SetPoints(vtk_points)
    cells = vtkCellArray()
    cells.SetCells(len(tets), numpy_to_vtkIdTypeArray(
        np.column_stack([np.full(len(tets), 4), tets]).ravel().astype(np.int64), deep=True))
    grid.SetCells(VTK_TETRA, cells)
    for name, value, components in (("AbsorptionCoefficient", 0.01, 3),
                                    ("ReducedScatteringCoefficient", 1.0, 3),
                                    ("RefractiveIndex", 1.3, 1)):
        array = numpy_to_vtk(np.full((len(tets), components), value), deep=True)
        array.SetName(name)
        grid.GetCellData().AddArray(array)
    return grid


def point_array(data, name):
    return vtk_to_numpy(data.GetPointData().GetArray(name)).copy()


class CollimatedDefaultsTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        cls.grid = box()
        cls.dir = tempfile.TemporaryDirectory()

    @classmethod
    def tearDownClass(cls):
        cls.dir.cleanup()

    def lights(self, kind, model=None):
        light = S()
        light.SetInputData(self.grid)
        if model is not None:
            light.SetCollimatedModel(model)
        if kind == "directional":
            light.AddDirectionalLight(0.2, 0.1, -1.0, 1.0)
        elif kind == "coloured":
            light.AddColouredDirectionalLight(0.2, 0.1, -1.0, 1.0, 0.5, 0.25)
        elif kind == "spot":
            light.AddSpotLight(4.0, 4.0, 25.0, 0.0, 0.0, -1.0, 10.0, 0.0, 400.0, 400.0, 400.0)
        else:
            light.SetDefaultLights(False)
        light.SetUniformLightIrradiance(0.1 if kind != "pencil" else 0.0)
        return light

    def solve(self, light, kind, solver="divergence"):
        solve = translucency.vtkSolveDiffusion()
        self.assertTrue(solve.SetSolverByName(solver))
        solve.SetInputConnection(light.GetOutputPort())
        solve.SetRelTol(1e-12)
        solve.SetMaxIter(20000)
        if kind == "pencil":
            solve.AddPencilBeam(4.0, 4.0, 5.0, 0.0, 0.0, -1.0, 1.0, 1.0, 1.0)
        return solve

    def default_model(self, kind):
        name = S.GetDefaultCollimatedModelName(kind)
        self.assertIn(name, MODELS, kind)
        return MODELS.index(name)

    # 1.
    def test_filter_default_keeps_every_light_in_the_irradiance(self):
        self.assertEqual(S().GetCollimatedModel(), S.COLLIMATED_DEFAULT)
        self.assertEqual(S.GetNumberOfCollimatedModels(), 3)
        self.assertEqual([S.GetCollimatedModelName(i) for i in range(3)], MODELS)
        default, surface = self.lights("directional"), self.lights("directional", 0)
        default.Update()
        surface.Update()
        q_default = point_array(default.GetOutput(), "Irradiance")
        self.assertGreater(q_default.max(), 0.5)
        self.assertEqual(abs(q_default - point_array(surface.GetOutput(), "Irradiance")).max(),
                         0.0)
        by_default = default.GetOutput().GetFieldData().GetArray(
            "TranslucencyCollimatedModelByDefault")
        self.assertEqual(by_default.GetValue(0), 1)
        self.assertTrue(S().SetCollimatedModelByName("Extended-Moments"))
        self.assertFalse(S().SetCollimatedModelByName("extnded"))

    # 2.
    def test_each_light_kind_solves_its_default_model(self):
        for kind in ("directional", "coloured", "spot", "pencil"):
            with self.subTest(kind=kind):
                model = self.default_model(kind)
                default = self.solve(self.lights(kind), kind)
                explicit = self.solve(self.lights(kind, model), kind)
                translucency.update(default)
                translucency.update(explicit)
                self.assertEqual(default.GetSolvedCollimatedModel(), model)
                self.assertEqual(explicit.GetSolvedCollimatedModel(), model)
                self.assertEqual(default.GetOutput().GetFieldData().GetArray(
                    "TranslucencyCollimatedModel").GetValue(0), model)
                for name in ("Fluence", "Irradiance"):
                    a = point_array(default.GetOutput(), name)
                    b = point_array(explicit.GetOutput(), name)
                    scale = max(abs(b).max(), 1e-300)
                    self.assertLess(abs(a - b).max() / scale, 1e-9, "%s, %s" % (kind, name))

    def test_quadgraph_solves_a_default_choice_with_the_surface_model(self):
        default = self.solve(self.lights("directional"), "directional", "quadgraph")
        surface = self.solve(self.lights("directional", 0), "directional", "quadgraph")
        translucency.update(default)
        translucency.update(surface)
        self.assertEqual(default.GetSolvedCollimatedModel(), 0)
        a, b = point_array(default.GetOutput(), "Fluence"), point_array(surface.GetOutput(),
                                                                           "Fluence")
        self.assertLess(abs(a - b).max() / abs(b).max(), 1e-9)
        extended = self.solve(self.lights("directional", 2), "directional", "quadgraph")
        with self.assertRaises(translucency.PipelineError) as raised:
            translucency.update(extended)
        self.assertIn("extended", str(raised.exception))

    # 3.
    def test_command_line_follows_the_table(self):
        help_text = subprocess.run([CLI, "help", "render"], capture_output=True, text=True,
                                   timeout=60).stdout
        for kind in ("directional", "coloured", "spot", "pencil"):
            self.assertIn("%s: %s" % (kind, S.GetDefaultCollimatedModelName(kind)), help_text)
        mesh = os.path.join(self.dir.name, "box.vtu")
        writer = vtkXMLUnstructuredGridWriter()
        writer.SetFileName(mesh)
        writer.SetInputData(self.grid)
        writer.Write()
        fluence = {}
        for label, extra in (("default", []),
                             ("explicit", ["--collimated",
                                           S.GetDefaultCollimatedModelName("directional")])):
            prefix = os.path.join(self.dir.name, label)
            result = subprocess.run(
                [CLI, "render", "--mesh", mesh, "--light", "directional:0.2,0.1,-1:1",
                 "--rel-tol", "1e-12", "--max-iter", "20000", "--output", prefix, "--quiet"]
                + extra, capture_output=True, text=True, timeout=300)
            self.assertEqual(result.returncode, 0, result.stdout + result.stderr)
            reader = vtkXMLUnstructuredGridReader()
            reader.SetFileName(prefix + ".vtu")
            reader.Update()
            fluence[label] = point_array(reader.GetOutput(), "Fluence")
        self.assertLess(abs(fluence["default"] - fluence["explicit"]).max() /
                        abs(fluence["explicit"]).max(), 1e-9)


if __name__ == "__main__":
    unittest.main(verbosity=2)
