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
