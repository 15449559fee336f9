#!/usr/bin/env python3
"""Diffuse optics through the command line: `translucency render` with
--source, --detector, --frequency and --light none (Apps/DiffuseOpticsOptions).

How to run (from a build tree; ctest sets the variables itself):

    TRANSLUCENCY_CLI=<build>/bin/translucency \\
    PYTHONPATH=<build>/lib/python3.11/site-packages /usr/bin/python3 TestDiffuseOpticsCLI.py

1. A pencil beam and a point source in a 20 x 20 x 10 mm box with two
   detectors: the JSON report lists the sources and the detectors (surface
   point, fluence, exitance per channel); with only --source options no light
   is added (the Irradiance array is zero); twice the power gives twice the
   readings (the diffusion equation is linear: to the solver tolerance).
2. --frequency (divergence solver): FluenceAmplitude and FluencePhase point arrays, detector
   phases in the JSON report, negative (lagging) and larger in magnitude at a
   farther detector; the amplitude is below the continuous-wave fluence.
3. --light none without sources: zero fluence.
3b. Detectors with quadgraph and grid: a point detector on a boundary vertex
   reads that vertex's Fluence.
3c. Sources with quadgraph (eq. 5, two-point flux) and grid: fem's injected
   power, readings linear in the power, near fem's (grid, two-point flux);
   `compare` with sources runs all four diffusion solvers.
4. Bad input (point source outside, pencil beam pointing out, detector off
   the surface, zero frequency, malformed specs, grid with --frequency, montecarlo with --frequency, --anisotropy)
   exits non-zero with a message naming the option or source, and leaves an
   existing output file alone.

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

CLI = find_cli("TestDiffuseOpticsCLI")


class DiffuseOpticsCLI(BoxRenderTest):
    CLI = CLI
    BOX_TETS = 20000

    def render(self, extra, name, solver="fem"):
        prefix = os.path.join(self.dir.name, name)
        self.run_ok(["--mesh", self.mesh, "--solver", solver, "--rel-tol", "1e-10",
                     "--max-iter", "20000", "--output", prefix, "--json", prefix + ".json"]
                    + extra)
        with open(prefix + ".json") as f:
            report = json.load(f)
        reader = vtkXMLUnstructuredGridReader()
        reader.SetFileName(prefix + ".vtu")
        reader.Update()
        return report, reader.GetOutput().GetPointData()

    def test_sources_and_detectors(self):
        sources = ["--source", "pencil:0,0,5:0,0,-1", "--source", "point:2,3,-1:0.5"]
        detectors = ["--detector", "5,0,5", "--detector", "0,-8,5:1.5"]
        report, points = self.render(sources + detectors, "cw")
        self.assertEqual([s["type"] for s in report["sources"]], ["pencil", "point"])
        self.assertEqual(len(report["detectors"]), 2)
        irradiance = vtk_to_numpy(points.GetArray("Irradiance"))
        self.assertEqual(np.abs(irradiance).max(), 0.0)  # no default light
        for detector in report["detectors"]:
            self.assertAlmostEqual(detector["surface_position_mm"][2], 5.0, places=9)
            for c in "RGB":
                self.assertGreater(detector["fluence_w_mm2"][c], 0.0)
                self.assertGreater(detector["exitance_w_mm2"][c], 0.0)
                # Exitance phi / (2 A) with A(1.3) = 2.6 (marble): below phi / 4.
                self.assertLess(detector["exitance_w_mm2"][c], detector["fluence_w_mm2"][c] / 4)
        near, far = report["detectors"]
        self.assertGreater(near["fluence_w_mm2"]["R"], far["fluence_w_mm2"]["R"])
        # Linear in the power.
        double, _ = self.render(["--source", "pencil:0,0,5:0,0,-1:2",
                                 "--source", "point:2,3,-1:1"] + detectors, "cw2")
        for one, two in zip(report["detectors"], double["detectors"]):
            for c in "RGB":
                self.assertAlmostEqual(two["fluence_w_mm2"][c] / one["fluence_w_mm2"][c], 2.0,
                                       places=6)

    def test_frequency_domain(self):
        extra = ["--source", "pencil:0,0,5:0,0,-1", "--detector", "3,0,5", "--detector", "8,0,5"]
        cw, cw_points = self.render(extra, "cw3", "divergence")
        fd, fd_points = self.render(extra + ["--frequency", "200e6"], "fd", "divergence")
        self.assertEqual(fd["frequency_hz"], 200e6)
        amplitude = vtk_to_numpy(fd_points.GetArray("FluenceAmplitude"))
        phase = vtk_to_numpy(fd_points.GetArray("FluencePhase"))
        fluence = vtk_to_numpy(cw_points.GetArray("Fluence"))
        self.assertEqual(amplitude.shape, fluence.shape)
        # |Phi(omega)| <= Phi(0) and arg Phi < 0 hold for the continuous
        # Green's function (the Fourier transform of a positive response) and
        # for the lumped-mass divergence discretisation here (measured: ratio
        # <= 0.9997, phase <= -0.0105 rad); the consistent-mass fem breaks
        # them where its fluence is tiny or slightly negative (not tested).
        self.assertGreater(fluence.min(), 0.0)
        self.assertTrue(np.all(amplitude <= fluence))
        self.assertTrue(np.all(phase < 0.0))
        near, far = fd["detectors"]
        for c in "RGB":
            self.assertLess(near["fluence_phase_rad"][c], 0.0)
            self.assertLess(far["fluence_phase_rad"][c], near["fluence_phase_rad"][c])
            self.assertLess(near["fluence_w_mm2"][c], cw["detectors"][0]["fluence_w_mm2"][c])

    def test_sp3_frequency_domain(self):
        # sp3 in the frequency domain through the filter: the detectors read
        # SP3's own complex exitance. At 1 kHz the amplitudes are the
        # continuous-wave readings (to the solver tolerance) and the phases
        # ~0; at 200 MHz the readings lag, the far detector more.
        extra = ["--source", "pencil:0,0,5:0,0,-1", "--detector", "3,0,5", "--detector", "8,0,5"]
        cw, _ = self.render(extra, "sp3cw", "sp3")
        low, _ = self.render(extra + ["--frequency", "1e3"], "sp3low", "sp3")
        fd, fd_points = self.render(extra + ["--frequency", "200e6"], "sp3fd", "sp3")
        self.assertIsNotNone(fd_points.GetArray("FluencePhase"))
        for k in range(2):
            for c in "RGB":
                for key in ("fluence_w_mm2", "exitance_w_mm2"):
                    self.assertAlmostEqual(low["detectors"][k][key][c] / cw["detectors"][k][key][c],
                                           1.0, delta=1e-6)
                self.assertLess(abs(low["detectors"][k]["exitance_phase_rad"][c]), 1e-5)
        near, far = fd["detectors"]
        for c in "RGB":
            self.assertLess(near["exitance_phase_rad"][c], 0.0)
            self.assertLess(far["exitance_phase_rad"][c], near["exitance_phase_rad"][c])
            self.assertLess(near["exitance_w_mm2"][c], cw["detectors"][0]["exitance_w_mm2"][c])

    def test_detectors_every_solver(self):
        # quadgraph and grid read their detectors from the vertex Fluence
        # they write (the P1 interpolant at the surface point): a point
        # detector placed on a boundary vertex reads that vertex's Fluence
        # (a second way to get the same number, to round-off).
        reader = vtkXMLUnstructuredGridReader()
        reader.SetFileName(self.mesh)
        reader.Update()
        points = vtk_to_numpy(reader.GetOutput().GetPoints().GetData())
        top = np.flatnonzero(np.isclose(points[:, 2], 5.0) & (np.abs(points[:, 0]) < 6)
                             & (np.abs(points[:, 1]) < 6))
        self.assertGreater(len(top), 0)
        vertex = int(top[0])
        spec = ",".join(repr(float(x)) for x in points[vertex])
        for solver in ("quadgraph", "grid"):
            report, solved = self.render(["--detector", spec, "--detector", "0,0,5:2"],
                                         "det_" + solver, solver)
            fluence = vtk_to_numpy(solved.GetArray("Fluence"))
            point, fibre = report["detectors"]
            for c, name in enumerate("RGB"):
                self.assertGreater(fluence[vertex, c], 0.0, solver)
                self.assertAlmostEqual(point["fluence_w_mm2"][name] / fluence[vertex, c], 1.0,
                                       places=9, msg=solver)
                self.assertGreater(point["exitance_w_mm2"][name], 0.0, solver)
                self.assertGreater(fibre["fluence_w_mm2"][name], 0.0, solver)

    def test_sources_every_solver(self):
        # quadgraph (eq. 5 and its two-point-flux variant) and grid take the
        # sources too (issue 19): the same injected power as fem, readings
        # linear in the power, and grid and the two-point flux near fem's
        # readings (measured on this graded mesh, R/G/B: grid +4..+6 % /
        # +8..+13 %, two-point flux +15..+22 % / +10..+19 % at the near / far
        # detector; eq. 5 -54..-59 % / -70..-73 %, not compared: it does not
        # conserve light on graded meshes, Documentation/Solvers.md).
        sources = ["--source", "pencil:0,0,5:0,0,-1", "--source", "point:2,3,-1:0.5"]
        doubled = ["--source", "pencil:0,0,5:0,0,-1:2", "--source", "point:2,3,-1:1"]
        detectors = ["--detector", "5,0,5", "--detector", "0,-8,5:1.5"]
        fem, _ = self.render(sources + detectors, "src_fem")
        cases = [("quadgraph", []), ("quadgraph", ["--two-point-flux"]), ("grid", [])]
        for solver, extra in cases:
            name = solver + "".join(extra)
            report, points = self.render(sources + detectors + extra, "src_" + name, solver)
            twice, _ = self.render(doubled + detectors + extra, "src2_" + name, solver)
            self.assertEqual(np.abs(vtk_to_numpy(points.GetArray("Irradiance"))).max(), 0.0)
            self.assertGreater(vtk_to_numpy(points.GetArray("Fluence")).max(), 0.0, name)
            for c in "RGB":
                self.assertAlmostEqual(report["power_W"][c]["injected"] /
                                       fem["power_W"][c]["injected"], 1.0, places=12, msg=name)
                near, far = report["detectors"]
                self.assertGreater(near["fluence_w_mm2"][c], far["fluence_w_mm2"][c], name)
                for one, two in zip(report["detectors"], twice["detectors"]):
                    self.assertAlmostEqual(two["fluence_w_mm2"][c] / one["fluence_w_mm2"][c], 2.0,
                                           places=6, msg=name)
                for ours, ref in zip(report["detectors"], fem["detectors"]):
                    if name == "quadgraph":
                        print("eq. 5 / fem, detector fluence, channel %s: %.3f"
                              % (c, ours["fluence_w_mm2"][c] / ref["fluence_w_mm2"][c]))
                if name != "quadgraph":
                    for ours, ref in zip(report["detectors"], fem["detectors"]):
                        ratio = ours["fluence_w_mm2"][c] / ref["fluence_w_mm2"][c]
                        print("%s / fem, detector fluence, channel %s: %.3f" % (name, c, ratio))
                        self.assertTrue(0.8 < ratio < 1.4, (name, c, ratio))

    def test_compare_with_sources(self):
        # `compare` runs every solver on the sources and reports each one's
        # detector readings (quadgraph and grid refused sources before).
        out = os.path.join(self.dir.name, "compare")
        result = subprocess.run(
            [self.CLI, "compare", "--mesh", self.mesh, "--solvers", "divergence,fem,quadgraph,grid",
             "--reference", "fem", "--source", "pencil:0,0,5:0,0,-1", "--detector", "5,0,5",
             "--no-png", "--output", out, "--json", out + ".json"],
            capture_output=True, text=True, timeout=600)
        self.assertEqual(result.returncode, 0, result.stderr)
        with open(out + ".json") as f:
            stats = json.load(f)
        rows = {s["solver"]: s for s in stats["solvers"]}
        self.assertEqual(sorted(rows), ["divergence", "fem", "grid", "quadgraph"])
        for name, row in rows.items():
            self.assertEqual([s["type"] for s in row["sources"]], ["pencil"], name)
            self.assertGreater(row["detectors"][0]["fluence_w_mm2"]["R"], 0.0, name)

    def test_light_none(self):
        _, points = self.render(["--light", "none"], "dark")
        self.assertEqual(np.abs(vtk_to_numpy(points.GetArray("Fluence"))).max(), 0.0)

    def test_bad_input(self):
        prefix = os.path.join(self.dir.name, "keep")
        with open(prefix + ".json", "w") as f:
            f.write("precious")
        cases = [
            (["--source", "point:0,0,50"], "point source 1: position (0, 0, 50) is outside"),
            (["--source", "pencil:0,0,5:0,0,1"], "does not point into the object"),
            (["--source", "pencil:0,0,7:0,0,-1"], "2 mm from the surface"),
            (["--source", "point:0,0,0", "--detector", "0,0,0"], "detector 1: (0, 0, 0) is off"),
            (["--source", "point:0,0,0", "--frequency", "0"], "--frequency must be > 0"),
            (["--source", "point:0,0,0", "--frequency", "-1e6"], "--frequency must be > 0"),
            (["--source", "point:1,2"], "--source point:1,2: the position needs three"),
            (["--source", "laser:0,0,0"], "unknown source type 'laser'"),
            (["--source", "point:0,0,0:-1"], "the power must be finite and >= 0"),
            (["--detector", "0,0,5:-1"], "fibre radius is one number >= 0"),
            (["--source", "point:0,0,0", "--solver", "montecarlo", "--frequency", "1e8"],
             "the montecarlo solver has no frequency domain"),
            (["--source", "point:0,0,0", "--solver", "grid", "--frequency", "1e8"],
             "the grid solver has no frequency domain"),
            (["--source", "point:0,0,50", "--solver", "quadgraph"],
             "point source 1: position (0, 0, 50) is outside"),
            (["--source", "pencil:0,0,5:0,0,1", "--solver", "grid"],
             "does not point into the object"),
            (["--source", "point:0,0,0", "--anisotropy", "0.8"],
             "--anisotropy 0.8 applies to --solver montecarlo and sp3 only"),
            (["--source", "point:0,0,0", "--solver", "montecarlo", "--anisotropy", "1"],
             "--anisotropy must be in (-1, 1)"),
            (["--light", "none", "--light", "uniform"], "--light none cannot be combined"),
        ]
        for extra, message in cases:
            result = self.run_cli(["--mesh", self.mesh, "--json", prefix + ".json"] + extra)
            self.assertNotEqual(result.returncode, 0, extra)
            self.assertIn(message, result.stderr, extra)
            with open(prefix + ".json") as f:
                self.assertEqual(f.read(), "precious", extra)


if __name__ == "__main__":
    unittest.main()
