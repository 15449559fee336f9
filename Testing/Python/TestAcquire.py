#!/usr/bin/env python3
"""Tests of `translucency acquire` and vtkInverseDiffusion (inverse diffusion).

How to run (from a build tree; ctest sets the variables itself):

    TRANSLUCENCY_CLI=<build>/bin/translucency \\
    PYTHONPATH=<build>/lib/python3.11/site-packages /usr/bin/python3 TestAcquire.py

1. `--help` documents the acquire options of the issue.
2. Synthetic mode on a small block with an inclusion: writes the recovered
   .vtu, the measurements .vtu, the JSON report and the PNGs; the JSON agrees
   with the files (pattern count, tets, channel objectives below the
   threshold); the recovered arrays follow the data contract (kappa =
   1/(3 (mu_a + sigma_s')) where sigma_s' > 0); the fitted radiance is within
   2 % RMS of the measurements (recomputed here from the arrays).
3. File mode on the written measurements (one .vtu, then a directory of one
   .vtu per pattern) gives the same material as the synthetic run
   (deterministic optimisation, same data by another path).
4. The pictures hold what they claim: the measured and fitted tiles of the
   radiance mosaic agree, and the true-mu_a tile of the top layer shows the
   inclusion (two colours) while the bottom layer's is uniform.
5. Bad input exits non-zero naming the problem, and does not replace an
   existing output: a pattern without its Radiance array, a NaN radiance, an
   empty mask, a non-positive initial value, a missing file, a bad --grid.
6. The filter directly: history table columns, ObservedMask shared by all
   patterns, ElementArrayName that does not exist.
7. The time estimate (issue 34: it said 5.1 s for 39 s of CPU): with
   --threshold 0 every --max-iter iteration runs; the estimated forward,
   adjoint and tangent passes are within 25 % of those the fit counted (work
   units, robust under load) and the estimated CPU seconds within a factor 3
   of the process's CPU time during the fit (both measured in this run), on
   the grid itself and on one calibrated smaller and scaled up; the files
   mode gives an estimate too.
8. --quiet: no progress bar, no estimate line, no raw VTK log line; what is
   left on stderr are "translucency: " lines (warnings), in synthetic mode
   with pictures and in files mode.

Exits non-zero on failure (unittest).
"""

import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

import numpy as np
import vtk
import translucency
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_under_test import find_cli  # noqa: E402

CLI = find_cli("TestAcquire")


def run(*args):
    return subprocess.run([CLI, *args], capture_output=True, text=True)


def read_vtu(path):
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(path)
    reader.Update()
    return reader.GetOutput()


def write_vtu(grid, path):
    writer = vtk.vtkXMLUnstructuredGridWriter()
    writer.SetFileName(path)
    writer.SetInputData(grid)
    writer.Write()


def array(data, name, cell=False):
    attributes = data.GetCellData() if cell else data.GetPointData()
    a = attributes.GetArray(name)
    if a is None:
        raise AssertionError("missing array %s" % name)
    return vtk_to_numpy(a)


def read_png(path):
    reader = vtk.vtkPNGReader()
    reader.SetFileName(path)
    reader.Update()
    image = reader.GetOutput()
    w, h, _ = image.GetDimensions()
    pixels = vtk_to_numpy(image.GetPointData().GetScalars()).reshape(h, w, -1)
    return pixels[::-1]  # row 0 at the top


class TestAcquire(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.mkdtemp(prefix="translucency_acquire_")
        # Truth: 4 x 4 x 1.5 mm block, inclusion under the top (measured) face.
        n = (16, 16, 6)
        image = vtk.vtkImageData()
        image.SetDimensions(n[0] + 1, n[1] + 1, n[2] + 1)
        image.SetSpacing(4.0 / n[0], 4.0 / n[1], 1.5 / n[2])
        k, j, i = np.meshgrid(np.arange(n[2]), np.arange(n[1]), np.arange(n[0]), indexing="ij")
        x, y, z = (i + 0.5) * 4.0 / n[0], (j + 0.5) * 4.0 / n[1], (k + 0.5) * 1.5 / n[2]
        inside = ((x - 1.6) ** 2 + (y - 2.2) ** 2 < 0.9 ** 2) & (z > 0.75)
        mua = np.where(inside[..., None], [0.08, 0.15, 0.25], [0.03, 0.05, 0.08]).reshape(-1, 3)
        sigma = np.where(inside[..., None], [0.7, 0.9, 1.0], [1.2, 1.5, 1.8]).reshape(-1, 3)
        for name, values in (("AbsorptionCoefficient", mua),
                             ("ReducedScatteringCoefficient", sigma)):
            a = numpy_to_vtk(np.ascontiguousarray(values), deep=True)
            a.SetName(name)
            image.GetCellData().AddArray(a)
        cls.truth = os.path.join(cls.dir, "truth.vti")
        writer = vtk.vtkXMLImageDataWriter()
        writer.SetFileName(cls.truth)
        writer.SetInputData(image)
        writer.Write()
        cls.prefix = os.path.join(cls.dir, "syn")
        cls.result = run("acquire", "--synthetic-truth", cls.truth, "--grid", "8x8x3",
                         "--patterns", "3x3", "--setup", "back", "--output", cls.prefix,
                         "--json", cls.prefix + ".json", "--no-png")
        cls.png_prefix = os.path.join(cls.dir, "png")
        cls.png_result = run("acquire", "--synthetic-truth", cls.truth, "--grid", "8x8x3",
                             "--patterns", "2x2", "--setup", "front", "--max-iter", "30",
                             "--output", cls.png_prefix)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.dir, ignore_errors=True)

    def test_1_help(self):
        out = run("--help").stdout
        for option in ("acquire", "--sample", "--patterns", "--output", "--lambda", "--max-iter",
                       "--json", "--synthetic-truth", "--grid", "--setup", "--noise",
                       "--homogeneous-fit", "--line-search-start"):
            self.assertIn(option, out)

    def test_2_synthetic(self):
        self.assertEqual(self.result.returncode, 0, self.result.stderr)
        with open(self.prefix + ".json") as f:
            report = json.load(f)
        out = read_vtu(self.prefix + ".vtu")
        self.assertEqual(report["patterns"], 9)
        self.assertEqual(report["tets"], out.GetNumberOfCells())
        self.assertEqual(out.GetNumberOfCells(), 6 * 8 * 8 * 3)
        self.assertEqual(report["grid"], [8, 8, 3])
        for channel in report["channels"]:
            self.assertTrue(channel["converged"], channel["channel"])
            self.assertLess(channel["final_objective"], 1e-4)
            objectives = [row["objective"] for row in channel["history"]]
            self.assertLess(objectives[-1], objectives[0])
        self.assertGreater(report["seconds_per_gradient"], 0.0)
        mua = array(out, "AbsorptionCoefficient", True)
        sigma = array(out, "ReducedScatteringCoefficient", True)
        kappa = array(out, "DiffusionCoefficient", True)
        self.assertTrue(np.all(mua > 0) and np.all(kappa > 0))
        ok = sigma > 0
        np.testing.assert_allclose(kappa[ok], 1.0 / (3.0 * (mua[ok] + sigma[ok])), rtol=1e-12)
        # Voxel-wise constant: the 6 tets of a voxel share their values.
        voxel = array(out, "VoxelId", True)
        for v in (0, 77, 191):
            rows = kappa[voxel == v]
            self.assertEqual(len(rows), 6)
            self.assertTrue(np.all(rows == rows[0]))
        # Fitted radiance vs measurements, recomputed from the arrays.
        num = den = 0.0
        for m in range(9):
            measured = array(out, "Radiance_%d" % m)
            fitted = array(out, "FittedRadiance_%d" % m)
            mask = array(out, "ObservedMask_%d" % m) != 0
            num += np.sum((fitted[mask] - measured[mask]) ** 2)
            den += np.sum(measured[mask] ** 2)
        rms = math.sqrt(num / den)
        self.assertLess(rms, 0.02)
        self.assertAlmostEqual(rms, report["fit_relative_rms"], places=9)

    def test_3_file_modes_agree(self):
        self.assertEqual(self.result.returncode, 0, self.result.stderr)
        measurements = self.prefix + "_measurements.vtu"
        reference = array(read_vtu(self.prefix + ".vtu"), "DiffusionCoefficient", True)
        prefix = os.path.join(self.dir, "file")
        r = run("acquire", "--sample", measurements, "--patterns", measurements,
                "--output", prefix, "--no-png")
        self.assertEqual(r.returncode, 0, r.stderr)
        np.testing.assert_array_equal(
            array(read_vtu(prefix + ".vtu"), "DiffusionCoefficient", True), reference)
        # A directory of one file per pattern.
        grid = read_vtu(measurements)
        pattern_dir = os.path.join(self.dir, "patterns")
        os.makedirs(pattern_dir, exist_ok=True)
        for m in range(9):
            one = vtk.vtkUnstructuredGrid()
            one.ShallowCopy(grid)
            pd = vtk.vtkPointData()
            for base in ("Irradiance", "Radiance", "ObservedMask"):
                a = grid.GetPointData().GetArray("%s_%d" % (base, m))
                copy = a.NewInstance()
                copy.DeepCopy(a)
                copy.SetName(base)
                pd.AddArray(copy)
            one.GetPointData().ShallowCopy(pd)
            write_vtu(one, os.path.join(pattern_dir, "pattern_%02d.vtu" % m))
        prefix = os.path.join(self.dir, "dir")
        r = run("acquire", "--sample", measurements, "--patterns", pattern_dir,
                "--output", prefix, "--no-png")
        self.assertEqual(r.returncode, 0, r.stderr)
        np.testing.assert_array_equal(
            array(read_vtu(prefix + ".vtu"), "DiffusionCoefficient", True), reference)

    def test_4_pictures(self):
        self.assertEqual(self.png_result.returncode, 0, self.png_result.stderr)
        radiance = read_png(self.png_prefix + "_radiance.png").astype(float)
        # 2 columns of (measured | fitted) tiles of 9x9 points; scale 16 -> 144 px.
        tile, gap = 9 * 16, 6
        self.assertEqual(radiance.shape[1], 2 * (2 * tile + 3 * gap))
        measured = radiance[gap:gap + tile, gap:gap + tile]
        fitted = radiance[gap:gap + tile, 2 * gap + tile:2 * gap + 2 * tile]
        self.assertGreater(np.abs(measured - measured.mean()).mean(), 5.0)  # not blank
        self.assertLess(np.abs(measured - fitted).mean(), 8.0)
        slices = read_png(self.png_prefix + "_slices.png").astype(float)
        tile = 8 * 16
        # Front setup: the layer nearest the camera is z = 0 (row 0, uniform
        # truth); the inclusion is in the top layers. True mu_a is column 4.
        x0 = 3 * (tile + gap) + 2 * gap
        rows = slices.shape[0] // (tile + gap)
        first = slices[gap:gap + tile, x0:x0 + tile].reshape(-1, 3)
        self.assertEqual(len(np.unique(first, axis=0)), 1)
        last = slices[(rows - 1) * (tile + gap) + gap:rows * (tile + gap), x0:x0 + tile]
        self.assertGreaterEqual(len(np.unique(last.reshape(-1, 3), axis=0)), 2)

    def test_5_bad_input(self):
        self.assertEqual(self.result.returncode, 0, self.result.stderr)
        grid = read_vtu(self.prefix + "_measurements.vtu")
        output = os.path.join(self.dir, "bad")
        with open(output + ".vtu", "w") as f:
            f.write("keep me")

        def expect_failure(args, words):
            r = run("acquire", *args, "--output", output, "--no-png")
            self.assertNotEqual(r.returncode, 0, "expected a failure for %s" % (args,))
            self.assertIn(words, r.stderr)
            with open(output + ".vtu") as f:
                self.assertEqual(f.read(), "keep me")

        def variant(name, edit):
            g = vtk.vtkUnstructuredGrid()
            g.DeepCopy(grid)
            edit(g)
            path = os.path.join(self.dir, name + ".vtu")
            write_vtu(g, path)
            return path

        path = variant("missing", lambda g: g.GetPointData().RemoveArray("Radiance_8"))
        expect_failure(["--sample", path, "--patterns", path],
                       "9 illumination patterns (Irradiance_<k>) but 8 measurements")

        def nan(g):
            a = g.GetPointData().GetArray("Radiance_2")
            mask = g.GetPointData().GetArray("ObservedMask_2")
            i = next(i for i in range(mask.GetNumberOfTuples()) if mask.GetValue(i))
            a.SetComponent(i, 1, float("nan"))
            nan.point = i
        path = variant("nan", nan)
        expect_failure(["--sample", path, "--patterns", path],
                       "measurement 'Radiance_2' holds nan at point %d (component 1)" % nan.point)

        def empty(g):
            mask = g.GetPointData().GetArray("ObservedMask_4")
            for i in range(mask.GetNumberOfTuples()):
                mask.SetValue(i, 0)
        path = variant("empty", empty)
        expect_failure(["--sample", path, "--patterns", path], "pattern 4 has no observed point")
        path = self.prefix + "_measurements.vtu"
        expect_failure(["--sample", path, "--patterns", path, "--initial-mua", "0.01,-1,0.01"],
                       "channel G: mu_a = -1")
        expect_failure(["--sample", os.path.join(self.dir, "nothing.vtu"), "--patterns", path],
                       "nothing.vtu")
        expect_failure(["--sample", path, "--patterns", path, "--homogeneous-fit", "newton"],
                       "'newton' is not gauss-newton or cg")
        expect_failure(["--sample", path, "--patterns", path, "--line-search-start", "x"],
                       "'x' is not gauss-newton or previous")
        r = run("acquire", "--synthetic-truth", self.truth, "--grid", "8x0x3", "--patterns", "2x2",
                "--output", output)
        self.assertEqual(r.returncode, 2)
        self.assertIn("--grid", r.stderr)

    def test_6_filter(self):
        self.assertEqual(self.result.returncode, 0, self.result.stderr)
        grid = read_vtu(self.prefix + "_measurements.vtu")
        # One shared mask (the back face is the same for every pattern).
        shared = vtk.vtkUnstructuredGrid()
        shared.DeepCopy(grid)
        mask = shared.GetPointData().GetArray("ObservedMask_0")
        for m in range(9):
            shared.GetPointData().RemoveArray("ObservedMask_%d" % m)
        mask.SetName("ObservedMask")
        shared.GetPointData().AddArray(mask)
        inverse = translucency.vtkInverseDiffusion()
        inverse.SetInputData(shared)
        inverse.SetElementArrayName("VoxelId")
        inverse.SetMaxIterations(2)
        inverse.Update()
        table = inverse.GetOutputDataObject(1)
        names = [table.GetColumnName(c) for c in range(table.GetNumberOfColumns())]
        self.assertEqual(names, ["Channel", "Stage", "Iteration", "Objective", "DataTerm",
                                 "GradientNorm", "Step", "Evaluations"])
        objective = vtk_to_numpy(table.GetColumnByName("Objective"))
        channel = vtk_to_numpy(table.GetColumnByName("Channel"))
        for c in range(3):
            rows = objective[channel == c]
            self.assertTrue(np.all(np.diff(rows) <= 0), rows)
        self.assertEqual(inverse.GetOutput().GetNumberOfCells(), grid.GetNumberOfCells())
        # A missing element array is an error.
        errors = []
        observer = lambda obj, event: errors.append(event)
        bad = translucency.vtkInverseDiffusion()
        bad.AddObserver("ErrorEvent", observer)
        bad.GetExecutive().AddObserver("ErrorEvent", observer)
        bad.SetInputData(grid)
        bad.SetElementArrayName("NoSuchArray")
        bad.Update()
        self.assertTrue(errors)


    def estimate_run(self, name, grid, *extra):
        prefix = os.path.join(self.dir, name)
        r = run("acquire", "--synthetic-truth", self.truth, "--grid", grid, "--patterns", "2x2",
                "--threshold", "0", "--max-iter", "6", "--no-png", "--output", prefix,
                "--json", prefix + ".json", *extra)
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(prefix + ".json") as f:
            return json.load(f), r

    def test_7_time_estimate(self):
        for grid in ("10x10x3", "20x20x12"):  # 20x20x12: 5,733 points, calibrated on fewer
            with self.subTest(grid=grid):
                report, r = self.estimate_run("estimate_" + grid, grid)
                self.assertIn("acquire: estimate: about ", r.stderr)
                self.assertIn("if all 6 iterations run", r.stderr)
                for channel in report["channels"]:  # --threshold 0: every iteration ran
                    self.assertEqual(channel["history"][-1]["iteration"], 6)
                e = report["estimate"]
                self.assertEqual(e["scaled"], grid != "10x10x3")
                for estimated, counted in ((e["forward_passes"], report["evaluations"]),
                                           (e["adjoint_passes"], report["gradients"]),
                                           (e["tangent_passes"], report["tangents"])):
                    self.assertGreater(counted, 0)
                    self.assertLess(abs(estimated / counted - 1.0), 0.25, (estimated, counted))
                ratio = e["cpu_seconds"] / report["cpu_seconds_fit"]
                self.assertTrue(1.0 / 3.0 < ratio < 3.0, (e, report["cpu_seconds_fit"]))
        # The paper's CG for the homogeneous pair and the previous step as the
        # line search's start: other pass counts, still the same within 25 %
        # for forward and adjoint passes (no tangent pass at all).
        report, _ = self.estimate_run("estimate_cg", "10x10x3", "--homogeneous-fit", "cg",
                                      "--line-search-start", "previous")
        e = report["estimate"]
        self.assertEqual(report["tangents"], 0)
        self.assertEqual(e["tangent_passes"], 0)
        for estimated, counted in ((e["forward_passes"], report["evaluations"]),
                                   (e["adjoint_passes"], report["gradients"])):
            self.assertLess(abs(estimated / counted - 1.0), 0.25, (estimated, counted))
        # Files mode: the estimate from a cube of as many points.
        measurements = os.path.join(self.dir, "estimate_10x10x3_measurements.vtu")
        prefix = os.path.join(self.dir, "estimate_files")
        r = run("acquire", "--sample", measurements, "--patterns", measurements, "--no-png",
                "--max-iter", "2", "--output", prefix, "--json", prefix + ".json")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("acquire: estimate: about ", r.stderr)
        with open(prefix + ".json") as f:
            self.assertGreater(json.load(f)["estimate"]["cpu_seconds"], 0.0)

    def test_8_quiet(self):
        prefix = os.path.join(self.dir, "quiet")
        synthetic = run("acquire", "--synthetic-truth", self.truth, "--grid", "6x6x2",
                        "--patterns", "2x2", "--max-iter", "3", "--output", prefix, "--quiet")
        self.assertEqual(synthetic.returncode, 0, synthetic.stderr)
        files = run("acquire", "--sample", prefix + "_measurements.vtu", "--patterns",
                    prefix + "_measurements.vtu", "--max-iter", "3", "--output",
                    prefix + "_files", "--quiet")
        self.assertEqual(files.returncode, 0, files.stderr)
        for r in (synthetic, files):
            self.assertNotIn("acquire [", r.stderr)  # the progress bar
            self.assertNotIn("estimate", r.stderr)
            for line in r.stderr.splitlines():
                if line.strip():
                    self.assertTrue(line.startswith("translucency: "), r.stderr)
                self.assertNotIn(".cxx, line", line)  # VTK's own message header
                self.assertNotIn("vtkOutputWindow", line)


if __name__ == "__main__":
    unittest.main()
