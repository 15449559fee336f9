#!/usr/bin/env python3
"""Smoke test of `translucency bench --pipeline` on a small sphere.

How to run (from a build tree; ctest sets the variables itself):

    TRANSLUCENCY_CLI=<build>/bin/translucency PYTHONPATH=<build>/lib/python3.11/site-packages \\
    /usr/bin/python3 TestBenchPipeline.py

The bench times the ParaView chain (Assign -> Surface Irradiance -> Paint ->
Solve Diffusion -> Outgoing Radiance, read from a .vtu) filter by filter on a
sphere of radius 10 mm tetrahedralised to ~6000 tets, one run. Checked:
1. the table: one row per step (cold, relight, paint, cut) with the filters
   each step re-executes, positive times and SpMV units, the SpMV time;
2. the relit Irradiance (its unchanged lights from the filter's cache)
   equals a new filter's to 1e-12;
3. the relit and the painted fluence are within 1 % (boundary RMS) of a
   solve of the same input to RelTol 1e-10, and the stroke painted tets;
4. --pipeline with --edit is refused (exit status 2).

Exits non-zero on failure (unittest).
"""

import os
import subprocess
import sys
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_under_test import BenchJsonTest, find_cli  # noqa: E402

CLI = find_cli("TestBenchPipeline")

# The filters each step executes (the bench's columns).
STEP_FILTERS = {
    "cold": ("assign", "irradiance", "paint", "solve", "radiance"),
    "relight": ("irradiance", "paint", "solve", "radiance"),
    "paint": ("paint", "solve", "radiance"),
    "cut": ("cut", "solve", "radiance"),
}


class BenchPipeline(BenchJsonTest):
    CLI = CLI
    BENCH_ARGS = ["--pipeline", "--tets", "6000", "--runs", "1"]
    TIMEOUT = 400

    def test_table(self):
        s = self.size
        self.assertGreater(s["tets"], 2000)
        self.assertGreater(s["spmv_1ch_ms_median"], 0.0)
        for step, filters in STEP_FILTERS.items():
            row = s[step]
            keys = sorted(k[:-len("_ms_median")] for k in row if k.endswith("_ms_median"))
            self.assertEqual(keys, sorted(filters), step)
            total = sum(row[f + "_ms_median"] for f in filters)
            self.assertAlmostEqual(row["total_ms"], total, places=6)
            self.assertGreater(row["total_ms"], 0.0, step)
            self.assertAlmostEqual(row["total_spmv"], total / s["spmv_1ch_ms_median"], places=6)
            self.assertGreater(row["iterations_3ch_median"], 0, step)
        # The relight's solve split into its set-up and linear solve (the
        # rest is the filter's own work): parts of the filter's time.
        relight = s["relight"]
        self.assertGreaterEqual(relight["solve_setup_median_ms"], 0.0)
        self.assertGreater(relight["solve_linear_median_ms"], 0.0)
        self.assertLessEqual(relight["solve_setup_median_ms"] + relight["solve_linear_median_ms"],
                             relight["solve_ms_median"])
        # The printed table: a header and one line per step.
        lines = self.run_result.stdout.splitlines()
        for step in STEP_FILTERS:
            self.assertTrue(any(line.split()[:1] == [step] for line in lines), step)

    def test_relit_irradiance_equals_a_new_filter(self):
        self.assertLessEqual(self.size["accuracy"]["relight_irradiance_max_relative_difference"],
                             1e-12)

    def test_fluence_within_one_percent(self):
        a = self.size["accuracy"]
        self.assertGreaterEqual(a["relight_fluence_boundary_error"], 0.0)
        self.assertLessEqual(a["relight_fluence_boundary_error"], 0.01)
        self.assertGreaterEqual(a["paint_fluence_boundary_error"], 0.0)
        self.assertLessEqual(a["paint_fluence_boundary_error"], 0.01)
        self.assertGreater(a["tets_painted"], 0)

    def test_excludes_edit(self):
        r = subprocess.run([CLI, "bench", "--pipeline", "--edit", "--mesh", self.mesh],
                           capture_output=True, text=True, timeout=60)
        self.assertEqual(r.returncode, 2, r.stderr)


if __name__ == "__main__":
    unittest.main(verbosity=2)
