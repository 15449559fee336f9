#!/usr/bin/env python3
"""The distributed Solve Diffusion (hypre on every rank) gives the serial Fluence.

How to run (ctest does this, with 2 and with 3 ranks):

    /usr/bin/python3 TestDistributedSolve.py <Translucency plugin> <number of ranks>

1. `pvbatch DistributedPipeline.py ... prepare` (one process) writes a
   heterogeneous sphere mesh, its partitioned copies and the serial
   references (divergence and fem, two lights, RelTol 1e-13).
2. `mpiexec -n N pvbatch --symmetric DistributedPipeline.py ... run` solves
   the cases on distributed data (see that script).
3. Here: at every point of every rank's piece (each rank's copy of a shared
   point), matched to the reference by its global id (PointIds), Fluence
   differs from the serial Fluence by at most 1e-6 relative; every
   reference point is covered; the distributed cases took the distributed
   path and the gathered case the gathered one; iterations and residuals
   are the same on every rank; the relight kept the hierarchies (assembly
   "unchanged"; by counters on every rank: no numbering and no hierarchy
   set up since the cold solve's one numbering and one BoomerAMG set-up) and
   the warm start of the same system needed at most 2
   iterations (0 when it is within RelTol already); the pieces stay distributed; with 3 ranks on 2 pieces one
   rank has an empty piece; an invalid mu_a on rank 1 only gives rank 1's
   error on every rank, and the next solve works; no other error is logged
   and nothing hangs; with a point source (one empty piece at 3 ranks) and
   a pencil beam, Fluence and the readings of a point and a fibre detector
   equal the serial ones to 1e-6 (the readings the same on every rank); a
   point source outside the object is the same error on every rank;
   painted (issue 32: the Paint filter's default targets, then mu_a x 1000,
   after an unpainted solve, so the hierarchy is kept and the values change)
   Fluence equals the serial painted Fluence to 1e-6; a solve that cannot
   converge (MaxIter 1) is an error on every rank with an empty output;
   the Monte Carlo (continuous wave and time-gated, on 3 and 2 pieces) runs
   replicated, its photons split over the ranks, and gives the serial
   Fluence, standard errors and detector readings to round-off.
"""

import os
import sys

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mpi_harness import RANKS, MpiSuite, main, pieces_of, worst_relative  # noqa: E402

CASES = {"pvtu3": "ref_a_divergence", "relight": "ref_b_divergence",
         "pvtu2": "ref_a_divergence", "redist": "ref_a_divergence", "fem": "ref_a_fem",
         "gathered": "ref_a_divergence", "paint": "ref_paint",
         "paint_extreme": "ref_paint_extreme"}
# Interior sources and detectors: case -> (reference, pieces written).
SOURCE_CASES = {"src_point": "ref_point_divergence", "src_pencil": "ref_pencil_divergence",
                "src_aimed": "ref_aimed_divergence"}


# Two solves of one system to RelTol 1e-13 compared point by point at 1e-6
# relative: relative to the point's own value, but not below 1e-9 of the
# largest, so that the absolute tolerance never falls below 1e-15 of the
# largest value (a few units in the last place of it: round-off of any
# correct solve, below what the stopping rule can hold a point to). An
# extreme absorber (paint_extreme) has points at 1e-13 of the maximum whose
# two solves differ by 1.5e-16 of it; a difference of 1e-12 of the maximum
# anywhere still fails.
SOLVE_FLOOR = 1e-9


def by_id(piece):
    ids = vtk_to_numpy(piece.GetPointData().GetArray("PointIds"))
    return ids, vtk_to_numpy(piece.GetPointData().GetArray("Fluence"))


class DistributedSolveTest(MpiSuite):
    SCRIPT = "DistributedPipeline.py"
    TIME_LIMIT = {"prepare": 200, "run": 300}  # seconds: hang ceilings for a loaded machine

    @classmethod
    def parse(cls):
        cls.solves = {case: {rank: m.groups()[2:] for rank, m in per_rank.items()}
                      for case, per_rank in cls.rank_reports(
                          "solves", r"^solve (\S+) rank (\d+) path (\S+) assembly (\S+) "
                          r"iterations (\S+) residuals (\S+)$").items()}

    def test_0_runs(self):
        self.assertIsNotNone(self.result.returncode, self.result.stderr)
        self.assertEqual(self.result.returncode, 0, self.result.stdout + self.result.stderr)
        self.assertEqual(self.result.stdout.count("run done"), RANKS)
        # The one expected error (mu_a < 0 on rank 1), once per rank with the
        # same text; no other.
        self.assert_error_on_every_rank(
            "rank 1: AbsorptionCoefficient of tet 5, channel G is -1 1/mm", failures=RANKS)

    def reference(self, name):
        reader = vtkXMLUnstructuredGridReader()
        reader.SetFileName(os.path.join(self.work, name + ".vtu"))
        reader.Update()
        ids, values = by_id(reader.GetOutput())
        return dict(zip(ids.tolist(), values))

    def test_fluence_equals_serial(self):
        for case, ref_name in CASES.items():
            ref = self.reference(ref_name)
            pieces = pieces_of(os.path.join(self.work, case + ".pvtu"))
            # (the writer leaves out an empty rank's piece)
            self.assertEqual(len(pieces), 2 if case == "pvtu2" and RANKS == 3 else RANKS, case)
            seen, worst = set(), 0.0
            scale = max(np.abs(v).max() for v in ref.values())
            for piece in pieces:
                if piece.GetNumberOfPoints() == 0:
                    continue
                for i, v in zip(*by_id(piece)):
                    worst = max(worst, worst_relative(v, ref[int(i)], scale, SOLVE_FLOOR))
                    seen.add(int(i))
            self.assertEqual(seen, set(ref), "every point of case " + case)
            self.assertLessEqual(worst, 1e-6, "max relative Fluence difference, case " + case)
            nonempty = sum(1 for p in pieces if p.GetNumberOfCells() > 0)
            if case == "pvtu2" and RANKS == 3:
                self.assertEqual(nonempty, 2, "3 ranks on 2 pieces: one empty piece")
            else:
                self.assertGreater(nonempty, 1, "the pieces stay distributed, case " + case)

    def test_same_iterations_on_every_rank(self):
        for case in list(CASES) + ["warm", "after_error"]:
            per_rank = self.solves.get(case, {})
            self.assertEqual(sorted(per_rank), list(range(RANKS)), case)
            path, assembly, iterations, residuals = per_rank[0]
            if case == "gathered":
                self.assertEqual(path, "gathered")
                continue
            self.assertEqual(path, "distributed", case)
            for rank in range(1, RANKS):
                self.assertEqual(per_rank[rank], per_rank[0], "rank %d, case %s" % (rank, case))
            # The warm start of the same system may already be within RelTol:
            # no iteration (the three-channel PCG tests convergence before
            # the preconditioner, Parallel.md "The stopping rule"; hypre's
            # PCG iterated at least once).
            if case != "warm":
                self.assertTrue(all(int(k) > 0 for k in iterations.split(",")), case)
            self.assertTrue(all(float(r) <= 2e-13 for r in residuals.split(",")), case)

    def numbers_per_rank(self, stem, key):
        """{case: {rank: [numbers]}} from the lines "<key> <case> rank <r> <numbers>"
        of every rank's <stem>_<rank>.txt."""
        return {case: {rank: [float(v) for v in m.group(3).split()]
                       for rank, m in per_rank.items()}
                for case, per_rank in self.rank_reports(
                    stem, r"^%s (\S+) rank (\d+) (.*)$" % key).items()}

    def test_sources_and_detectors_equal_serial(self):
        import json
        for case, ref_name in SOURCE_CASES.items():
            ref = self.reference(ref_name)
            scale = max(np.abs(v).max() for v in ref.values())
            seen, worst, nonempty = set(), 0.0, 0
            for piece in pieces_of(os.path.join(self.work, case + ".pvtu")):
                if piece.GetNumberOfPoints() == 0:
                    continue
                nonempty += piece.GetNumberOfCells() > 0
                for i, v in zip(*by_id(piece)):
                    worst = max(worst, worst_relative(v, ref[int(i)], scale, SOLVE_FLOOR))
                    seen.add(int(i))
            self.assertEqual(seen, set(ref), "every point of case " + case)
            self.assertLessEqual(worst, 1e-6, "max relative Fluence difference, case " + case)
            self.assertEqual(nonempty, 2 if case == "src_point" else RANKS, case)
            per_rank = self.solves.get(case, {})
            self.assertEqual(sorted(per_rank), list(range(RANKS)), case)
            for rank in range(RANKS):
                self.assertEqual(per_rank[rank], per_rank[0], "rank %d, case %s" % (rank, case))
            self.assertEqual(per_rank[0][0], "distributed", case)
        # Detector readings: the serial ones to 1e-6, the same on every rank.
        with open(os.path.join(self.work, "ref_detectors.json")) as f:
            refs = json.load(f)
        lines = self.numbers_per_rank("detectors", "detectors")
        for kind, ref in refs.items():
            expected = np.array(ref, dtype=float).ravel()
            self.assertEqual(sorted(lines.get(kind, {})), list(range(RANKS)), kind)
            for rank, values in lines[kind].items():
                self.assertEqual(values, lines[kind][0], "detectors %s rank %d" % (kind, rank))
                got = np.array(values)
                self.assertEqual(got.shape, expected.shape, kind)
                self.assertTrue(np.all(np.abs(expected) > 0), kind)
                self.assertLessEqual(float(np.max(np.abs(got - expected) / np.abs(expected))),
                                     1e-6, "detectors %s rank %d: %s vs %s" %
                                     (kind, rank, got, expected))

    def test_power_balance_equals_serial(self):
        # ComputePowerBalance on the distributed path: the whole object's
        # injected, absorbed and escaped power (summed over the ranks, the
        # partition faces left out), the same on every rank, equal to the
        # serial balance of the same tets to 1e-9 of the injected power
        # (both fluences solved to RelTol 1e-13; a partition face counted as
        # surface would add its flux: percent-level differences).
        import json
        with open(os.path.join(self.work, "ref_balance.json")) as f:
            refs = json.load(f)
        balances = self.numbers_per_rank("solves", "balance")
        cases = {"pvtu3": "a_divergence", "pvtu2": "a_divergence", "redist": "a_divergence",
                 "fem": "a_fem", "relight": "b_divergence", "src_point": "src_point",
                 "src_pencil": "src_pencil", "src_aimed": "src_aimed"}
        for case, ref_name in cases.items():
            expected = np.array(refs[ref_name], dtype=float)
            per_rank = balances.get(case, {})
            self.assertEqual(sorted(per_rank), list(range(RANKS)), case)
            for rank, values in per_rank.items():
                self.assertEqual(values, per_rank[0], "balance %s rank %d" % (case, rank))
            got = np.array(per_rank[0])
            injected = expected[:3]
            self.assertTrue(np.all(injected > 0), case)
            worst = max(float(np.max(np.abs(got[3 * k:3 * k + 3] - expected[3 * k:3 * k + 3]) /
                                     injected)) for k in range(3))
            self.assertLessEqual(worst, 1e-9, "power balance %s: %s vs serial %s" %
                                 (case, got, expected))

    def test_monte_carlo_replicated_equals_serial(self):
        # Issue 32: the photons split over the ranks on the replicated mesh.
        # Each rank traces every N-th batch of the one-process plan and the
        # batch sums are added over the ranks: on the pieces with GlobalIds
        # (merged in mesh.vtu's order) the serial run's estimates up to the
        # order of the additions (1e-12; the standard errors, a cancelling
        # difference of sums, 1e-9), at every point of every piece (the
        # pieces keep their partition); the detectors' readings and TPSFs the
        # same on every rank.
        import json
        with open(os.path.join(self.work, "ref_mc.json")) as f:
            refs = json.load(f)
        lines = self.numbers_per_rank("mc", "mc")
        for name in ("mc", "mc_tpsf"):
            reader = vtkXMLUnstructuredGridReader()
            reader.SetFileName(os.path.join(self.work, "ref_%s.vtu" % name))
            reader.Update()
            ref_data = reader.GetOutput().GetPointData()
            ids = vtk_to_numpy(ref_data.GetArray("PointIds")).tolist()
            ref_fluence = dict(zip(ids, vtk_to_numpy(ref_data.GetArray("Fluence"))))
            ref_error = dict(zip(ids, vtk_to_numpy(ref_data.GetArray("FluenceStandardError"))))
            for suffix in ("", "_pvtu2"):
                case = name + suffix
                per_rank = self.solves.get(case, {})
                self.assertEqual(sorted(per_rank), list(range(RANKS)), case)
                for rank in range(RANKS):
                    self.assertEqual(per_rank[rank][0], "replicated", "rank %d, %s" % (rank, case))
                # The detectors' readings: the same on every rank.
                self.assertEqual(sorted(lines.get(case, {})), list(range(RANKS)), case)
                for rank, values in lines[case].items():
                    self.assertEqual(values, lines[case][0], "%s rank %d" % (case, rank))
                if suffix:
                    # Without GlobalIds the pieces are merged in another point
                    # and triangle order than mesh.vtu's, and the photons'
                    # launch tables follow the order (Parallel.md): another
                    # sample of the same estimate. Both within their errors.
                    z = []
                    for piece in pieces_of(os.path.join(self.work, case + ".pvtu")):
                        if piece.GetNumberOfPoints() == 0:
                            continue
                        data = piece.GetPointData()
                        for i, v, e in zip(vtk_to_numpy(data.GetArray("PointIds")),
                                           vtk_to_numpy(data.GetArray("Fluence")),
                                           vtk_to_numpy(data.GetArray("FluenceStandardError"))):
                            combined = np.sqrt(e ** 2 + ref_error[int(i)] ** 2)
                            z.append(np.abs(v - ref_fluence[int(i)]) / combined)
                    z = np.concatenate(z)
                    self.assertLess(float(np.mean(z > 4)), 0.01, case)
                    self.assertTrue(0.5 < float(np.mean(z ** 2)) < 2.0, case)
                    continue
                for array, tol in (("Fluence", 1e-12), ("FluenceStandardError", 1e-9)):
                    ref = dict(zip(ids, vtk_to_numpy(ref_data.GetArray(array))))
                    scale = max(np.abs(v).max() for v in ref.values())
                    self.assertGreater(scale, 0.0, case)
                    seen, worst = set(), 0.0
                    for piece in pieces_of(os.path.join(self.work, case + ".pvtu")):
                        if piece.GetNumberOfPoints() == 0:
                            continue
                        pids = vtk_to_numpy(piece.GetPointData().GetArray("PointIds"))
                        values = vtk_to_numpy(piece.GetPointData().GetArray(array))
                        for i, v in zip(pids, values):
                            worst = max(worst, worst_relative(v, ref[int(i)], scale))
                            seen.add(int(i))
                    self.assertEqual(seen, set(ref), "every point of " + case)
                    self.assertLessEqual(worst, tol, "%s of %s" % (array, case))
                # and the serial ones to round-off.
                expected = np.array(refs[name])
                self.assertGreater(np.abs(expected).max(), 0.0, case)
                for rank, values in lines[case].items():
                    got = np.array(values)
                    self.assertEqual(got.shape, expected.shape, case)
                    self.assertLessEqual(worst_relative(got, expected, np.abs(expected).max()),
                                         1e-12, "%s rank %d: %s vs %s" % (case, rank, got,
                                                                         expected))

    def test_monte_carlo_gathers_when_a_copy_per_rank_does_not_fit(self):
        plans = {case: {rank: m.group(3) for rank, m in per_rank.items()}
                 for case, per_rank in self.rank_reports(
                     "mc", r"^plan (\S+) rank (\d+) (.*)$").items()}
        expected = {
            "mc_small_memory": r"^gathered \(same mesh\): the Monte Carlo on rank 0 alone: "
                               r"rank 0: a copy of the whole mesh on each of the %d ranks of "
                               r"this node needs about [\d.]+ MiB \([\d.e+]+ bytes\); the node "
                               r"has 0\.00102 MiB \(1074 bytes\) "
                               r"\(TRANSLUCENCY_REPLICATED_MEMORY\)$" % RANKS,
            "mc_bad_memory": r"^gathered \(same mesh\): the Monte Carlo on rank 0 alone: rank 0: "
                             r"TRANSLUCENCY_REPLICATED_MEMORY='lots' is not a number of GiB > 0$"}
        reader = vtkXMLUnstructuredGridReader()
        reader.SetFileName(os.path.join(self.work, "ref_mc.vtu"))
        reader.Update()
        ref = dict(zip(*by_id(reader.GetOutput())))
        scale = max(np.abs(v).max() for v in ref.values())
        # Said once, by rank 0, as a warning too (not only in the plan).
        warnings = {case: {rank: m.group(3) for rank, m in per_rank.items()}
                    for case, per_rank in self.rank_reports(
                        "mc", r"^warning (\S+) rank (\d+) .*(the Monte Carlo runs on rank 0 "
                              r"alone \(no faster than one process\): rank 0: .*)$").items()}
        for case, pattern in expected.items():
            self.assertEqual(sorted(plans.get(case, {})), list(range(RANKS)), case)
            self.assertEqual(sorted(warnings.get(case, {})), [0], case)
            self.assertIn(plans[case][0].split("rank 0 alone: ", 1)[1], warnings[case][0], case)
            for rank in range(RANKS):
                self.assertRegex(plans[case][rank], pattern, "rank %d" % rank)
                self.assertEqual(self.solves[case][rank][0], "gathered", case)
            # rank 0 traced alone: the serial run's numbers (ids: the same order)
            worst, seen = 0.0, set()
            for piece in pieces_of(os.path.join(self.work, case + ".pvtu")):
                if piece.GetNumberOfPoints() == 0:
                    continue
                for i, v in zip(*by_id(piece)):
                    worst = max(worst, worst_relative(v, ref[int(i)], scale))
                    seen.add(int(i))
            self.assertEqual(seen, set(ref), case)
            self.assertLessEqual(worst, 1e-12, case)

    def test_monte_carlo_error_on_every_rank(self):
        texts = [self.rank_text("mc_outside", rank) for rank in range(RANKS)]
        self.assertIn("path replicated points 0", texts[0])
        self.assertIn("point source 1: position (20, 0, 0) is outside the object", texts[0])
        self.assertIn("executive: returned failure", texts[0])
        for rank in range(1, RANKS):
            self.assertEqual(texts[rank], texts[0], "rank %d" % rank)

    def test_source_outside_same_error_everywhere(self):
        texts = [self.rank_text("outside", rank) for rank in range(RANKS)]
        self.assertIn("path distributed", texts[0])
        self.assertIn("point source 1: position (20, 0, 0) is outside the object", texts[0])
        self.assertIn("executive: returned failure", texts[0])
        self.assertRegex(texts[0], r"outside the object \(\d+ tets, bounds x -[34][.\d]*\.\.[34]")
        for rank in range(1, RANKS):
            self.assertEqual(texts[rank], texts[0], "rank %d" % rank)
        # and the next solve works on every rank
        per_rank = self.solves.get("src_after_error", {})
        self.assertEqual(sorted(per_rank), list(range(RANKS)))
        self.assertEqual(per_rank[0][0], "distributed")

    def test_nonconverged_is_an_error_everywhere(self):
        # Issue 32: never a non-converged field, on any rank.
        texts = []
        for rank in range(RANKS):
            name = os.path.join(self.work, "stuck_%d.txt" % rank)
            texts.append(open(name).read() if os.path.exists(name) else "")
        self.assertIn("path distributed points 0 fluence False", texts[0])
        self.assertIn("did not converge, also after a full set-up", texts[0])
        self.assertIn("MaxIter 1", texts[0])
        self.assertIn("executive: returned failure", texts[0])
        for rank in range(1, RANKS):
            self.assertEqual(texts[rank], texts[0], "rank %d" % rank)

    def test_paint_is_values_only_and_converged(self):
        # The paint reused the hierarchy of the unpainted solve (the path of
        # issue 32's bug) and still gave the serial field (test above).
        self.assertEqual(self.solves["unpainted"][0][1], "full")
        self.assertEqual(self.solves["paint"][0][1], "values-only")

    def test_set_ups_counted(self):
        # Issue 32, by counters on every rank: the cold solve numbers the mesh
        # once and sets up one BoomerAMG coarsening for the three channels
        # (the other two their Galerkin levels on it); the relight and the
        # warm start (same mesh and material) number and set up nothing.
        setups = {case: {rank: m.group(3) for rank, m in per_rank.items()}
                  for case, per_rank in self.rank_reports(
                      "solves", r"^setup (\S+) rank (\d+) (.*)$").items()}
        for case, expected in (("pvtu3", "rebuilt (numberings 1, hierarchies 1)"),
                               ("relight", "kept (numberings 1, hierarchies 1)"),
                               ("warm", "kept (numberings 1, hierarchies 1)")):
            per_rank = setups.get(case, {})
            self.assertEqual(sorted(per_rank), list(range(RANKS)), case)
            for rank in range(RANKS):
                self.assertEqual(per_rank[rank], expected, "rank %d, %s" % (rank, case))

    def test_relight_reads_no_material(self):
        # Issues 31/32: the relight and the warm start carry the same
        # coefficient arrays, unmodified: every rank solves its kept material
        # again instead of reading its piece's arrays; a paint (new arrays on
        # pieces without ghost cells) is compared with the kept material in
        # place, so it reads no copy either (its fields equal serial:
        # the "paint" and "paint_extreme" cases of CASES).
        conversions = {case: {rank: int(m.group(3)) for rank, m in per_rank.items()}
                       for case, per_rank in self.rank_reports(
                           "solves", r"^conversions (\S+) rank (\d+) (\d+)$").items()}
        for rank in range(RANKS):
            cold = conversions["pvtu3"][rank]
            self.assertEqual(cold, 1, "rank %d" % rank)
            self.assertEqual(conversions["relight"][rank], cold, "rank %d" % rank)
            self.assertEqual(conversions["warm"][rank], cold, "rank %d" % rank)
            self.assertEqual(conversions["paint"][rank], conversions["unpainted"][rank],
                             "rank %d" % rank)

    def test_hierarchy_kept_and_warm_start(self):
        self.assertEqual(self.solves["pvtu3"][0][1], "full")
        self.assertEqual(self.solves["relight"][0][1], "unchanged")
        self.assertEqual(self.solves["warm"][0][1], "unchanged")
        cold = [int(k) for k in self.solves["relight"][0][2].split(",")]
        warm = [int(k) for k in self.solves["warm"][0][2].split(",")]
        self.assertTrue(all(w <= 2 for w in warm), "warm %s after cold %s" % (warm, cold))


if __name__ == "__main__":
    main()
