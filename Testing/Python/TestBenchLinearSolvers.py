#!/usr/bin/env python3
"""Smoke test of `translucency bench --linear-solvers` on a tiny bunny.

How to run (from a build tree; ctest sets the variables itself):

    TRANSLUCENCY_CLI=<build>/bin/translucency PYTHONPATH=<build>/lib/python3.11/site-packages \\
    /usr/bin/python3 TestBenchLinearSolvers.py

The bench runs every linear solver of the build on a small sphere (radius
10 mm, written here; the bunny's surface alone gives TetGen > 40k tets)
tetrahedralised to ~4000 tets (plus hypre-amg on 2 MPI ranks when the build has hypre) and
writes JSON and the error-vs-time CSV/PNG. Checked in the JSON:
1. the reference solution's true relative residual is <= 1e-10;
2. every solver (cold and warm) reached <= 1 % relative L2 error of the
   boundary fluence, and the tolerance chosen is the loosest of the ladder:
   one step looser gave > 1 % (when there is a looser step);
3. iterative solvers report iterations and SpMV-equivalents > 0, warm
   solves need no more SpMV-equivalents than cold ones;
4. the SpMV time, its bandwidth bound and the STREAM bandwidth are positive;
5. the cut -> new fluence figure's solution is within 1 % of its reference;
6. the CSV has a curve for each solver whose errors reach <= 1 %, and the
   PNG was written when matplotlib is available;
7. an unknown solver name exits with status 1 and lists the known names.

Exits non-zero on failure (unittest).
"""

import csv
import importlib.util
import json
import os
import shutil
import subprocess
import sys
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_under_test import BenchJsonTest, find_cli  # noqa: E402

CLI = find_cli("TestBenchLinearSolvers")


class BenchLinearSolvers(BenchJsonTest):
    CLI = CLI
    BENCH_ARGS = ["--linear-solvers", "--tets", "3000", "--runs", "1"]

    @classmethod
    def extra_args(cls):
        cls.png_path = os.path.join(cls.tmp.name, "curve.png")
        return ["--plot", cls.png_path]

    def test_reference_and_bandwidth(self):
        s = self.size
        self.assertLessEqual(s["reference_residual"], 1e-10)
        self.assertGreater(s["tets"], 1000)
        for key in ("spmv_1ch_ms", "spmv_bandwidth_bound_ms", "stream_triad_gbs", "assembly_3ch_ms"):
            self.assertGreater(s[key], 0.0, key)
        # Bytes per nonzero of the bound: at least the 12 of values and indices.
        self.assertGreaterEqual(s["spmv_bytes"], 12 * s["nonzeros"])

    def test_every_solver_reaches_one_percent(self):
        names = [r["solver"] for r in self.size["solvers"]]
        self.assertIn("cg-jacobi", names)
        self.assertIn("cg-ichol", names)
        for r in self.size["solvers"]:
            for kind in ("cold", "warm"):
                self.assertTrue(r[kind + "_reached_1pct"], (r["solver"], kind))
                self.assertLessEqual(r[kind + "_error"], 0.01, (r["solver"], kind))
                looser = r[kind + "_error_one_step_looser"]
                if looser >= 0 and not r["solver"].startswith("hypre-amg-"):
                    self.assertGreater(looser, 0.01, (r["solver"], kind))
            if max(r["cold_iterations"]) > 0:
                self.assertGreater(r["cold_spmv_equivalents"], 0.0, r["solver"])
                self.assertLessEqual(r["warm_spmv_equivalents"], r["cold_spmv_equivalents"],
                                     r["solver"])
            self.assertGreater(r["setup_with_topology_ms"], 0.0)

    def test_hypre_ranks_when_built(self):
        names = [r["solver"] for r in self.size["solvers"]]
        if "hypre-amg" in names and shutil.which("mpiexec"):
            self.assertIn("hypre-amg-2ranks", names, self.size.get("hypre_ranks_error"))

    def test_cut(self):
        cut = self.size["cut"]
        # The cut figure uses multigrid-agg (cheapest set-up + cold solve).
        self.assertEqual(cut["solver"], self.size["cut_solver"])
        self.assertEqual(cut["solver"], "multigrid-agg")
        self.assertLess(cut["tets_kept"], self.size["tets"])
        self.assertGreater(cut["tets_kept"], 0.2 * self.size["tets"])
        self.assertLessEqual(cut["reference_residual"], 1e-10)
        self.assertTrue(cut["reached_1pct"])
        self.assertLessEqual(cut["error"], 0.01)
        if cut["error_one_step_looser"] >= 0:
            self.assertGreater(cut["error_one_step_looser"], 0.01)

    def test_curve(self):
        csv_path = os.path.splitext(self.png_path)[0] + ".csv"
        rows = list(csv.DictReader(open(csv_path)))
        in_process = [r["solver"] for r in self.size["solvers"]
                      if not r["solver"].startswith("hypre-amg-")]
        for name in in_process:
            errors = [float(r["error"]) for r in rows if r["solver"] == name]
            self.assertTrue(errors, name)
            self.assertLessEqual(min(errors), 0.01, name)
        if importlib.util.find_spec("matplotlib"):
            self.assertTrue(os.path.getsize(self.png_path) > 1000)

    def test_unknown_solver(self):
        r = subprocess.run([CLI, "bench", "--linear-solvers", "no-such-solver", "--tets", "1000"],
                           capture_output=True, text=True, timeout=60)
        self.assertEqual(r.returncode, 1)
        self.assertIn("no-such-solver", r.stderr)
        self.assertIn("cg-jacobi", r.stderr)

    def test_named_solvers_as_a_comma_list(self):
        # The README's form: only the named solvers, in the given order.
        json_path = os.path.join(self.tmp.name, "named.json")
        r = subprocess.run([CLI, "bench", "--linear-solvers", "multigrid-agg,cg-jacobi",
                            "--mesh", self.mesh, "--tets", "3000", "--runs", "1", "--no-cut",
                            "--json", json_path],
                           capture_output=True, text=True, timeout=300)
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(json_path) as f:
            sizes = json.load(f)
        self.assertEqual([row["solver"] for row in sizes[0]["solvers"]],
                         ["multigrid-agg", "cg-jacobi"])


if __name__ == "__main__":
    unittest.main()
