#!/usr/bin/env python3
"""Image regression test of the translucent-radiosity Cornell box (the
paper's Fig. 6 panels: direct, subsurface only, inter-reflection only, combined).

How to run (ctest runs it under xvfb-run with the variables set):

    TRANSLUCENCY_CLI=<build>/bin/translucency xvfb-run -a /usr/bin/python3 Testing/Python/TestCornellBoxImage.py

To (re)create the committed baseline Testing/Baselines/cornell_box.png after a
deliberate change of the picture, look at the new image, then run it with
--update-baseline (under xvfb-run).

1. Runs `translucency radiosity --scene Data/cornell_box.json --png ... --json ...`.
2. Compares the PNG with the baseline (vtkImageDifference with the thresholds
   of TestDemoImage.py, plus the mean absolute difference) and checks that
   every panel is not blank.
3. Physics, from the written .vtp files: the marble side facing the red wall
   is redder (R/G) than the side facing the green wall, by more than 50 %,
   and that difference is absent from the first bounce (white light);
   radiosity = first bounce + inter-reflection; the iteration converged.
"""

import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

import numpy as np

from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkImagingCore import vtkImageDifference
from vtkmodules.vtkIOImage import vtkPNGReader
from vtkmodules.vtkIOXML import vtkXMLPolyDataReader

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_under_test import find_cli  # noqa: E402

SOURCE_DIR = os.environ.get("TRANSLUCENCY_SOURCE_DIR") or os.path.abspath(
    os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
BASELINE = os.path.join(SOURCE_DIR, "Testing", "Baselines", "cornell_box.png")
SCENE = os.path.join(SOURCE_DIR, "Data", "cornell_box.json")
PIXEL_THRESHOLD = 16
IMAGE_TOLERANCE = 10.0
MEAN_TOLERANCE = 2.0


def run(out_dir):
    png = os.path.join(out_dir, "cornell.png")
    report = os.path.join(out_dir, "cornell.json")
    command = [find_cli("TestCornellBoxImage"), "radiosity", "--scene", SCENE, "--output",
               os.path.join(out_dir, "cornell"), "--png", png, "--json", report]
    if not os.environ.get("DISPLAY") and shutil.which("xvfb-run"):
        command = ["xvfb-run", "-a", "-s", "-screen 0 1024x768x24"] + command
    result = subprocess.run(command, capture_output=True, text=True, timeout=800)
    return png, report, result


def read_png(path):
    reader = vtkPNGReader()
    reader.SetFileName(path)
    reader.Update()
    return reader.GetOutput()


def cell_array(poly, name):
    return vtk_to_numpy(poly.GetCellData().GetArray(name))


class TestCornellBoxImage(unittest.TestCase):
    def test_image_and_bleeding(self):
        with tempfile.TemporaryDirectory() as tmp:
            png, report, result = run(tmp)
            self.assertEqual(result.returncode, 0, result.stderr)
            with open(report) as f:
                data = json.load(f)
            self.assertTrue(data["converged"])

            # 3. Colour bleeding on the marble (object 2).
            reader = vtkXMLPolyDataReader()
            reader.SetFileName(os.path.join(tmp, "cornell_2.vtp"))
            reader.Update()
            marble = reader.GetOutput()
            pts = vtk_to_numpy(marble.GetPoints().GetData())
            normals = []
            for c in range(marble.GetNumberOfCells()):
                ids = [marble.GetCell(c).GetPointId(k) for k in range(3)]
                a, b, d = pts[ids]
                n = np.cross(b - a, d - a)
                normals.append(n / np.linalg.norm(n))
            normals = np.array(normals)
            combined = cell_array(marble, "Radiosity")
            first = cell_array(marble, "SubsurfaceRadiosity")
            inter = cell_array(marble, "InterReflectionRadiosity")
            np.testing.assert_allclose(combined, first + inter, rtol=1e-12, atol=1e-12)
            red, green = normals[:, 0] < -0.9, normals[:, 0] > 0.9
            rg = lambda sel, arr: arr[sel, 0].sum() / arr[sel, 1].sum()
            self.assertGreater(rg(red, combined), 1.5 * rg(green, combined))
            if first[red].sum() > 0 and first[green].sum() > 0:
                self.assertLess(abs(rg(red, first) / rg(green, first) - 1.0), 0.2)

            # 2. The picture.
            if "--update-baseline" in sys.argv:
                shutil.copyfile(png, BASELINE)
                print("wrote the baseline %s: look at it before committing" % BASELINE)
                return
            self.assertTrue(os.path.exists(BASELINE), "missing baseline %s" % BASELINE)
            new, old = read_png(png), read_png(BASELINE)
            self.assertEqual(new.GetDimensions(), old.GetDimensions())
            a = vtk_to_numpy(new.GetPointData().GetScalars()).astype(int)
            width = new.GetDimensions()[0]
            for panel in range(4):
                cols = (np.arange(a.shape[0]) % width) // (width // 4) == panel
                self.assertGreater((a[cols].max(axis=1) > 10).mean(), 0.2, "panel %d blank" % panel)
            diff = vtkImageDifference()
            diff.SetInputData(new)
            diff.SetImageData(old)
            diff.SetThreshold(PIXEL_THRESHOLD)
            diff.AllowShiftOn()
            diff.AveragingOn()
            diff.Update()
            b = vtk_to_numpy(old.GetPointData().GetScalars()).astype(int)
            mean = np.abs(a - b).mean()
            if diff.GetThresholdedError() > IMAGE_TOLERANCE or mean > MEAN_TOLERANCE:
                kept = os.path.join(os.environ.get("TRANSLUCENCY_BINARY_DIR", tmp),
                                    "cornell_box_new.png")
                shutil.copyfile(png, kept)
                self.fail("image differs from %s: thresholded error %.1f, mean %.2f (new image: %s)"
                          % (BASELINE, diff.GetThresholdedError(), mean, kept))


if __name__ == "__main__":
    unittest.main(argv=[a for a in sys.argv if a != "--update-baseline"])
