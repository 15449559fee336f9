#!/usr/bin/env python3
"""`translucency compare --time-gates ... --measured FILE`: a measured TPSF
and the closed form on the TPSF plot's data (Apps/CompareMeasured,
Apps/CompareClosedForm, Documentation/DiffuseOptics.md, "Measured curves and
the closed form on the TPSF plot").

How to run (from a build tree; ctest sets the variables itself):

    TRANSLUCENCY_CLI=<build>/bin/translucency \\
    PYTHONPATH=<build>/lib/python3.11/site-packages /usr/bin/python3 TestCompareMeasured.py

1. On the 20 x 20 x 10 mm box (3k tets; a pencil beam at the top centre, a point
   detector and a 1.5 mm fibre 6 mm off the axis, 10 gates of 100 ps): the
   measured columns (ps in the file, 6 times that are not the gates)
   interpolated to the gate centres and scaled to the reference's exitance
   area over the gates they cover (1e-9), nan before the first time; the
   closed form (Patterson et al. 1989, semi-infinite, extrapolated
   boundary) at the point detector against an independent implementation
   (gate averages by a 4001-point trapezoid rule: 1e-5, every channel, 4
   gates), drawn for the fibre too; on a material with one tet changed it
   is skipped with the reason printed and no columns.
2. Malformed files (a non-numeric or non-finite cell, the column count,
   times not increasing, no time unit, a short row, one row, no overlap
   with the gates, no positive area), a missing file and an unknown
   normalisation: each exits non-zero with a message naming the file and
   the place, before any solving, and the output folder's tpsf.csv is left
   alone.

Exits non-zero on failure (unittest).
"""

import json
import os
import subprocess
import unittest

import numpy as np

from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader, vtkXMLUnstructuredGridWriter

from cli_under_test import BoxRenderTest, find_cli  # noqa: E402

CLI = find_cli("TestCompareMeasured")


class CompareMeasured(BoxRenderTest):
    CLI = CLI
    BOX_TETS = 3000  # the checks are exact or independent of the mesh: keep it small

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



if __name__ == "__main__":
    unittest.main()
