#!/usr/bin/env pvpython
"""The InverseDiffusion proxy of the Translucency plugin, in pvpython.

How to run (ctest passes the plugin path and sets TRANSLUCENCY_CLI):

    TRANSLUCENCY_CLI=<build>/bin/translucency pvpython --force-offscreen-rendering \\
        TestAcquirePlugin.py <build>/lib/paraview-plugins/Translucency/Translucency.so

1. `translucency acquire` (synthetic mode, no fit) writes measurements of a small
   block; the proxy, applied to them with ElementArrayName = VoxelId, outputs
   the recovered coefficient arrays on port 0 (voxel-wise constant, positive)
   and the iteration history on port 1 (objective non-increasing per channel).
"""

import os
import subprocess
import sys
import tempfile
import unittest

from paraview.simple import *  # noqa: F401,F403
from paraview import servermanager

if len(sys.argv) < 2 or not os.path.isfile(sys.argv[1]):
    sys.exit("usage: pvpython TestAcquirePlugin.py <path to Translucency plugin>")
PLUGIN = sys.argv.pop(1)
LoadPlugin(PLUGIN, ns=globals())

import numpy as np  # noqa: E402
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_under_test import find_cli  # noqa: E402
from vtkmodules.vtkCommonDataModel import vtkImageData  # noqa: E402
from vtkmodules.vtkIOXML import vtkXMLImageDataWriter  # noqa: E402
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy  # noqa: E402


class AcquirePluginTest(unittest.TestCase):

    def test_inverse_diffusion_proxy(self):
        folder = tempfile.mkdtemp(prefix="translucency_acquire_plugin_")
        image = vtkImageData()
        image.SetDimensions(9, 9, 4)
        image.SetSpacing(0.5, 0.5, 0.5)
        n = 8 * 8 * 3
        mua = np.tile([0.03, 0.05, 0.08], (n, 1))
        mua[n - 20:] *= 2.0
        sigma = np.tile([1.2, 1.5, 1.8], (n, 1))
        for name, values in (("AbsorptionCoefficient", mua),
                             ("ReducedScatteringCoefficient", sigma)):
            a = numpy_to_vtk(np.ascontiguousarray(values), deep=True)
            a.SetName(name)
            image.GetCellData().AddArray(a)
        truth = os.path.join(folder, "truth.vti")
        writer = vtkXMLImageDataWriter()
        writer.SetFileName(truth)
        writer.SetInputData(image)
        writer.Write()
        prefix = os.path.join(folder, "m")
        subprocess.run([find_cli("TestAcquirePlugin"), "acquire", "--synthetic-truth", truth, "--grid", "6x6x3",
                        "--patterns", "2x2", "--max-iter", "0", "--output", prefix, "--no-png"],
                       check=True, capture_output=True)
        reader = XMLUnstructuredGridReader(FileName=[prefix + "_measurements.vtu"])
        inverse = InverseDiffusion(Input=reader, ElementArrayName="VoxelId", MaxIterations=2,
                                   Lambda=1e-5)
        inverse.UpdatePipeline()
        mesh = servermanager.Fetch(inverse, idx=0)
        table = servermanager.Fetch(inverse, idx=1)
        self.assertEqual(mesh.GetNumberOfCells(), 6 * 6 * 6 * 3)
        kappa = vtk_to_numpy(mesh.GetCellData().GetArray("DiffusionCoefficient"))
        mu = vtk_to_numpy(mesh.GetCellData().GetArray("AbsorptionCoefficient"))
        self.assertTrue(np.all(kappa > 0) and np.all(mu > 0))
        voxel = vtk_to_numpy(mesh.GetCellData().GetArray("VoxelId"))
        self.assertTrue(np.all(kappa[voxel == 5] == kappa[voxel == 5][0]))
        for k in range(4):
            self.assertIsNotNone(mesh.GetPointData().GetArray("FittedRadiance_%d" % k))
        objective = vtk_to_numpy(table.GetColumnByName("Objective"))
        channel = vtk_to_numpy(table.GetColumnByName("Channel"))
        for c in range(3):
            rows = objective[channel == c]
            self.assertGreater(len(rows), 1)
            self.assertTrue(np.all(np.diff(rows) <= 0))


if __name__ == "__main__":
    unittest.main()
