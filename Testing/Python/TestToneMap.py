#!/usr/bin/env python3
"""The RadianceRGB array of vtkOutgoingRadiance (issue 20: show the rendered
appearance in ParaView with Map Scalars off, as the CLI's PNG does).

How to run (from a build tree; ctest sets the environment):

    PYTHONPATH=<build>/lib/python3.11/site-packages /usr/bin/python3 TestToneMap.py

1. With Exposure e, RadianceRGB = round(255 sRGB(clamp(e L))) for every point
   and channel, computed here independently from the sRGB definition
   (IEC 61966-2-1: 12.92 v below 0.0031308, 1.055 v^(1/2.4) - 0.055 above);
   components named R, G, B; RadianceExposure = e.
2. Exposure 0 (automatic): the exposure used is 0.9 / the 99th percentile of
   each point's brightest channel (numpy's order statistic): the brightest
   1 % reach sRGB(0.9) or more, at most 1 % saturate, none is all black.
3. A larger exposure never darkens a point (monotone).

Exits non-zero on failure (unittest).
"""

import unittest

import numpy as np

import translucency
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkFiltersSources import vtkSphereSource


def srgb(v):
    v = np.clip(v, 0.0, 1.0)
    return np.where(v <= 0.0031308, 12.92 * v, 1.055 * np.power(v, 1.0 / 2.4) - 0.055)


class ToneMapTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        sphere = vtkSphereSource()
        sphere.SetRadius(5.0)
        sphere.SetThetaResolution(20)
        sphere.SetPhiResolution(20)
        tetra = translucency.vtkTetrahedralizeSurface()
        tetra.SetInputConnection(sphere.GetOutputPort())
        tetra.SetTargetNumberOfTets(3000)
        assign = translucency.vtkAssignScatteringCoefficients()
        assign.SetInputConnection(tetra.GetOutputPort())
        assign.SetMaterialName("marble")
        light = translucency.vtkSurfaceIrradiance()  # the default lights
        light.SetInputConnection(assign.GetOutputPort())
        solve = translucency.vtkSolveDiffusion()
        solve.SetInputConnection(light.GetOutputPort())
        cls.radiance = translucency.vtkOutgoingRadiance()
        cls.radiance.SetInputConnection(solve.GetOutputPort())

    def run_with(self, exposure):
        self.radiance.SetExposure(exposure)
        output = translucency.update(self.radiance)
        data = output.GetPointData()
        rgb = data.GetArray("RadianceRGB")
        self.assertIsNotNone(rgb)
        self.assertEqual(rgb.GetDataTypeAsString(), "unsigned char")
        self.assertEqual([rgb.GetComponentName(c) for c in range(3)], ["R", "G", "B"])
        used = output.GetFieldData().GetArray("RadianceExposure").GetValue(0)
        self.assertEqual(used, self.radiance.GetExposureUsed())
        return (vtk_to_numpy(data.GetArray("Radiance")).copy(),
                vtk_to_numpy(rgb).astype(int), used)

    def test_explicit_exposure(self):
        radiance, rgb, used = self.run_with(2.0)
        self.assertEqual(used, 2.0)
        expected = np.rint(255.0 * srgb(2.0 * radiance)).astype(int)
        self.assertEqual(np.abs(rgb - expected).max(), 0)
        self.assertGreater(rgb.max(), 100)  # not a black picture

    def test_automatic_exposure(self):
        radiance, rgb, used = self.run_with(0.0)
        peaks = radiance.max(axis=1)
        k = int(0.99 * (len(peaks) - 1))
        p99 = np.partition(peaks, k)[k]
        self.assertAlmostEqual(used, 0.9 / p99, delta=1e-12 * used)
        expected = np.rint(255.0 * srgb(used * radiance)).astype(int)
        self.assertEqual(np.abs(rgb - expected).max(), 0)
        # The brightest 1 % of the points reach at least sRGB(0.9) (243 of
        # 255); at most 1 % saturate.
        bright = peaks >= p99
        self.assertGreater(int(np.sum(bright)), 0)
        self.assertTrue(np.all(rgb[bright].max(axis=1) >= int(np.rint(255 * srgb(0.9)))))
        self.assertLessEqual(np.mean(rgb.max(axis=1) == 255), 0.01)
        self.assertEqual(int(np.sum(rgb.max(axis=1) == 0)), 0)

    def test_monotone_in_exposure(self):
        _, dark, _ = self.run_with(0.5)
        _, bright, _ = self.run_with(3.0)
        self.assertTrue(np.all(bright >= dark))
        self.assertGreater(int(np.sum(bright > dark)), 0)


if __name__ == "__main__":
    unittest.main()
