#!/usr/bin/env python3
"""Smoke test of `translucency bench --diffuse-optics` on a small sphere.

How to run (from a build tree; ctest sets the variables itself):

    TRANSLUCENCY_CLI=<build>/bin/translucency PYTHONPATH=<build>/lib/python3.11/site-packages \\
    /usr/bin/python3 TestBenchDiffuseOptics.py

The bench runs on a sphere of radius 10 mm (written here) tetrahedralised to
~3000 tets, one run, 10 time gates. Checked in the JSON:
1. every solve converged and reports positive times;
2. the frequency-domain solves used COCG with Jacobi and with the multigrid
   of the real part, and the multigrid one needed fewer than half the
   iterations of Jacobi in every channel;
3. the ratios to the CW solve are the medians' quotients;
4. the time-gate table ran both step solvers (cg-jacobi, multigrid-agg);
5. an option of the bench without --diffuse-optics is a usage error;
6. the multigrid step solver ran with and without the recycled step
   solutions (session 21): both converged, and the recycled run needed fewer
   iterations in all.

Exits non-zero on failure (unittest).
"""

import os
import subprocess
import sys
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_under_test import BenchJsonTest, find_cli  # noqa: E402

CLI = find_cli("TestBenchDiffuseOptics")


class BenchDiffuseOptics(BenchJsonTest):
    CLI = CLI
    BENCH_ARGS = ["--diffuse-optics", "--tets", "3000", "--gate-tets", "3000", "--gates", "10",
                  "--runs", "1"]

    def test_frequency_domain(self):
        tables = self.results["frequency_domain"]
        self.assertEqual(len(tables), 1)
        t = tables[0]
        self.assertGreater(t["tets"], 1000)
        self.assertEqual(t["fd_jacobi"]["linear_solver"], "cocg-jacobi")
        self.assertEqual(t["fd_multigrid"]["linear_solver"], "cocg-multigrid-agg")
        for key in ("cw", "fd_jacobi", "fd_multigrid"):
            self.assertTrue(t[key]["converged"], key)
            self.assertGreater(t[key]["solve_ms_median"], 0.0, key)
            self.assertGreater(t[key]["total_ms_median"], t[key]["solve_ms_median"], key)
            self.assertAlmostEqual(t[key]["solve_over_cw_solve"],
                                   t[key]["solve_ms_median"] / t["cw"]["solve_ms_median"],
                                   places=9)
        for c in range(3):
            self.assertLess(2 * t["fd_multigrid"]["iterations"][c],
                            t["fd_jacobi"]["iterations"][c], c)

    def test_time_gates(self):
        g = self.results["time_gates"]
        self.assertEqual(g["gates"], 10)
        self.assertGreaterEqual(g["steps"], 40)
        self.assertEqual(g["cg_jacobi"]["linear_solver"], "cg-jacobi")
        self.assertEqual(g["multigrid_agg"]["linear_solver"], "multigrid-agg")
        for key in ("cg_jacobi", "multigrid_agg"):
            self.assertTrue(g[key]["converged"], key)
            self.assertGreater(g[key]["solve_ms_median"], 0.0, key)
            self.assertGreater(min(g[key]["iterations"]), 0, key)

    def test_recycled_step_solutions(self):
        g = self.results["time_gates"]
        before = g["multigrid_agg_extrapolated"]
        self.assertEqual(before["linear_solver"], "multigrid-agg")
        self.assertTrue(before["converged"])
        self.assertAlmostEqual(before["solve_over_cw_solve"], 1.0, places=12)
        self.assertLess(sum(g["multigrid_agg"]["iterations"]), sum(before["iterations"]))
        r = subprocess.run([CLI, "bench", "--steps-per-gate", "2", "--mesh", self.mesh],
                           capture_output=True, text=True, timeout=60)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("--diffuse-optics", r.stderr + r.stdout)

    def test_options_need_the_flag(self):
        r = subprocess.run([CLI, "bench", "--gates", "5", "--mesh", self.mesh],
                           capture_output=True, text=True, timeout=60)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("--diffuse-optics", r.stderr + r.stdout)


if __name__ == "__main__":
    unittest.main()
