#!/usr/bin/env python3
"""No exit 0 with NaN or nonsense (issue 34, finding 5).

How to run (from a build tree; ctest sets the variable itself):

    TRANSLUCENCY_CLI=<build>/bin/translucency /usr/bin/python3 TestMeaninglessResults.py

Each degenerate setting once gave exit 0 with a NaN or an all-zero result.
Each must now exit 1 (2 for the option checks of --time-gates) with a
message stating the number that makes it meaningless, and write nothing:

1. --solver grid --grid-spacing 1e300 (a spacing larger than the object);
2. --time-gates 0,1e-320,10 (a time step of 2.5e-322 ns) and 0,1e308,10
   (gates to 1e308 ns);
3. --frequency 1e308 (and 1e13 Hz: a diffusion wave of a few micrometres,
   below the mesh's edge);
4. acquire with a -inf (and a NaN) measurement;
5. a point light (and a spot light) inside the object.
And the neighbours that are meaningful still run: --grid-spacing 2 on the
10 mm cube, --frequency 1e8, a point light outside the object.

Exits non-zero on failure (unittest).
"""

import os
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_under_test import find_cli  # noqa: E402

CLI = find_cli("TestMeaninglessResults")
TIME_LIMIT = 300

CUBE_OBJ = "\n".join(
    ["v 0 0 0", "v 10 0 0", "v 10 10 0", "v 0 10 0", "v 0 0 10", "v 10 0 10", "v 10 10 10",
     "v 0 10 10", "f 1 3 2", "f 1 4 3", "f 5 6 7", "f 5 7 8", "f 1 2 6", "f 1 6 5", "f 2 3 7",
     "f 2 7 6", "f 3 4 8", "f 3 8 7", "f 4 1 5", "f 4 5 8"]) + "\n"
SMALL = ["--max-tet-volume", "4", "--no-shadows", "--uniform-samples", "1"]
OPTICS = ["--source", "pencil:5,5,10:0,0,-1", "--detector", "8,5,10"]


class MeaninglessResults(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.dir = cls.tmp.name
        cls.cube = os.path.join(cls.dir, "cube.obj")
        with open(cls.cube, "w") as f:
            f.write(CUBE_OBJ)
        cls.out = os.path.join(cls.dir, "out")

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def run_cli(self, args):
        try:
            return subprocess.run([CLI] + args, capture_output=True, text=True, timeout=TIME_LIMIT)
        except subprocess.TimeoutExpired:
            self.fail("no answer within %d s: %s" % (TIME_LIMIT, " ".join(args)))

    def render(self, *args):
        return self.run_cli(["render", "--mesh", self.cube] + SMALL + list(args) +
                            ["--output", self.out])

    def expect_refused(self, result, *needles, code=1):
        self.assertEqual(result.returncode, code, result.stdout + result.stderr)
        for needle in needles:
            self.assertIn(needle, result.stderr)
        for ext in (".vtu", ".vtp"):
            self.assertFalse(os.path.exists(self.out + ext), ext)

    def test_grid_spacing_larger_than_the_object(self):
        self.expect_refused(self.render("--solver", "grid", "--grid-spacing", "1e300"),
                            "grid spacing 1e+300 mm is larger than the object", "10 x 10 x 10 mm")
        ok = self.render("--solver", "grid", "--grid-spacing", "2")
        self.assertEqual(ok.returncode, 0, ok.stderr)
        for ext in (".vtu", ".vtp"):
            os.remove(self.out + ext)

    def test_degenerate_time_gates(self):
        self.expect_refused(self.render(*OPTICS, "--time-gates", "0,1e-320,10"),
                            "the gates are too narrow", "is below 1e-06 ns", code=2)
        self.expect_refused(self.render(*OPTICS, "--time-gates", "0,1e308,10"),
                            "T1 = 1e+308 ns is later than 1000000 ns", code=2)

    def test_frequency_beyond_the_mesh(self):
        self.expect_refused(self.render(*OPTICS, "--frequency", "1e308"),
                            "modulation frequency 1e+308 Hz")
        self.expect_refused(self.render(*OPTICS, "--frequency", "1e13"),
                            "modulation frequency 1e+13 Hz",
                            "is below the mesh's typical edge")
        ok = self.render(*OPTICS, "--frequency", "1e8")
        self.assertEqual(ok.returncode, 0, ok.stderr)
        for ext in (".vtu", ".vtp"):
            os.remove(self.out + ext)

    def test_acquire_refuses_non_finite_measurements(self):
        from vtkmodules.vtkCommonCore import vtkDoubleArray
        from vtkmodules.vtkCommonDataModel import vtkImageData
        from vtkmodules.vtkIOXML import (vtkXMLImageDataWriter, vtkXMLUnstructuredGridReader,
                                         vtkXMLUnstructuredGridWriter)
        image = vtkImageData()
        image.SetDimensions(5, 5, 3)
        for name, value in (("AbsorptionCoefficient", 0.01), ("ReducedScatteringCoefficient", 1.0)):
            array = vtkDoubleArray()
            array.SetName(name)
            array.SetNumberOfComponents(3)
            for _ in range(image.GetNumberOfCells()):
                array.InsertNextTuple3(value, value, value)
            image.GetCellData().AddArray(array)
        truth = os.path.join(self.dir, "truth.vti")
        writer = vtkXMLImageDataWriter()
        writer.SetFileName(truth)
        writer.SetInputData(image)
        writer.Write()
        prefix = os.path.join(self.dir, "syn")
        made = self.run_cli(["acquire", "--synthetic-truth", truth, "--grid", "4x4x2",
                             "--patterns", "1x1", "--max-iter", "1", "--no-png", "--output",
                             prefix])
        self.assertEqual(made.returncode, 0, made.stderr)
        reader = vtkXMLUnstructuredGridReader()
        reader.SetFileName(prefix + "_measurements.vtu")
        reader.Update()
        grid = reader.GetOutput()
        radiance = grid.GetPointData().GetArray("Radiance_0")
        self.assertIsNotNone(radiance)
        for value, shown in ((float("-inf"), "-inf"), (float("nan"), "nan")):
            with self.subTest(value=shown):
                radiance.SetComponent(3, 1, value)
                damaged = os.path.join(self.dir, "damaged_%s.vtu" % shown.strip("-"))
                w = vtkXMLUnstructuredGridWriter()
                w.SetFileName(damaged)
                w.SetInputData(grid)
                w.Write()
                out = os.path.join(self.dir, "fit_" + shown.strip("-"))
                result = self.run_cli(["acquire", "--sample", damaged, "--patterns", damaged,
                                       "--max-iter", "1", "--no-png", "--output", out])
                self.assertEqual(result.returncode, 1, result.stdout + result.stderr)
                self.assertIn("measurement 'Radiance_0' holds %s at point 3" % shown,
                              result.stderr)
                self.assertFalse(os.path.exists(out + ".vtu"))

    def test_light_inside_the_object(self):
        self.expect_refused(self.render("--light", "point:5,5,5:1"),
                            "--light point at (5, 5, 5) mm is inside the object",
                            "--source point")
        self.expect_refused(self.render("--light", "spot:5,5,4:0,0,-1:30:1"),
                            "--light spot at (5, 5, 4) mm is inside the object")
        ok = self.render("--light", "point:5,5,20:1")
        self.assertEqual(ok.returncode, 0, ok.stderr)
        for ext in (".vtu", ".vtp"):
            os.remove(self.out + ext)


if __name__ == "__main__":
    unittest.main()
