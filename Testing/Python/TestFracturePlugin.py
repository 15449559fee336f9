#!/usr/bin/env pvpython
"""The FractureTetMesh proxy of the Translucency plugin, in pvpython.

How to run (ctest passes the plugin path):

    pvpython --force-offscreen-rendering TestFracturePlugin.py <build>/lib/paraview-plugins/Translucency/Translucency.so

1. SeedPoints (a repeated x, y, z property) gives one block "piece_k" per
   non-empty Voronoi cell; clearing it and setting RandomSeeds gives that many.
2. Merge Blocks recombines the pieces: every original cell id exactly once.
"""

import os
import sys
import unittest

from paraview.simple import *  # noqa: F401,F403
from paraview import servermanager

if len(sys.argv) < 2 or not os.path.isfile(sys.argv[1]):
    sys.exit("usage: pvpython TestFracturePlugin.py <path to Translucency plugin>")
PLUGIN = sys.argv.pop(1)
LoadPlugin(PLUGIN, ns=globals())

import numpy as np  # noqa: E402
from vtkmodules.util.numpy_support import vtk_to_numpy  # noqa: E402


class FracturePluginTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        sphere = Sphere(Radius=4.0, ThetaResolution=12, PhiResolution=12)
        tetra = TetrahedralizeSurface(Input=Triangulate(Input=sphere), TargetNumberOfTets=1500)
        cls.assign = AssignScatteringCoefficients(Input=tetra)
        cls.fracture = FractureTetMesh(Input=cls.assign)

    def fetch(self, proxy):
        proxy.UpdatePipeline()
        return servermanager.Fetch(proxy)

    def test_seed_points_and_random_seeds(self):
        self.fracture.SeedPoints = [-2.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 2.5, 0.0]
        self.fracture.RandomSeeds = [0, 0]
        output = self.fetch(self.fracture)
        self.assertEqual(output.GetClassName(), "vtkMultiBlockDataSet")
        self.assertEqual(output.GetNumberOfBlocks(), 3)
        names = [output.GetMetaData(k).Get(output.NAME()) for k in range(3)]
        self.assertEqual(names, ["piece_0", "piece_1", "piece_2"])
        self.fracture.SeedPoints = []
        self.fracture.RandomSeeds = [5, 11]
        self.assertEqual(self.fetch(self.fracture).GetNumberOfBlocks(), 5)

    def test_merge_blocks_recombines(self):
        self.fracture.SeedPoints = [-2.0, 0.0, 0.0, 2.0, 0.0, 0.0]
        self.fracture.RandomSeeds = [0, 0]
        merged = self.fetch(MergeBlocks(Input=self.fracture))
        total = self.fetch(self.assign).GetNumberOfCells()
        cids = vtk_to_numpy(merged.GetCellData().GetArray("vtkOriginalCellIds"))
        self.assertTrue(np.array_equal(np.sort(cids), np.arange(total)))


if __name__ == "__main__":
    unittest.main()
