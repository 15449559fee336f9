"""Test of the Translucent Radiosity proxy of the ParaView plugin, run by pvpython.

How to run (ctest does this):

    pvpython --force-offscreen-rendering TestRadiosityPlugin.py <build>/lib/paraview-plugins/Translucency/Translucency.so

1. Builds a scene from ParaView sources: a floor (Plane -> Triangulate ->
   Calculator giving the cell array Albedo) and a marble sphere above it
   (Sphere -> Triangulate -> TetrahedralizeSurface -> AssignScatteringCoefficients),
   grouped with Group Datasets.
2. Applies TranslucentRadiosity with a point light above: every leaf of the
   output carries the radiosity arrays, Radiosity = SubsurfaceRadiosity +
   InterReflectionRadiosity, and the floor receives inter-reflected light from
   the sphere (InterReflectionRadiosity > 0 under it).
3. The light properties reach the filter: doubling LightPower doubles the
   radiosity (the problem is linear in the light).

Exits non-zero on failure (unittest). No rendering.
"""

import os
import sys
import unittest

from paraview.simple import *  # noqa: F401,F403
from paraview import servermanager

if len(sys.argv) < 2 or not os.path.isfile(sys.argv[1]):
    sys.exit("usage: pvpython --force-offscreen-rendering TestRadiosityPlugin.py <Translucency plugin>")
LoadPlugin(sys.argv[1], ns=globals())

from vtkmodules.util.numpy_support import vtk_to_numpy  # noqa: E402
import numpy as np  # noqa: E402


def leaves(data):
    it = data.NewIterator()
    it.InitTraversal()
    out = []
    while not it.IsDoneWithTraversal():
        out.append(it.GetCurrentDataObject())
        it.GoToNextItem()
    return out


class RadiosityPluginTest(unittest.TestCase):
    def test_scene(self):
        plane = Plane(Origin=[-10, -10, 0], Point1=[10, -10, 0], Point2=[-10, 10, 0],
                      XResolution=10, YResolution=10)
        floor = Calculator(Input=Triangulate(Input=plane), AttributeType="Cell Data",
                           ResultArrayName="Albedo", Function="0.6*iHat+0.6*jHat+0.6*kHat")
        sphere = Sphere(Center=[0, 0, 4], Radius=3.0, ThetaResolution=16, PhiResolution=16)
        marble = AssignScatteringCoefficients(
            Input=TetrahedralizeSurface(Input=Triangulate(Input=sphere), TargetNumberOfTets=2000))
        group = GroupDatasets(Input=[floor, marble])
        radiosity = TranslucentRadiosity(Input=group)
        radiosity.LightPosition = [0, 0, 20]
        radiosity.LightPower = [500, 500, 500]
        radiosity.RaysPerPatch = 128
        # Linear Solver is a drop-down of this build's solvers (the information
        # property the panel reads), cg-jacobi first chosen.
        domain = radiosity.GetProperty("LinearSolver").GetDomain("list")
        radiosity.UpdatePropertyInformation()
        choices = [domain.GetString(i) for i in range(domain.GetNumberOfStrings())]
        self.assertIn("cg-jacobi", choices)
        self.assertIn("multigrid-agg", choices)
        self.assertEqual(radiosity.LinearSolver, "cg-jacobi")
        radiosity.UpdatePipeline()
        data = servermanager.Fetch(radiosity)
        parts = leaves(data)
        self.assertEqual(len(parts), 2)
        for part in parts:
            self.assertEqual(part.GetClassName(), "vtkPolyData")
            get = lambda name: vtk_to_numpy(part.GetCellData().GetArray(name))
            np.testing.assert_allclose(
                get("Radiosity"), get("SubsurfaceRadiosity") + get("InterReflectionRadiosity"),
                rtol=1e-12, atol=1e-12)
        # The floor: which leaf has z = 0 everywhere.
        floor_part = [p for p in parts
                      if np.allclose(vtk_to_numpy(p.GetPoints().GetData())[:, 2], 0.0)][0]
        inter = vtk_to_numpy(floor_part.GetCellData().GetArray("InterReflectionRadiosity"))
        self.assertGreater(inter.max(), 0.0)
        b1 = vtk_to_numpy(floor_part.GetCellData().GetArray("Radiosity")).copy()

        radiosity.LightPower = [1000, 1000, 1000]
        radiosity.UpdatePipeline()
        parts = leaves(servermanager.Fetch(radiosity))
        floor_part = [p for p in parts
                      if np.allclose(vtk_to_numpy(p.GetPoints().GetData())[:, 2], 0.0)][0]
        b2 = vtk_to_numpy(floor_part.GetCellData().GetArray("Radiosity"))
        np.testing.assert_allclose(b2, 2.0 * b1, rtol=2e-3, atol=1e-9 * b1.max())


if __name__ == "__main__":
    unittest.main(argv=[sys.argv[0]])
