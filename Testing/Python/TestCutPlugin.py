#!/usr/bin/env pvpython
"""The StrokeCut proxy of the Translucency plugin, in pvpython.

How to run (ctest passes the plugin path):

    pvpython --force-offscreen-rendering TestCutPlugin.py <build>/lib/paraview-plugins/Translucency/Translucency.so

1. Every cutter of the "Cut Type" list (Plane, Box, Sphere, Cylinder) gives a
   non-empty tet mesh with vtkOriginalCellIds, and fewer tets than its input
   for a cutter that crosses the mesh; Invert keeps the other side.
2. Surface Irradiance -> Solve Diffusion after the cut gives a positive Fluence.
3. A PolyLineSource connected as the optional "Stroke" input overrides the
   cut function: a straight 2-point stroke swept along ViewDirection (0,0,-1)
   is a plane, and it keeps exactly the tets of the equivalent Plane cut (the
   removed side is the left of the stroke looking along the view direction);
   Surface Irradiance -> Solve Diffusion then solves.
"""

import os
import sys
import unittest

from paraview.simple import *  # noqa: F401,F403
from paraview import servermanager

if len(sys.argv) < 2 or not os.path.isfile(sys.argv[1]):
    sys.exit("usage: pvpython TestCutPlugin.py <path to Translucency plugin>")
PLUGIN = sys.argv.pop(1)
LoadPlugin(PLUGIN, ns=globals())

import numpy as np  # noqa: E402
from vtkmodules.util.numpy_support import vtk_to_numpy  # noqa: E402


class CutPluginTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        sphere = Sphere(Radius=4.0, ThetaResolution=12, PhiResolution=12)
        tetra = TetrahedralizeSurface(Input=Triangulate(Input=sphere), TargetNumberOfTets=1500)
        cls.assign = AssignScatteringCoefficients(Input=tetra)
        cls.cut = StrokeCut(Input=cls.assign)

    def fetch(self, proxy):
        proxy.UpdatePipeline()
        return servermanager.Fetch(proxy)

    def test_cutters(self):
        total = self.fetch(self.assign).GetNumberOfCells()
        cut = self.cut
        self.assertEqual(cut.NumberOfRelaxationIterations, 10)
        self.assertAlmostEqual(cut.RelaxationFactor, 0.1)
        self.assertAlmostEqual(cut.MinimumDihedralAngle, 0.5)
        for name in ("Plane", "Box", "Sphere", "Cylinder"):
            with self.subTest(cutter=name):
                cut.CutType = name
                if name == "Plane":
                    cut.CutType.Origin = [1.0, 0.0, 0.0]
                    cut.CutType.Normal = [1.0, 0.0, 0.0]
                elif name == "Box":
                    cut.CutType.Position = [0.0, 0.0, 0.0]
                    cut.CutType.Length = [10.0, 10.0, 10.0]
                elif name == "Sphere":
                    cut.CutType.Center = [4.0, 0.0, 0.0]
                    cut.CutType.Radius = 3.0
                else:
                    cut.CutType.Center = [0.0, 0.0, 0.0]
                    cut.CutType.Axis = [0.0, 0.0, 1.0]
                    cut.CutType.Radius = 2.0
                kept = []
                for invert in (0, 1):
                    cut.Invert = invert
                    grid = self.fetch(cut)
                    kept.append(grid.GetNumberOfCells())
                    ids = grid.GetCellData().GetArray("vtkOriginalCellIds")
                    self.assertIsNotNone(ids)
                    self.assertLess(vtk_to_numpy(ids).max(), total)
                self.assertGreater(min(kept), 0)
                self.assertLess(min(kept), total)
        cut.Invert = 0

    def test_solves_after_cut(self):
        self.cut.CutType = "Plane"
        self.cut.CutType.Origin = [0.0, 0.0, 0.5]
        self.cut.CutType.Normal = [0.0, 0.2, 1.0]
        solve = SolveDiffusion(Input=SurfaceIrradiance(Input=self.cut))
        grid = self.fetch(solve)
        fluence = vtk_to_numpy(grid.GetPointData().GetArray("Fluence"))
        self.assertEqual(fluence.shape, (grid.GetNumberOfPoints(), 3))
        self.assertTrue(np.all(np.isfinite(fluence)) and np.all(fluence > 0.0))

    def test_stroke(self):
        # Stroke going +y at x = X0, looking along -z (screen x right, y up):
        # its left, x < X0, is removed, i.e. the Plane with normal (-1, 0, 0).
        x0 = 0.37
        plane_cut = StrokeCut(Input=self.assign, CutType="Plane")
        plane_cut.CutType.Origin = [x0, 0.0, 0.0]
        plane_cut.CutType.Normal = [-1.0, 0.0, 0.0]
        plane = self.fetch(plane_cut)

        stroke = PolyLineSource(Points=[x0, -10.0, 0.0, x0, 10.0, 0.0])
        stroke_cut = StrokeCut(Input=self.assign, Stroke=stroke)
        self.assertEqual(list(stroke_cut.ViewDirection), [0.0, 0.0, -1.0])
        # The cut function (default Plane here, set far off) must be ignored.
        stroke_cut.CutType = "Plane"
        stroke_cut.CutType.Origin = [0.0, 0.0, 3.0]
        stroke_cut.CutType.Normal = [0.0, 0.0, 1.0]
        cut = self.fetch(stroke_cut)

        total = self.fetch(self.assign).GetNumberOfCells()
        self.assertGreater(cut.GetNumberOfCells(), 0)
        self.assertLess(cut.GetNumberOfCells(), total)
        ids = lambda g: vtk_to_numpy(g.GetCellData().GetArray("vtkOriginalCellIds"))  # noqa: E731
        np.testing.assert_array_equal(np.sort(ids(cut)), np.sort(ids(plane)))
        np.testing.assert_allclose(
            vtk_to_numpy(cut.GetPoints().GetData()),
            vtk_to_numpy(plane.GetPoints().GetData()), atol=1e-6)
        # Looking the other way (view direction (0, 0, 1)) the left of the
        # stroke is x > X0: the Plane with normal (1, 0, 0).
        stroke_cut.ViewDirection = [0.0, 0.0, 1.0]
        flipped = self.fetch(stroke_cut)
        plane_cut.CutType.Normal = [1.0, 0.0, 0.0]
        np.testing.assert_array_equal(np.sort(ids(flipped)), np.sort(ids(self.fetch(plane_cut))))
        stroke_cut.ViewDirection = [0.0, 0.0, -1.0]

        # Disconnecting the stroke falls back on the cut function.
        stroke_cut.Stroke = []
        fallback = self.fetch(stroke_cut)
        self.assertFalse(np.array_equal(np.sort(ids(fallback)), np.sort(ids(cut))))
        stroke_cut.Stroke = stroke

        solve = SolveDiffusion(Input=SurfaceIrradiance(Input=stroke_cut))
        grid = self.fetch(solve)
        self.assertEqual(grid.GetNumberOfCells(), cut.GetNumberOfCells())
        fluence = vtk_to_numpy(grid.GetPointData().GetArray("Fluence"))
        self.assertEqual(fluence.shape, (grid.GetNumberOfPoints(), 3))
        self.assertTrue(np.all(np.isfinite(fluence)) and np.all(fluence > 0.0))


if __name__ == "__main__":
    unittest.main()
