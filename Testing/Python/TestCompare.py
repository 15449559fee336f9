#!/usr/bin/env python3
"""Tests of `translucency compare` (Apps/CompareCommand.cxx).

How to run (ctest sets the variables itself):

    TRANSLUCENCY_CLI=<build>/bin/translucency \\
    PYTHONPATH=<build>/lib/python3.11/site-packages /usr/bin/python3 TestCompare.py

1. With mu_a = 0 and an unoccluded uniform light every diffusion solver has the
   exact solution phi = 4 q / (1 - Fdr) everywhere, so every solver's error
   against the reference must be ~0: the comparison machinery (mapping,
   errors, table) is checked against an identity, not against our own numbers.
2. Under a directional light the JSON table is complete (unknowns, nonzeros,
   memory, times, iterations, errors), the reference's own error is exactly 0,
   and the .vtm holds each solver's fluence identical to its surface block.
3. Bad input: an unknown solver (the message lists the known ones), a grid
   spacing <= 0, photons <= 0, no --output — each exits non-zero naming it.

--no-png keeps the test free of an X display.
"""

import json
import os
import subprocess
import sys
import tempfile
import unittest

import numpy as np

from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOXML import vtkXMLMultiBlockDataReader

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_under_test import find_cli, write_sphere  # noqa: E402

CLI = find_cli("TestCompare")


def run(*args):
    return subprocess.run([CLI, *args], capture_output=True, text=True, timeout=600)


class CompareTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.mesh = os.path.join(cls.tmp.name, "sphere.vtp")
        write_sphere(cls.mesh, 5.0, 16, clean=True)
        cls.material = os.path.join(cls.tmp.name, "nonabsorbing.json")
        with open(cls.material, "w") as f:
            json.dump({"absorption": [0, 0, 0], "reduced_scattering": [1.0, 2.0, 3.0],
                       "refractive_index": 1.4}, f)

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def compare(self, name, *extra):
        out = os.path.join(self.tmp.name, name)
        stats = os.path.join(self.tmp.name, name + ".json")
        result = run("compare", "--mesh", self.mesh, "--target-tets", "3000", "--output", out,
                     "--json", stats, "--no-png", *extra)
        self.assertEqual(result.returncode, 0, result.stderr)
        with open(stats) as f:
            return out, json.load(f), result.stdout

    def test_identity_uniform_light(self):
        _, stats, stdout = self.compare(
            "uniform", "--material", self.material, "--light", "uniform:0.5",
            "--uniform-samples", "0", "--solvers", "divergence,fem", "--reference", "fem")
        self.assertEqual([s["solver"] for s in stats["solvers"]], ["fem", "divergence"])
        for s in stats["solvers"]:
            for kind in ("fluence_relative_error", "radiance_relative_error"):
                self.assertLess(s[kind]["max"], 1e-6, (s["solver"], kind, s[kind]))
        self.assertIn("divergence", stdout)

    def test_table_and_multiblock(self):
        # The surface model: Outgoing Radiance's Fluence is then the volume's
        # (an extended model's is the diffuse part, without the unscattered beam).
        out, stats, _ = self.compare("directional", "--light", "directional:0,-1,-1:1",
                                     "--collimated", "surface",
                                     "--solvers", "divergence,fem", "--reference", "fem")
        self.assertEqual(stats["reference"], "fem")
        rows = {s["solver"]: s for s in stats["solvers"]}
        self.assertEqual(set(rows), {"divergence", "fem"})
        for s in rows.values():
            for key in ("unknowns", "nonzeros", "memory_bytes", "setup_ms", "solve_ms",
                        "wall_ms", "iterations", "relative_residual", "linear_solver"):
                self.assertIn(key, s)
            self.assertEqual(s["unknowns"], stats["points"])  # vertex unknowns
            self.assertGreater(s["nonzeros"], s["unknowns"])
            self.assertTrue(all(s["converged"]))
        self.assertEqual(rows["fem"]["fluence_relative_error"]["max"], 0.0)
        # Different discretisations differ, but not wildly on a smooth sphere.
        self.assertGreater(rows["divergence"]["fluence_relative_error"]["rms"], 0.0)
        self.assertLess(rows["divergence"]["fluence_relative_error"]["rms"], 0.2)

        reader = vtkXMLMultiBlockDataReader()
        reader.SetFileName(os.path.join(out, "compare.vtm"))
        reader.Update()
        blocks = reader.GetOutput()
        self.assertEqual(blocks.GetNumberOfBlocks(), 3)
        volume = blocks.GetBlock(0)
        names = [blocks.GetMetaData(i).Get(blocks.NAME()) for i in range(3)]
        self.assertEqual(names, ["volume", "fem", "divergence"])
        for i, name in ((1, "fem"), (2, "divergence")):
            surface = blocks.GetBlock(i)
            ids = vtk_to_numpy(surface.GetPointData().GetArray("vtkOriginalPointIds"))
            phi_volume = vtk_to_numpy(volume.GetPointData().GetArray("Fluence_" + name))
            phi_surface = vtk_to_numpy(surface.GetPointData().GetArray("Fluence"))
            np.testing.assert_array_equal(phi_volume[ids], phi_surface)

    def expect_failure(self, fragment, *args):
        result = run("compare", "--mesh", self.mesh, "--target-tets", "2000", *args)
        self.assertNotEqual(result.returncode, 0)
        self.assertIn(fragment, result.stderr)
        self.assertNotIn("Traceback", result.stderr)

    def test_bad_input(self):
        out = os.path.join(self.tmp.name, "bad")
        self.expect_failure("unknown solver 'nope'", "--solvers", "divergence,nope",
                            "--output", out)
        self.expect_failure("known solvers: divergence, fem", "--solvers", "nope",
                            "--output", out)
        self.expect_failure("--grid-spacing must be > 0", "--grid-spacing", "0", "--output", out)
        self.expect_failure("--photons must be >= 1", "--photons", "0", "--output", out)
        self.expect_failure("compare needs --output DIR")
        self.assertFalse(os.path.exists(out), "a failed run must not create outputs")


if __name__ == "__main__":
    unittest.main(verbosity=2)
