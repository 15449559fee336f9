#!/usr/bin/env python3
"""Time-resolved diffusion through the command line: `translucency render
--time-gates T0,T1,N` (with --steps-per-gate, --time-snapshots;
Apps/DiffuseOpticsOptions, Documentation/DiffuseOptics.md).

How to run (from a build tree; ctest sets the variables itself):

    TRANSLUCENCY_CLI=<build>/bin/translucency \\
    PYTHONPATH=<build>/lib/python3.11/site-packages /usr/bin/python3 TestTimeResolvedCLI.py

1. A pencil beam in a 20 x 20 x 10 mm box, two detectors, 100 gates over
   0-4 ns: the JSON report has the gates and, per detector, a TPSF of 100
   values per channel; the readings are the time integrals of the TPSFs
   (sum of width x gate average, to rounding); they equal the continuous-
   wave readings (the power identity; the response has died out by 4 ns:
   1e-6 relative at rel-tol 1e-10); the farther detector peaks later; the
   point arrays FluenceGate<g> of --time-snapshots are there; positive once
   the front has reached every vertex (gate 20, 0.8 ns; measured: the
   smallest value 2e-4 of the largest); in gates 1 and 5 small undershoots
   ahead of the front, which this 1.5 mm mesh does not resolve (the discrete
   divergence is not an M-matrix on obtuse tets): measured -0.7 % and
   -0.02 % of the gate's largest value, bound 2 %.
1b. `compare` with --time-gates and detectors: every solver's TPSF (fem,
   divergence, montecarlo) in tpsf.csv and the JSON; Monte Carlo's exitance
   within 3 SE + 10 % of fem's at the peak.
1c. `compare --measured FILE`: the measured columns scaled to the reference's
   area (1e-9), the closed form against an independent implementation
   (1e-5), skipped on a heterogeneous material; malformed files (a
   non-numeric cell, the column count, times not increasing, no time unit,
   a short row, one row, no overlap with the gates, no positive area, a
   missing file) each an error naming the file and the place.
2. Bad input (gates with T1 <= T0, N < 1, N not whole, too many gates or
   steps, non-finite or negative T0, --frequency with --time-gates, a
   snapshot gate >= N, --steps-per-gate without --time-gates, a solver
   without time gates, snapshots with montecarlo) exits non-zero with a message naming the option and
   the value, and leaves an existing output file alone.

Exits non-zero on failure (unittest).
"""

import json
import os
import subprocess
import sys
import unittest

import numpy as np

from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader


from cli_under_test import BoxRenderTest, find_cli  # noqa: E402

CLI = find_cli("TestTimeResolvedCLI")


class TimeResolvedCLI(BoxRenderTest):
    CLI = CLI
    BOX_TETS = 10000

    def render(self, extra, name):
        prefix = os.path.join(self.dir.name, name)
        result = self.run_ok(["--mesh", self.mesh, "--solver", "divergence", "--rel-tol", "1e-10",
                              "--max-iter", "20000", "--output", prefix,
                              "--json", prefix + ".json"] + extra)
        with open(prefix + ".json") as f:
            report = json.load(f)
        reader = vtkXMLUnstructuredGridReader()
        reader.SetFileName(prefix + ".vtu")
        reader.Update()
        return report, reader.GetOutput().GetPointData(), result.stdout

    def test_tpsf(self):
        extra = ["--source", "pencil:0,0,5:0,0,-1", "--detector", "3,0,5",
                 "--detector", "8,0,5"]
        cw, _, _ = self.render(extra, "cw")
        tr, points, stdout = self.render(
            extra + ["--time-gates", "0,4,100", "--time-snapshots", "1,5", "--time-snapshots", "20"],
            "tr")
        gates = tr["time_gates"]
        self.assertEqual(gates["count"], 100)
        self.assertAlmostEqual(gates["width_ns"], 0.04, places=12)
        self.assertGreaterEqual(gates["steps_per_gate"], 4)
        self.assertEqual(len(gates["gate_centres_ns"]), 100)
        self.assertAlmostEqual(gates["gate_centres_ns"][0], 0.02, places=12)
        self.assertIn("TPSF", stdout)
        peaks = []
        for k, detector in enumerate(tr["detectors"]):
            for c in "RGB":
                tpsf = np.array(detector["tpsf"]["fluence_j_mm2_ns"][c])
                exitance = np.array(detector["tpsf"]["exitance_j_mm2_ns"][c])
                self.assertEqual(tpsf.shape, (100,))
                self.assertTrue(np.all(tpsf > 0.0))
                # The reading is the time integral of the TPSF ...
                self.assertAlmostEqual(0.04 * tpsf.sum() / detector["fluence_w_mm2"][c], 1.0,
                                       places=9)
                self.assertAlmostEqual(0.04 * exitance.sum() / detector["exitance_w_mm2"][c],
                                       1.0, places=9)
                # ... and the time integral is the continuous-wave reading.
                for key in ("fluence_w_mm2", "exitance_w_mm2"):
                    self.assertAlmostEqual(detector[key][c] / cw["detectors"][k][key][c], 1.0,
                                           places=6)
            peaks.append(int(np.argmax(detector["tpsf"]["fluence_j_mm2_ns"]["R"])))
        self.assertLess(peaks[0], peaks[1])  # the farther detector peaks later
        for g in (1, 5, 20):
            snapshot = vtk_to_numpy(points.GetArray("FluenceGate%d" % g))
            self.assertEqual(snapshot.shape[1], 3)
            self.assertGreater(snapshot.min(), -0.02 * snapshot.max() if g < 20 else 0.0, g)
        self.assertIsNone(points.GetArray("FluenceGate6"))

    def test_montecarlo_tpsf(self):
        """Monte Carlo fills the same detector outputs from its photons'
        time of flight: the gate averages integrate to the readings, the
        farther fibre peaks later, and the standard errors are in the
        .vtu's field data."""
        prefix = os.path.join(self.dir.name, "mc")
        result = self.run_ok(["--mesh", self.mesh, "--solver", "montecarlo", "--photons", "20000",
                              "--anisotropy", "0.5", "--source", "pencil:0,0,5:0,0,-1",
                              "--detector", "3,0,5:1", "--detector", "6,0,5:1.5",
                              "--time-gates", "0,2,40", "--output", prefix,
                              "--json", prefix + ".json"])
        self.assertIn("TPSF", result.stdout)
        with open(prefix + ".json") as f:
            report = json.load(f)
        self.assertEqual(report["time_gates"]["count"], 40)
        peaks = []
        for detector in report["detectors"]:
            exitance = np.array(detector["tpsf"]["exitance_j_mm2_ns"]["R"])
            self.assertEqual(exitance.shape, (40,))
            self.assertTrue(np.all(exitance >= 0.0))
            self.assertGreater(exitance.max(), 0.0)
            self.assertAlmostEqual(0.05 * exitance.sum() / detector["exitance_w_mm2"]["R"], 1.0,
                                   places=9)
            peaks.append(int(np.argmax(exitance)))
        self.assertLessEqual(peaks[0], peaks[1])
        reader = vtkXMLUnstructuredGridReader()
        reader.SetFileName(prefix + ".vtu")
        reader.Update()
        fields = reader.GetOutput().GetFieldData()
        for name in ("DetectorExitanceTPSF0", "DetectorExitanceTPSFStandardError1",
                     "TimeGateCentres"):
            self.assertIsNotNone(fields.GetArray(name), name)

    def test_compare_tpsf(self):
        """`compare --time-gates --detector`: every solver's TPSF per
        detector in tpsf.csv and the JSON report's "tpsf" (the plot's data;
        the plot itself is TestPictures' test_7): the diffusion series equal
        what render reports for the same detector, and Monte Carlo's exitance
        agrees with fem's at fem's peak gate within 3 standard errors + 10 %
        (the TPSF-peak tolerance of TestMonteCarloSources, which compares
        exitance too). Two fibres 6 mm from the beam (nearer, the peak falls
        in the first 50 ps, where diffusion does not hold; measured there:
        Monte Carlo / fem 1.12 at 4 mm; 0.96 and 1.16, SE 6-7 %, at 6 mm)."""
        out = os.path.join(self.dir.name, "compare_tpsf")
        args = ["compare", "--mesh", self.mesh, "--solvers", "fem,divergence,montecarlo",
                "--photons", "100000", "--no-png", "--output", out,
                "--json", os.path.join(out, "report.json"),
                "--source", "pencil:0,0,5:0,0,-1", "--detector", "0,-6,5:2",
                "--detector", "-6,0,5:2", "--time-gates", "0,1,20"]
        result = subprocess.run([CLI] + args, capture_output=True, text=True, timeout=300)
        self.assertEqual(result.returncode, 0, result.stderr)
        with open(os.path.join(out, "report.json")) as f:
            report = json.load(f)
        table = np.genfromtxt(os.path.join(out, "tpsf.csv"), delimiter=",", names=True)
        self.assertEqual(len(table), 20)
        np.testing.assert_allclose(table["t_ns"], report["tpsf"]["gate_centres_ns"], rtol=1e-9)
        self.assertEqual([(s["solver"], s["detector"]) for s in report["tpsf"]["series"]],
                         [(solver, d) for solver in ("fem", "divergence", "montecarlo")
                          for d in (1, 2)])
        # The series are each solver's own detector TPSF (its "detectors" entry).
        for solver in report["solvers"]:
            for d, detector in enumerate(solver["detectors"]):
                for quantity in ("fluence", "exitance"):
                    for c in "RGB":
                        column = table["%s_d%d_%s_%s" % (solver["solver"], d + 1, quantity, c)]
                        np.testing.assert_allclose(
                            column, detector["tpsf"]["%s_j_mm2_ns" % quantity][c], rtol=1e-9)
        for d in (1, 2):
            fem = table["fem_d%d_exitance_R" % d]
            peak = int(np.argmax(fem))
            mc = table["montecarlo_d%d_exitance_R" % d][peak]
            se = table["montecarlo_d%d_exitance_R_se" % d][peak]
            self.assertGreater(se, 0.0)
            self.assertLess(abs(mc - fem[peak]), 3 * se + 0.10 * fem[peak],
                            "detector %d: montecarlo %g +- %g vs fem %g at gate %d"
                            % (d, mc, se, fem[peak], peak))
            print("detector %d peak gate %d: montecarlo / fem = %.3f (SE %.3f)"
                  % (d, peak, mc / fem[peak], se / fem[peak]))
        self.assertFalse(os.path.exists(os.path.join(out, "error_vs_time.png")))

    def compare(self, out, extra):
        args = ["compare", "--mesh", self.mesh, "--solvers", "divergence",
                "--reference", "divergence", "--no-png", "--output", out,
                "--json", os.path.join(out, "report.json"), "--material", self.material,
                "--source", "pencil:0,0,5:0,0,-1", "--detector", "0,-6,5",
                "--detector", "-6,0,5:1.5", "--time-gates", "0,1,10"] + extra
        return subprocess.run([CLI] + args, capture_output=True, text=True, timeout=300)

    @property
    def material(self):
        path = os.path.join(self.dir.name, "tissue.json")
        with open(path, "w") as f:
            json.dump({"absorption": [0.01, 0.02, 0.05], "reduced_scattering": [1.0, 1.2, 0.8],
                       "refractive_index": 1.4}, f)
        return path

    def test_compare_measured_and_closed_form(self):
        """`compare --measured FILE`: the measured columns (ps in the file)
        interpolated to the gate centres and scaled to the reference's
        exitance area over the gates they cover (1e-9); the closed form
        (Patterson et al. 1989, semi-infinite, extrapolated boundary) equals an
        independent implementation here at the point detector (gate averages
        by a 4001-point trapezoid rule: 1e-5) and is drawn for both
        detectors; on a heterogeneous material it is skipped with the
        reason printed."""
        out = os.path.join(self.dir.name, "compare_measured")
        os.makedirs(out, exist_ok=True)
        measured = os.path.join(out, "measured.csv")
        times_ps = np.array([60.0, 120.0, 250.0, 400.0, 700.0, 1200.0])
        counts = np.array([[10.0, 2.0], [900.0, 300.0], [700.0, 650.0], [420.0, 500.0],
                           [130.0, 190.0], [20.0, 35.0]])
        with open(measured, "w") as f:
            f.write("# two fibres, counts per 10 ps bin\nt_ps, fibre A, fibre B\n")
            for t, (a, b) in zip(times_ps, counts):
                f.write("%g, %g, %g\n" % (t, a, b))
        result = self.compare(out, ["--measured", measured])
        self.assertEqual(result.returncode, 0, result.stderr)
        self.assertNotIn("closed form not drawn", result.stdout)
        with open(os.path.join(out, "report.json")) as f:
            report = json.load(f)
        table = np.genfromtxt(os.path.join(out, "tpsf.csv"), delimiter=",", names=True)
        centres = table["t_ns"]
        m = report["tpsf"]["measured"]
        self.assertEqual((m["normalise"], m["time_unit_in_file"], m["reference_solver"]),
                         ("area", "ps", "divergence"))
        for d in (1, 2):
            inside = (centres >= 0.06) & (centres <= 1.2)
            expected = np.interp(centres, times_ps / 1000.0, counts[:, d - 1])
            reference = table["divergence_d%d_exitance_R" % d]
            scale = reference[inside].sum() / expected[inside].sum()
            column = table["measured_d%d" % d]
            np.testing.assert_allclose(column[inside], scale * expected[inside], rtol=1e-9)
            self.assertTrue(np.all(np.isnan(column[~inside])))
            self.assertEqual(np.isnan(column).sum(), 1)  # the first gate, 50 ps < 60 ps
            self.assertAlmostEqual(m["series"][d - 1]["scale"] / scale, 1.0, places=9)
            self.assertEqual(m["series"][d - 1]["column"], ["fibre A", "fibre B"][d - 1])
        # The closed form at the point detector, computed here from the formula.
        c = report["tpsf"]["closed_form"]
        self.assertTrue(c["computed"], c)
        self.assertEqual(c["assumption"], "semi-infinite, homogeneous")
        detector = report["solvers"][0]["detectors"][0]["surface_position_mm"]
        rho = np.hypot(detector[0], detector[1])
        eta, speed = 1.4, 299.792458 / 1.4
        fdr = -1.440 / eta**2 + 0.710 / eta + 0.668 + 0.0636 * eta
        a = (1 + fdr) / (1 - fdr)
        transmitted = 1.0 - ((eta - 1) / (eta + 1)) ** 2
        for k, (mua, mus) in enumerate(((0.01, 1.0), (0.02, 1.2), (0.05, 0.8))):
            d = 1.0 / (3.0 * (mua + mus))
            z0, zb = 1.0 / (mua + mus), 2.0 * a * d
            z2 = z0 + 2.0 * zb

            def reflectance(t):
                return (0.5 * (4 * np.pi * d * speed) ** -1.5 * t ** -2.5
                        * np.exp(-mua * speed * t)
                        * (z0 * np.exp(-(rho**2 + z0**2) / (4 * d * speed * t))
                           + z2 * np.exp(-(rho**2 + z2**2) / (4 * d * speed * t))))
            for g in (1, 3, 6, 9):
                t = np.linspace(0.1 * g, 0.1 * (g + 1), 4001)
                expected = transmitted * np.trapz(reflectance(t), t) / 0.1
                got = table["closedform_d1_exitance_%s" % "RGB"[k]][g]
                self.assertAlmostEqual(got / expected, 1.0, delta=1e-5, msg=(k, g))
        self.assertEqual(len(table["closedform_d2_exitance_R"]), 10)  # the fibre too
        # A heterogeneous material: skipped, the reason printed; no columns.
        reader = vtkXMLUnstructuredGridReader()
        reader.SetFileName(self.mesh)
        reader.Update()
        grid = reader.GetOutput()
        absorption = grid.GetCellData().GetArray("AbsorptionCoefficient")
        absorption.SetComponent(0, 0, 2.0 * absorption.GetComponent(0, 0))
        from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridWriter
        writer = vtkXMLUnstructuredGridWriter()
        mixed = os.path.join(self.dir.name, "mixed.vtu")
        writer.SetFileName(mixed)
        writer.SetInputData(grid)
        writer.Write()
        args = ["compare", "--mesh", mixed, "--solvers", "divergence", "--reference",
                "divergence", "--no-png", "--output", os.path.join(self.dir.name, "mixed"),
                "--source", "pencil:0,0,5:0,0,-1", "--detector", "0,-6,5",
                "--time-gates", "0,1,4"]
        result = subprocess.run([CLI] + args, capture_output=True, text=True, timeout=300)
        self.assertEqual(result.returncode, 0, result.stderr)
        self.assertIn("closed form not drawn: the material is heterogeneous "
                      "(AbsorptionCoefficient R from", result.stdout)
        with open(os.path.join(self.dir.name, "mixed", "tpsf.csv")) as f:
            self.assertNotIn("closedform", f.readline())

    def test_compare_measured_bad_files(self):
        """A malformed --measured file: an error naming the file, the line and
        the column or the count, before any solving; the output folder's
        existing files are left alone."""
        out = os.path.join(self.dir.name, "compare_bad")
        os.makedirs(out, exist_ok=True)
        with open(os.path.join(out, "tpsf.csv"), "w") as f:
            f.write("precious")
        cases = [
            ("t_ns,a,b\n0,1,2\n0.1,x2,3\n",
             "line 3, column 2 (a): 'x2' is not a finite number"),
            ("t_ns,a,b\n0,1,2\n0.1,nan,3\n", "line 3, column 2 (a): 'nan' is not a finite"),
            ("t_ns,a\n0,1\n0.1,2\n", "1 detector column(s) after the time column, but 2"),
            ("t_ns,a,b\n0,1,2\n0.2,2,3\n0.1,3,4\n",
             "line 4: time 0.1 ns is not after 0.2 ns on line 3; times must increase"),
            ("time,a,b\n0,1,2\n", "line 1: the first column's header 'time' names no time unit"),
            ("t_ps,a,b\n0,1,2\n10,1\n", "line 3: 2 cells, the header has 3"),
            ("t_ps,a,b\n0,1,2\n", "1 data row(s); a curve needs at least 2"),
            ("t_ns,a,b\n5,1,2\n6,1,2\n", "no gate centre lies within its times"),
            ("t_ns,a,b\n0,0,1\n1,0,2\n", "detector 1's column 'a' has no positive area"),
        ]
        for text, message in cases:
            path = os.path.join(self.dir.name, "bad.csv")
            with open(path, "w") as f:
                f.write(text)
            result = self.compare(out, ["--measured", path])
            self.assertNotEqual(result.returncode, 0, text)
            self.assertIn("--measured " + path, result.stderr, text)
            self.assertIn(message, result.stderr, text)
            with open(os.path.join(out, "tpsf.csv")) as f:
                self.assertEqual(f.read(), "precious", text)
        result = self.compare(out, ["--measured", os.path.join(self.dir.name, "missing.csv")])
        self.assertNotEqual(result.returncode, 0)
        self.assertIn("missing.csv: cannot open the file (No such file or directory)",
                      result.stderr)
        result = self.compare(out, ["--measured", path, "--measured-normalise", "median"])
        self.assertNotEqual(result.returncode, 0)
        self.assertIn("--measured-normalise", result.stderr)

    def test_bad_input(self):
        prefix = os.path.join(self.dir.name, "keep")
        with open(prefix + ".json", "w") as f:
            f.write("precious")
        cases = [
            (["--time-gates", "2,1,10"], "--time-gates 2,1,10: T1 = 1 ns is not after T0 = 2 ns"),
            (["--time-gates", "1,1,10"], "--time-gates 1,1,10: T1 = 1 ns is not after T0 = 1 ns"),
            (["--time-gates", "0,1,0"], "--time-gates 0,1,0: N = 0 gates (expected N >= 1)"),
            (["--time-gates", "0,1,-3"], "--time-gates 0,1,-3: N = -3 gates"),
            (["--time-gates", "0,1,2.5"], "--time-gates 0,1,2.5: N = 2.5 is not a whole number"),
            (["--time-gates", "0,1,20000"], "N = 20000 gates is more than the limit of 10000"),
            (["--time-gates", "0,1,1e12"], "N = 1e12 gates is more than the limit of 10000"),
            (["--time-gates", "-1,1,10"], "--time-gates -1,1,10: T0 = -1 ns is negative"),
            (["--time-gates", "nan,1,10"], "'nan' in --time-gates nan,1,10 is not a number"),
            (["--time-gates", "0,inf,10"], "'inf' in --time-gates 0,inf,10 is not a finite"),
            (["--time-gates", "0,1"], "--time-gates 0,1: expected T0,T1,N"),
            (["--time-gates", "1000,1001,100"], "the limit is 100000"),
            (["--time-gates", "0,1,10", "--frequency", "1e8"], "--frequency excludes --time-gates"),
            (["--time-gates", "0,1,4", "--time-snapshots", "4"],
             "--time-snapshots: gate 4 (expected 0..3 for --time-gates 0,1,4"),
            (["--time-gates", "0,1,4", "--time-snapshots", "-1"], "--time-snapshots -1: a gate is"),
            (["--steps-per-gate", "3"], "--steps-per-gate requires --time-gates"),
            (["--time-gates", "0,1,4", "--steps-per-gate", "1001"], "--steps-per-gate must be"),
            (["--time-gates", "0,1,4", "--solver", "quadgraph"],
             "no interior sources, frequency domain or time gates"),
            (["--time-gates", "0,1,4", "--time-snapshots", "1", "--solver", "montecarlo"],
             "no fluence snapshots per gate"),
        ]
        for extra, message in cases:
            result = self.run_cli(["--mesh", self.mesh, "--source", "point:0,0,0",
                                   "--json", prefix + ".json"] + extra)
            self.assertNotEqual(result.returncode, 0, extra)
            self.assertIn(message, result.stderr, extra)
            with open(prefix + ".json") as f:
                self.assertEqual(f.read(), "precious", extra)

    def test_panel_property_counts_gates_as_whole_numbers(self):
        """The ParaView property passes N as a double (SetTimeGatesFromPanel):
        a whole number runs that many gates, anything else fails naming it."""
        import translucency
        reader = vtkXMLUnstructuredGridReader()
        reader.SetFileName(self.mesh)
        reader.Update()
        light = translucency.vtkSurfaceIrradiance()
        light.SetInputData(reader.GetOutput())
        solve = translucency.vtkSolveDiffusion()
        solve.SetInputConnection(light.GetOutputPort())
        solve.SetTimeGatesFromPanel(0.0, 2.0, 8.0)
        output = translucency.update(solve)
        centres = vtk_to_numpy(output.GetFieldData().GetArray("TimeGateCentres"))
        np.testing.assert_allclose(centres.ravel(), 0.125 + 0.25 * np.arange(8), rtol=1e-12)
        solve.SetTimeGatesFromPanel(0.0, 2.0, 2.5)
        with self.assertRaises(translucency.PipelineError) as caught:
            translucency.update(solve)
        self.assertIn("whole number, got 2.5", str(caught.exception))
        solve.SetTimeGatesFromPanel(0.0, 0.0, 0.0)  # back to continuous wave
        self.assertIsNone(translucency.update(solve).GetFieldData().GetArray("TimeGateCentres"))


if __name__ == "__main__":
    unittest.main()
