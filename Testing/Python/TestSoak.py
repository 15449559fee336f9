#!/usr/bin/env python3
"""Seeded soak test of the editing loop: random cuts, paints and relights, each re-solved.

How to run (from a build tree; ctest sets the variables itself):

    PYTHONPATH=<build>/lib/python3.11/site-packages /usr/bin/python3 TestSoak.py [--steps N] [--seed S]

(TRANSLUCENCY_SOAK_SEED and TRANSLUCENCY_SOAK_STEPS do the same.) The state is
the ORIGINAL tet mesh (a sphere, about 3k tets) with its current coefficients,
the current cut (or none) and the current lights. Each step is one of

1. a cut: a random plane (origin in the bounding box, random normal, random
   InsideOut) cuts the ORIGINAL mesh (carrying the current coefficients) with
   vtkStrokeCut; a cut that removes everything is checked and dropped;
2. a paint: a random point, width, mode and target painted with
   vtkPaintScatteringCoefficients on the current (cut or whole) mesh, the new
   values scattered back to the original tets by vtkOriginalCellIds;
3. a relight: a random directional light (and uniform light level);

followed by vtkSurfaceIrradiance + vtkSolveDiffusion on the current mesh.
After every step: no VTK error and no exception; Fluence has no NaN or
infinity; every coefficient array is finite and >= 0 and equals the original
mesh's values through vtkOriginalCellIds. After a cut: every tet has positive
volume and a minimum dihedral angle >= 0.5 deg (or >= its original tet's, if
that was lower), output tets are the original ones through vtkOriginalPointIds
and vtkOriginalCellIds, points of the kept side did not move, moved points
stayed on the removed side, and exactly the tets with a vertex on the kept
side were kept.

The second test, test_soak_incremental (Python.TestSoakIncremental in ctest:
1,000 operations on a 200k-tet sphere), keeps ONE vtkSurfaceIrradiance ->
vtkSolveDiffusion pipeline alive, as the GUI does, so that paints take the
incremental (values-only) path, relights warm-start and cuts rebuild; a fourth
kind of step switches the solver (divergence, fem) and the linear solver
(multigrid-agg, multigrid-cg, cg-ichol). Besides the invariants above, every
SOAK_COLD_EVERY steps and after the last one the kept pipeline's Fluence must
equal a fresh, cold pipeline's on the same input (both solved to RelTol 1e-10:
|difference| <= 1e-6 of the largest fluence), so a stale cache, a wrong
incremental update or a warm start that kept old state is caught, not only a
crash. TRANSLUCENCY_SOAK_TETS, TRANSLUCENCY_SOAK_INCREMENTAL_STEPS and
TRANSLUCENCY_SOAK_COLD_EVERY size it.

On failure, the message names the seed and step to reproduce. Exits non-zero
on failure (unittest).
"""

import math
import os
import random
import sys
import time
import unittest

import numpy as np

from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.util.misc import calldata_type
from vtkmodules.vtkCommonCore import VTK_STRING, vtkCommand
from vtkmodules.vtkCommonDataModel import vtkPlane, vtkUnstructuredGrid
from vtkmodules.vtkFiltersSources import vtkSphereSource

import translucency

SEED = int(os.environ.get("TRANSLUCENCY_SOAK_SEED", "20261121"))
STEPS = int(os.environ.get("TRANSLUCENCY_SOAK_STEPS", "200"))
COEFFICIENTS = ("AbsorptionCoefficient", "ReducedScatteringCoefficient", "RefractiveIndex")
INCREMENTAL_STEPS = int(os.environ.get("TRANSLUCENCY_SOAK_INCREMENTAL_STEPS", "1000"))
# TRANSLUCENCY_SOAK_TETS (make test-soak) wins over the ctest default
# TRANSLUCENCY_SOAK_DEFAULT_TETS (a 3k-tet sphere, to keep the suite short).
INCREMENTAL_TETS = int(os.environ.get("TRANSLUCENCY_SOAK_TETS") or
                       os.environ.get("TRANSLUCENCY_SOAK_DEFAULT_TETS", "200000"))
COLD_EVERY = int(os.environ.get("TRANSLUCENCY_SOAK_COLD_EVERY", "25"))
SOLVERS = ("divergence", "fem")
LINEAR_SOLVERS = ("multigrid-agg", "multigrid-cg", "cg-ichol")
MIN_DIHEDRAL = 0.5  # degrees: vtkStrokeCut's default MinimumDihedralAngle


class Messages:
    """Collects the errors (and counts the warnings) of the observed filters."""

    def __init__(self):
        self.errors, self.warnings = [], 0

    def watch(self, algorithm):
        @calldata_type(VTK_STRING)
        def on_error(caller, event, message):
            self.errors.append("%s: %s" % (caller.GetClassName(), message))

        @calldata_type(VTK_STRING)
        def on_warning(caller, event, message):
            self.warnings += 1

        algorithm.AddObserver(vtkCommand.ErrorEvent, on_error)
        algorithm.AddObserver(vtkCommand.WarningEvent, on_warning)
        algorithm.GetExecutive().AddObserver(vtkCommand.ErrorEvent, on_error)
        return algorithm


def points_of(grid):
    return vtk_to_numpy(grid.GetPoints().GetData()).astype(float).reshape(-1, 3)


def tets_of(grid):
    return vtk_to_numpy(grid.GetCells().GetConnectivityArray()).astype(np.int64).reshape(-1, 4)


def signed_volumes(points, tets):
    a, b, c, d = (points[tets[:, k]] for k in range(4))
    return np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) / 6.0


def min_dihedral(points, tets):
    """Smallest of the six dihedral angles of every tet (degrees)."""
    p = [points[tets[:, k]] for k in range(4)]
    normals = []
    for k in range(4):
        q0, q1, q2 = p[(k + 1) % 4], p[(k + 2) % 4], p[(k + 3) % 4]
        n = np.cross(q1 - q0, q2 - q0)
        outward = np.where(np.einsum("ij,ij->i", n, p[k] - q0) > 0, -1.0, 1.0)
        normals.append(n * (outward / np.linalg.norm(n, axis=1))[:, None])
    angles = [np.degrees(np.arccos(np.clip(-np.einsum("ij,ij->i", normals[k], normals[l]),
                                           -1.0, 1.0)))
              for k in range(4) for l in range(k + 1, 4)]
    return np.min(np.array(angles), axis=0)


def original_mesh(tets=3000, resolution=18):
    source = vtkSphereSource()
    source.SetRadius(10.0)
    source.SetThetaResolution(resolution)
    source.SetPhiResolution(resolution)
    tetra = translucency.vtkTetrahedralizeSurface()
    tetra.SetInputConnection(source.GetOutputPort())
    tetra.SetTargetNumberOfTets(tets)
    assign = translucency.vtkAssignScatteringCoefficients()
    assign.SetInputConnection(tetra.GetOutputPort())
    assign.SetMaterialName("marble")
    assign.Update()
    grid = vtkUnstructuredGrid()
    grid.DeepCopy(assign.GetOutput())
    return grid


def unit_vector(rng):
    while True:
        v = np.array([rng.gauss(0, 1) for _ in range(3)])
        if np.linalg.norm(v) > 1e-3:
            return v / np.linalg.norm(v)


class SoakTest(unittest.TestCase):

    def setUp(self):
        self.start_with(original_mesh())

    def start_with(self, original):
        self.original = original
        self.p0 = points_of(self.original)
        self.t0 = tets_of(self.original)
        self.dihedral0 = min_dihedral(self.p0, self.t0)
        # The current coefficients of the original tets (painting changes them).
        self.coefficients = {name: vtk_to_numpy(self.original.GetCellData().GetArray(name))
                             .astype(float).copy() for name in COEFFICIENTS}
        self.current = self.original  # the mesh solved: the original or a cut of it
        self.cut_ids = None  # vtkOriginalCellIds of the current cut
        self.lights = [(0.0, -1.0, -1.0, 1.0)]
        self.uniform = 0.1
        self.paint_width = 6.0  # mm: the widest stroke
        self.paint_points = 5  # the most points of a stroke

    def with_coefficients(self, grid, ids):
        """A shallow copy of `grid` with the current coefficients of tets `ids`."""
        copy = vtkUnstructuredGrid()
        copy.ShallowCopy(grid)
        for name, values in self.coefficients.items():
            array = numpy_to_vtk(np.ascontiguousarray(values[ids]), deep=1)
            array.SetName(name)
            copy.GetCellData().AddArray(array)
        return copy

    # ------------------------------------------------------------- steps

    def step_cut(self, rng, where):
        lo, hi = self.p0.min(axis=0), self.p0.max(axis=0)
        origin = np.array([rng.uniform(lo[k], hi[k]) for k in range(3)])
        normal = unit_vector(rng)
        inside_out = rng.random() < 0.5
        plane = vtkPlane()
        plane.SetOrigin(*origin)
        plane.SetNormal(*normal)
        messages = Messages()
        cut = messages.watch(translucency.vtkStrokeCut())
        cut.SetInputData(self.with_coefficients(self.original, np.arange(len(self.t0))))
        cut.SetCutFunction(plane)
        cut.SetInsideOut(inside_out)
        cut.Update()
        self.assertEqual(messages.errors, [], where)
        out = cut.GetOutput()
        side0 = (self.p0 - origin) @ normal * (-1.0 if inside_out else 1.0)  # > 0: removed
        expected = np.nonzero((side0[self.t0] <= 0).any(axis=1))[0]
        if out.GetNumberOfCells() == 0:
            self.assertEqual(len(expected), 0, where + ": an empty cut kept tets")
            return "cut (everything removed; dropped)"
        cell_ids = vtk_to_numpy(out.GetCellData().GetArray("vtkOriginalCellIds")).astype(np.int64)
        point_ids = vtk_to_numpy(out.GetPointData().GetArray("vtkOriginalPointIds")).astype(
            np.int64)
        p1, t1 = points_of(out), tets_of(out)
        self.assertTrue(np.array_equal(np.sort(cell_ids), expected), where + ": tets kept")
        self.assertTrue(np.array_equal(point_ids[t1], self.t0[cell_ids]), where + ": point ids")
        kept = side0[point_ids] <= 0
        self.assertTrue(np.array_equal(p1[kept], self.p0[point_ids[kept]]),
                        where + ": a point of the kept side moved")
        side1 = (p1[~kept] - origin) @ normal * (-1.0 if inside_out else 1.0)
        self.assertTrue(np.all(side1 >= -1e-9), where + ": a point crossed the cut")
        self.assertTrue(np.all(signed_volumes(p1, t1) > 0), where + ": non-positive tet")
        # A tet without a moved vertex is its original tet (points checked above):
        # the dihedral bound needs checking only where a vertex moved.
        moved = (~kept[t1]).any(axis=1)
        bound = np.minimum(MIN_DIHEDRAL, self.dihedral0[cell_ids[moved]]) - 1e-6
        self.assertTrue(np.all(min_dihedral(p1, t1[moved]) >= bound), where + ": flat tet")
        self.current, self.cut_ids = out, cell_ids
        return "cut (%d tets kept, %d moved)" % (len(cell_ids), cut.GetNumberOfMovedVertices())

    def step_paint(self, rng, where):
        lo, hi = self.p0.min(axis=0), self.p0.max(axis=0)
        mode = rng.choice(("set", "multiply", "add"))
        paint = translucency.vtkPaintScatteringCoefficients()
        for _ in range(rng.randint(1, self.paint_points)):
            paint.AddStrokePoint(*[rng.uniform(lo[k], hi[k]) for k in range(3)])
        paint.SetWidth(rng.uniform(0.0, self.paint_width))
        paint.SetStrength(rng.uniform(0.0, 1.0))
        if mode == "set":
            paint.SetModeToSet()
            mu_a = [rng.uniform(0.0, 2.0) for _ in range(3)]
            sigma = [rng.uniform(0.0, 3.0) for _ in range(3)]
        elif mode == "multiply":
            paint.SetModeToMultiply()
            mu_a = [rng.uniform(0.0, 3.0) for _ in range(3)]
            sigma = [rng.uniform(0.0, 3.0) for _ in range(3)]
        else:
            paint.SetModeToAdd()
            mu_a = [rng.uniform(-1.0, 1.0) for _ in range(3)]
            sigma = [rng.uniform(-2.0, 2.0) for _ in range(3)]
        paint.SetTargetAbsorptionCoefficient(*mu_a)
        paint.SetTargetReducedScatteringCoefficient(*sigma)
        paint.SetChannelMask(*[rng.random() < 0.8 for _ in range(3)])
        ids = np.arange(len(self.t0)) if self.cut_ids is None else self.cut_ids
        messages = Messages()
        messages.watch(paint)
        paint.SetInputData(self.with_coefficients(self.current, ids))
        paint.Update()
        self.assertEqual(messages.errors, [], where)
        out = paint.GetOutput()
        for name in ("AbsorptionCoefficient", "ReducedScatteringCoefficient"):
            self.coefficients[name][ids] = vtk_to_numpy(out.GetCellData().GetArray(name))
        self.current = out
        weights = vtk_to_numpy(out.GetCellData().GetArray("PaintWeight"))
        return "paint %s (%d tets touched)" % (mode, int(np.sum(weights > 1e-6)))

    def step_relight(self, rng, where):
        d = unit_vector(rng)
        self.lights = [(d[0], d[1], d[2], rng.uniform(0.0, 2.0))]
        self.uniform = rng.choice((0.0, rng.uniform(0.0, 0.5)))
        if self.lights[0][3] == 0.0 and self.uniform == 0.0:
            self.uniform = 0.1
        return "relight"

    # ------------------------------------------------------------- solve

    def solve_and_check(self, where):
        ids = np.arange(len(self.t0)) if self.cut_ids is None else self.cut_ids
        grid = self.with_coefficients(self.current, ids)
        messages = Messages()
        light = messages.watch(translucency.vtkSurfaceIrradiance())
        light.SetInputData(grid)
        for x, y, z, e in self.lights:
            light.AddDirectionalLight(x, y, z, e)
        light.SetUniformLightIrradiance(self.uniform)
        light.SetUniformLightSamples(8)
        solve = messages.watch(translucency.vtkSolveDiffusion())
        solve.SetInputConnection(light.GetOutputPort())
        solve.Update()
        self.assertEqual(messages.errors, [], where)
        out = solve.GetOutput()
        self.assertEqual(out.GetNumberOfCells(), len(ids), where)
        fluence = vtk_to_numpy(out.GetPointData().GetArray("Fluence"))
        self.assertTrue(np.all(np.isfinite(fluence)), where + ": Fluence not finite")
        for name in COEFFICIENTS:
            values = vtk_to_numpy(out.GetCellData().GetArray(name))
            self.assertTrue(np.all(np.isfinite(values)) and np.all(values >= 0),
                            where + ": " + name + " not finite or negative")
            self.assertTrue(np.array_equal(values, self.coefficients[name][ids]),
                            where + ": " + name + " does not map to the original tets")
        if self.cut_ids is not None:
            self.assertTrue(np.array_equal(
                vtk_to_numpy(out.GetCellData().GetArray("vtkOriginalCellIds")), self.cut_ids),
                where + ": vtkOriginalCellIds changed in the solve")

    def test_soak(self):
        rng = random.Random(SEED)
        start = time.time()
        kinds = {"cut": 0, "paint": 0, "relight": 0}
        for step in range(STEPS):
            kind = rng.choice(("cut", "paint", "relight"))
            where = "seed %d, step %d (%s)" % (SEED, step, kind)
            what = getattr(self, "step_" + kind)(rng, where)
            self.solve_and_check(where)
            kinds[kind] += 1
            if step % 20 == 0:
                print("step %3d: %s" % (step, what), flush=True)
        print("%d steps (%s) in %.1f s, seed %d" % (
            STEPS, ", ".join("%d %ss" % (n, k) for k, n in kinds.items()), time.time() - start,
            SEED))
        self.assertTrue(all(n > 0 for n in kinds.values()))


    # ------------------------------------------------- the kept pipeline

    def step_switch(self, rng, where):
        self.solver = rng.choice(SOLVERS)
        self.linear_solver = rng.choice(LINEAR_SOLVERS)
        return "switch to %s / %s" % (self.solver, self.linear_solver)

    def make_pipeline(self, messages):
        light = messages.watch(translucency.vtkSurfaceIrradiance())
        light.SetUniformLightSamples(8)
        solve = messages.watch(translucency.vtkSolveDiffusion())
        solve.SetInputConnection(light.GetOutputPort())
        solve.SetRelTol(1e-10)
        solve.SetMaxIter(20000)
        return light, solve

    def run_pipeline(self, light, solve, grid):
        light.SetInputData(grid)
        light.RemoveAllDirectionalLights()
        for x, y, z, e in self.lights:
            light.AddDirectionalLight(x, y, z, e)
        light.SetUniformLightIrradiance(self.uniform)
        if not solve.SetSolverByName(self.solver):
            self.fail("SetSolverByName(%r) refused" % self.solver)
        solve.SetLinearSolver(self.linear_solver)
        solve.Update()
        return solve.GetOutput()

    def test_soak_incremental(self):
        # The sphere's surface resolution grows with the tets asked for (TetGen
        # keeps the surface's triangles: resolution 64 alone gives ~40k tets).
        resolution = 64 if INCREMENTAL_TETS >= 100000 else 32 if INCREMENTAL_TETS >= 10000 else 18
        self.start_with(original_mesh(INCREMENTAL_TETS, resolution))
        self.solver, self.linear_solver = "divergence", "multigrid-agg"
        # Strokes of 1-2 points up to 1 mm wide touch a few % of the tets, so
        # most paints take the incremental path (vtkSolveDiffusion's
        # MaximumChangedFraction, 5 %).
        self.paint_width, self.paint_points = 1.0, 2
        rng = random.Random(SEED)
        start = time.time()
        messages = Messages()
        light, solve = self.make_pipeline(messages)
        kinds = {"cut": 0, "paint": 0, "relight": 0, "switch": 0}
        paths, colds, worst = {}, 0, 0.0
        print("%d tets, %d steps, cold comparison every %d" % (
            len(self.t0), INCREMENTAL_STEPS, COLD_EVERY), flush=True)
        for step in range(INCREMENTAL_STEPS):
            kind = rng.choice(tuple(kinds))
            where = "seed %d, step %d (%s)" % (SEED, step, kind)
            what = getattr(self, "step_" + kind)(rng, where)
            ids = np.arange(len(self.t0)) if self.cut_ids is None else self.cut_ids
            grid = self.with_coefficients(self.current, ids)
            out = self.run_pipeline(light, solve, grid)
            self.assertEqual(messages.errors, [], where)
            for c in range(3):
                self.assertTrue(solve.GetConverged(c), where + ": channel %d" % c)
            self.assertEqual(out.GetNumberOfCells(), len(ids), where)
            fluence = vtk_to_numpy(out.GetPointData().GetArray("Fluence")).copy()
            self.assertTrue(np.all(np.isfinite(fluence)), where + ": Fluence not finite")
            for name in COEFFICIENTS:
                values = vtk_to_numpy(out.GetCellData().GetArray(name))
                self.assertTrue(np.array_equal(values, self.coefficients[name][ids]),
                                where + ": " + name + " does not map to the original tets")
            path = "%s/%s" % (kind, solve.GetLastAssembly())
            paths[path] = paths.get(path, 0) + 1
            if (step + 1) % COLD_EVERY == 0 or step == INCREMENTAL_STEPS - 1:
                cold_messages = Messages()
                cold_light, cold_solve = self.make_pipeline(cold_messages)
                cold = self.run_pipeline(cold_light, cold_solve,
                                         self.with_coefficients(self.current, ids))
                self.assertEqual(cold_messages.errors, [], where + " (cold)")
                reference = vtk_to_numpy(cold.GetPointData().GetArray("Fluence"))
                scale = np.max(np.abs(reference))
                difference = np.max(np.abs(fluence - reference)) / scale
                self.assertLessEqual(difference, 1e-6,
                                     where + ": kept pipeline differs from a cold solve")
                colds += 1
                worst = max(worst, difference)
            kinds[kind] += 1
            if step % 50 == 0 or os.environ.get("TRANSLUCENCY_SOAK_VERBOSE"):
                print("step %4d (%.0f s): %s, %s" % (step, time.time() - start, what,
                                                    solve.GetLastAssembly()), flush=True)
        print("%d steps (%s) in %.1f s, %d cold comparisons (largest difference %.2g), "
              "seed %d; paths: %s" % (
            INCREMENTAL_STEPS, ", ".join("%d %ss" % (n, k) for k, n in kinds.items()),
            time.time() - start, colds, worst, SEED,
            ", ".join("%s %d" % kv for kv in sorted(paths.items()))))
        self.assertTrue(all(n > 0 for n in kinds.values()))
        # The kept pipeline must have taken its incremental paths at least once.
        self.assertTrue(any(p.startswith("paint/") and not p.endswith("/full")
                            for p in paths), paths)


if __name__ == "__main__":
    args = sys.argv[1:]
    for flag, name in (("--steps", "STEPS"), ("--seed", "SEED")):
        if flag in args:
            k = args.index(flag)
            globals()[name] = int(args[k + 1])
            del args[k:k + 2]
    unittest.main(argv=[sys.argv[0]] + args, verbosity=2)
