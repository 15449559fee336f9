#!/usr/bin/env python3
"""The parallel seam under MPI: every filter prints its plan, the gathered
Solve Diffusion ends (issue 32 item 2), and every failure ends on every rank
with the same message (issue 32 item 3 and "every error agreed").

How to run (ctest does this, with 2 and with 3 ranks):

    /usr/bin/python3 TestParallelSeam.py <Translucency plugin> <number of ranks>

1. Here: a sphere surface (radius 4 mm) is written as sphere.ply.
2. `mpiexec -n N pvbatch --symmetric SeamPipeline.py ... run`: the chain and
   the other filters (see that script) on every rank. Checked: the run ends
   within its time limit; every one of the 11 public filters reports on every
   rank a path and a plan with a reason, the same on every rank, the path
   being the plan's kind (per piece, distributed, gathered); the chain's
   plans are those of Documentation/Parallel.md (Tetrahedralize gathered to
   rank 0, Assign and Outgoing Radiance per piece, Irradiance and Solve
   distributed); Solve Diffusion with TRANSLUCENCY_PARALLEL=gathered and with
   the deprecated TRANSLUCENCY_GATHERED_SOLVE=1 takes the gathered path and
   gives the distributed Fluence to 1e-6 at every point of every rank's
   piece; with the extended collimated model and DistributedSolve on it plans
   and takes the distributed path (naming the beam) and equals
   DistributedSolve off (gathered) to 1e-6. Before the seam both gathered
   cases hung.
3. `... failures`: a missing file for the Surface Reader (rank 0 reads), a
   wrong mesher, an unknown material, a paint and a Surface Irradiance
   without materials, a solve without Irradiance, a radiance without
   Fluence, a cut of an empty mesh, a fracture without seeds, a radiosity
   without materials, an inverse problem without measurements, detector readings without
   detectors, an unknown TRANSLUCENCY_PARALLEL: the run ends within its
   time limit, and every case has an error on every rank, the same text on
   every rank. Before the seam the missing file hung every rank.
"""

import os
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from mpi_harness import run  # noqa: E402  (the time-limited runner that ends hung ranks)

PLUGIN = sys.argv[1] if len(sys.argv) > 1 else ""
RANKS = int(sys.argv[2]) if len(sys.argv) > 2 else 2
TIME_LIMIT = 240  # seconds per mpiexec run: a hang ceiling for a loaded machine
FILTERS = ["TetrahedralizeSurface", "AssignScatteringCoefficients", "SurfaceIrradiance",
           "SolveDiffusion", "OutgoingRadiance", "DetectorReadings",
           "PaintScatteringCoefficients", "StrokeCut", "FractureTetMesh",
           "TranslucentRadiosity", "InverseDiffusion"]
EXPECTED = {"TetrahedralizeSurface": "gathered (rank 0)",
            "AssignScatteringCoefficients": "per piece", "SurfaceIrradiance": "distributed",
            "SolveDiffusion": "distributed", "OutgoingRadiance": "per piece",
            "DetectorReadings": "per piece", "PaintScatteringCoefficients": "per piece",
            "StrokeCut": "per piece", "FractureTetMesh": "gathered (rank 0)",
            "TranslucentRadiosity": "gathered (rank 0)",
            "InverseDiffusion": "gathered (same mesh)"}


def write_sphere(name):
    from vtkmodules.vtkFiltersSources import vtkSphereSource
    from vtkmodules.vtkIOPLY import vtkPLYWriter
    sphere = vtkSphereSource()
    sphere.SetRadius(4.0)
    sphere.SetThetaResolution(16)
    sphere.SetPhiResolution(12)
    writer = vtkPLYWriter()
    writer.SetInputConnection(sphere.GetOutputPort())
    writer.SetFileName(name)
    writer.Write()


def per_rank(work, mode):
    """[{key: value}] per rank from <mode>_<rank>.txt (key: words before the value)."""
    ranks = []
    for r in range(RANKS):
        with open(os.path.join(work, "%s_%d.txt" % (mode, r))) as f:
            lines = f.read().splitlines()
        ranks.append(lines)
    return ranks


def fields(text):
    return dict(item.split("=", 1) for item in text.split("|"))


class ParallelSeamTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.work = cls.tmp.name
        write_sphere(os.path.join(cls.work, "sphere.ply"))
        script = os.path.join(HERE, "SeamPipeline.py")
        cls.results = {}
        for mode in ("run", "failures"):
            cls.results[mode] = run(
                ["mpiexec", "--allow-run-as-root", "--oversubscribe", "-n", str(RANKS),
                 "-x", "OMP_NUM_THREADS=1", "pvbatch", "--symmetric", script, PLUGIN,
                 cls.work, mode], cls.work, TIME_LIMIT)

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def ended(self, mode):
        result = self.results[mode]
        self.assertIsNotNone(result.returncode, "%s hung:\n%s" % (mode, result.stderr[-3000:]))
        self.assertEqual(result.returncode, 0, result.stdout[-2000:] + result.stderr[-3000:])
        ranks = per_rank(self.work, mode)
        for r, lines in enumerate(ranks):
            self.assertEqual(lines[-1], "done", "rank %d did not finish %s" % (r, mode))
        return ranks

    def test_plans(self):
        ranks = self.ended("run")
        plans = []
        for lines in ranks:
            plans.append({l.split()[1]: fields(l.split(" ", 2)[2])
                          for l in lines if l.startswith("plan ")})
        self.assertEqual(sorted(plans[0]), sorted(FILTERS))
        for name in FILTERS:
            with self.subTest(filter=name):
                first = plans[0][name]
                for r in range(1, RANKS):
                    self.assertEqual(plans[r][name], first, "rank %d differs" % r)
                kind, _, reason = first["plan"].partition(": ")
                self.assertEqual(kind, EXPECTED[name])
                self.assertGreater(len(reason), 10)
                self.assertEqual(first["path"], kind.split(" (")[0])

    def test_gathered_solves(self):
        ranks = self.ended("run")
        for r, lines in enumerate(ranks):
            solves = {l.split()[1]: fields(l.split(" ", 2)[2])
                      for l in lines if l.startswith("solve ")}
            self.assertEqual(sorted(solves), ["collimated", "deprecated", "override"])
            for case in ("override", "deprecated"):
                with self.subTest(rank=r, case=case):
                    s = solves[case]
                    self.assertEqual(s["path"], "gathered")
                    self.assertIn("TRANSLUCENCY_", s["plan"])
                    self.assertNotEqual(s["diff"], "missing")
                    self.assertLess(float(s["diff"]), 1e-6)
            c = solves["collimated"]
            self.assertEqual(c["path"], "distributed")
            self.assertIn("extended collimated models", c["plan"])
            self.assertNotEqual(c["diff"], "missing")
            self.assertLess(float(c["diff"]), 1e-6)
        total = sum(int(fields(l.split(" ", 2)[2])["points"])
                    for lines in ranks for l in lines if l.startswith("solve override"))
        self.assertGreater(total, 0)

    def test_failures_agree(self):
        ranks = self.ended("failures")
        cases = [{l.split()[1]: l.split(" ", 2)[2] for l in lines if l.startswith("fail ")}
                 for lines in ranks]
        self.assertEqual(len(cases[0]), 13)
        for case, message in cases[0].items():
            with self.subTest(case=case, message=message):
                self.assertNotEqual(message, "NONE")
                for r in range(1, RANKS):
                    self.assertEqual(cases[r][case], message, "rank %d differs" % r)
        self.assertIn("missing.ply", cases[0]["reader_missing"])
        self.assertIn("TRANSLUCENCY_PARALLEL='sometimes'", cases[0]["override_unknown"])


if __name__ == "__main__":
    unittest.main(argv=sys.argv[:1])
