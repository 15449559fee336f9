#!/usr/bin/env python3
"""The extended collimated-source models with --frequency and --time-gates
through the command line (`translucency render --collimated extended|
extended-moments`; Documentation/DiffuseOptics.md, "Collimated beams in
the frequency and time domain").

How to run (from a build tree; ctest sets the variables itself):

    TRANSLUCENCY_CLI=<build>/bin/translucency \\
    PYTHONPATH=<build>/lib/python3.11/site-packages /usr/bin/python3 TestCollimatedTimeFrequencyCLI.py

The 20 x 20 x 10 mm box under the default lights (a directional key light,
now the unscattered beam and its volume source, and the uniform fill light,
still q), two detectors, the divergence solver at rel-tol 1e-10:

1. --time-gates 0,4,100 with extended-moments: the detectors' time
   integrals equal the continuous-wave readings (the power identity: 1e-6,
   the response has died out by 4 ns, as TestTimeResolvedCLI), the power
   report of the gated run closes (its Fluence is the time integral
   phi_d + E_c: |imbalance| < 1e-5), CollimatedFluence is the CW E_c (the
   beam arrives within the first gate).
2. --frequency with extended: at 1 Hz the detector readings are the
   continuous-wave ones (1e-6) with phase ~ 0; at 200 MHz the amplitudes are
   below them and the phases negative, CollimatedFluence is the CW E_c and
   CollimatedFluencePhase = -omega eta s / c lies in [-omega eta d / c, 0]
   (d the box diagonal) with its most negative value below -0.01 rad, and
   FluenceAmplitude <= Fluence = |Phi_d| + E_c (the triangle inequality).

Exits non-zero on failure (unittest).
"""

import json
import math
import os
import unittest

import numpy as np

from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader


from cli_under_test import BoxRenderTest, find_cli  # noqa: E402

CLI = find_cli("TestCollimatedTimeFrequencyCLI")

DETECTORS = ["--detector", "0,0,5", "--detector", "8,0,5:1.5"]


class CollimatedTimeFrequencyCLI(BoxRenderTest):
    CLI = CLI
    BOX_TETS = 6000

    def render(self, extra, name):
        prefix = os.path.join(self.dir.name, name)
        self.run_ok(["--mesh", self.mesh, "--solver", "divergence", "--rel-tol", "1e-10",
                     "--max-iter", "20000", "--output", prefix, "--json", prefix + ".json"]
                    + DETECTORS + extra)
        with open(prefix + ".json") as f:
            report = json.load(f)
        reader = vtkXMLUnstructuredGridReader()
        reader.SetFileName(prefix + ".vtu")
        reader.Update()
        self.cells = reader.GetOutput().GetCellData()
        return report, reader.GetOutput().GetPointData()

    def test_time_gates(self):
        model = ["--collimated", "extended-moments"]
        cw, cw_points = self.render(model, "cw")
        tr, tr_points = self.render(model + ["--time-gates", "0,4,100"], "tr")
        for k, detector in enumerate(tr["detectors"]):
            for c in "RGB":
                for key in ("fluence_w_mm2", "exitance_w_mm2"):
                    self.assertAlmostEqual(detector[key][c] / cw["detectors"][k][key][c], 1.0,
                                           places=6, msg="%s detector %d %s" % (key, k, c))
                tpsf = np.array(detector["tpsf"]["fluence_j_mm2_ns"][c])
                self.assertAlmostEqual(0.04 * tpsf.sum() / detector["fluence_w_mm2"][c], 1.0,
                                       places=9)
        for c in "RGB":
            self.assertLess(abs(tr["power_W"][c]["imbalance"]), 1e-5, c)
        beam = vtk_to_numpy(tr_points.GetArray("CollimatedFluence"))
        cw_beam = vtk_to_numpy(cw_points.GetArray("CollimatedFluence"))
        self.assertGreater(cw_beam.max(), 0.1)
        np.testing.assert_allclose(beam, cw_beam, rtol=1e-12, atol=0.0)
        fluence = vtk_to_numpy(tr_points.GetArray("Fluence"))
        np.testing.assert_allclose(fluence, vtk_to_numpy(cw_points.GetArray("Fluence")),
                                   rtol=0.0, atol=1e-6 * fluence.max())

    def test_frequency(self):
        model = ["--collimated", "extended"]
        cw, cw_points = self.render(model, "cw_fd")
        low, _ = self.render(model + ["--frequency", "1"], "low")
        fd, points = self.render(model + ["--frequency", "200e6"], "fd")
        for k in range(2):
            for c in "RGB":
                reference = cw["detectors"][k]["fluence_w_mm2"][c]
                self.assertAlmostEqual(low["detectors"][k]["fluence_w_mm2"][c] / reference, 1.0,
                                       places=6)
                self.assertLess(abs(low["detectors"][k]["fluence_phase_rad"][c]), 1e-6)
                self.assertLess(fd["detectors"][k]["fluence_w_mm2"][c], reference)
                self.assertLess(fd["detectors"][k]["fluence_phase_rad"][c], 0.0)
        beam = vtk_to_numpy(points.GetArray("CollimatedFluence"))
        np.testing.assert_allclose(beam, vtk_to_numpy(cw_points.GetArray("CollimatedFluence")),
                                   rtol=1e-12, atol=0.0)
        phase = vtk_to_numpy(points.GetArray("CollimatedFluencePhase"))
        eta = vtk_to_numpy(self.cells.GetArray("RefractiveIndex")).max()
        omega_over_c = 2.0 * math.pi * 200e6 / 299792458e3  # rad/mm
        diagonal = math.sqrt(20 ** 2 + 20 ** 2 + 10 ** 2)
        lit = beam > 0.0
        self.assertTrue(np.all(phase <= 0.0))
        self.assertLess(phase[lit].min(), -0.01)
        self.assertGreaterEqual(phase.min(), -omega_over_c * eta * diagonal)
        amplitude = vtk_to_numpy(points.GetArray("FluenceAmplitude"))
        fluence = vtk_to_numpy(points.GetArray("Fluence"))
        self.assertTrue(np.all(amplitude <= fluence * (1.0 + 1e-12)))


if __name__ == "__main__":
    unittest.main()
