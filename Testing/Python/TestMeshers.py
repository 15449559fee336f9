#!/usr/bin/env python3
"""The two tetrahedralisers of vtkTetrahedralizeSurface and mesh sizing (issue 22).

How to run (from a build tree; ctest sets the variables itself):

    PYTHONPATH=<build>/lib/python3.11/site-packages /usr/bin/python3 TestMeshers.py

Asserts:
  - the same bad surfaces give the same error message with mesher "tetgen"
    and "hxt" (the checks run before either mesher); an unknown mesher is
    named; in a build without gmsh, "hxt" says "this build has no gmsh";
  - hxt fills the bunny: the tets' volumes sum to the enclosed volume, none is
    degenerate by TetMesh's test (|V| > 1e-14 diag^3), the count is near the
    target, the output is in positive (VTK) orientation;
  - sizes honoured (issue 33): on the bunny, tetgen at 5,000, 30,000 and
    100,000 tets (the last in the slow tier, Python.TestMeshersLarge, with
    hxt's quality on the bunny below) and hxt with uniform sizing at 5,000
    and 30,000 give a
    count within 25 % of the target, or (tetgen below the floor its quality
    bound and the surface's 3,674 triangles set) one warning naming the
    floor, checked by an unbounded run, and what to do;
  - uniform sizing is measurably uniform on a 5 mm sphere: the fraction of
    tets whose centroid lies within 0.5 mm of the surface is the shell's volume
    fraction 0.271 +- 0.08 (measured at 30k tets: TetGen 0.284, hxt 0.330;
    TetGen's graded default: > 0.40, measured 0.44-0.46),
    and the edge lengths' coefficient of variation is < 0.23 (graded TetGen:
    0.26-0.27);
  - TetGen honours its radius-edge bound for all but < 1 % of the tets (those
    it keeps near the input surface's small angles), with a stricter bound
    leaving more tets above 1.414; smallest dihedral angle > 1 degree;
  - GradingFactor g (tetgen): the interior / surface edge-length ratio is
    below 1.35 at g = 1 and 2.2-3.8 times that at g = 3 (measured 1.17 and
    3.08 / 1.17 on a finer sphere), the count near the target, the quality
    bound kept; out-of-range g, g with UniformSizing and g with hxt are
    errors naming GradingFactor;
  - a surface on which TetGen 1.5.0 itself crashes (the bunny with one
    vertex moved 143 m away, found by `make fuzz-long`: a failed assertion in
    tetgenmesh::fillcavity aborted the program) is a clean error naming the
    signal, with an empty output; the process lives on and meshes the intact
    bunny afterwards (TetGen runs in a child process);
  - hxt (the surface refined, then HXT and its optimisation pass) meets the
    quality criterion of Documentation/Performance.md ("Tetrahedralisers") on
    the bundled bunny, the slab and a sphere, against TetGen on the same
    surface and target in the same test: smallest dihedral angle at least TetGen's
    and no tet below 5 degrees, largest radius-edge ratio at most TetGen's,
    the count within 25 % of the target, the enclosed volume exact (the
    surface is refined, not moved), and the surface refined to about the
    interior size (no boundary edge longer than 1.35 h);
  - QuadGraph on a uniform mesh of a 5 mm sphere under uniform light: RMS
    relative error against the exact solution phi = C sinh(k r) / r below 12 %
    in every channel (printed), and below the graded mesh's error.

Exits non-zero on failure (unittest).
"""

import os
import sys
import unittest

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import TestPipeline as tp  # noqa: E402  (helpers: surfaces, optics, Messages)

import translucency  # noqa: E402
from vtkmodules.vtkCommonDataModel import vtkPolyData  # noqa: E402
from vtkmodules.vtkFiltersCore import vtkAppendPolyData  # noqa: E402
from vtkmodules.vtkIOGeometry import vtkSTLReader  # noqa: E402
from vtkmodules.vtkIOPLY import vtkPLYReader  # noqa: E402

SOURCE_DIR = os.environ.get("TRANSLUCENCY_SOURCE_DIR",
                            os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))

HAS_HXT = translucency.vtkTetrahedralizeSurface.HasMesher("hxt")
MESHERS = ("tetgen", "hxt") if HAS_HXT else ("tetgen",)
SHELL_FRACTION = 1.0 - 0.9 ** 3  # volume fraction within 0.5 mm of a 5 mm sphere's surface
# The cases on the bunny at 50,000 and 100,000 tets (TetGen runs 3-4 times
# there: about 20 s) run in the slow tier, Python.TestMeshersLarge
# (Testing/CMakeLists.txt), which sets this variable; `make test` runs the
# others.
LARGE = os.environ.get("TRANSLUCENCY_LARGE_MESHES") == "1"


def tetrahedralize(surface, mesher, target=None, uniform=False, quality=None, max_volume=None):
    """(output grid, errors) of vtkTetrahedralizeSurface."""
    tetra = translucency.vtkTetrahedralizeSurface()
    tetra.SetInputData(surface)
    tetra.SetMesher(mesher)
    tetra.SetUniformSizing(uniform)
    if target is not None:
        tetra.SetTargetNumberOfTets(target)
    if max_volume is not None:
        tetra.SetMaxTetVolume(max_volume)
    if quality is not None:
        tetra.SetQuality(quality)
    messages = tp.Messages(tetra)
    try:
        tetra.Update()
    finally:
        messages.remove()
    return tetra.GetOutput(), messages.errors


def quality(grid):
    """(min dihedral per tet in degrees, radius-edge ratio per tet, edge lengths)."""
    p = tp.points_of(grid)[tp.tets_of(grid)]
    faces = ((1, 2, 3), (0, 3, 2), (0, 1, 3), (0, 2, 1))
    normals = []
    for a, b, c in faces:
        n = np.cross(p[:, b] - p[:, a], p[:, c] - p[:, a])
        normals.append(n / np.linalg.norm(n, axis=1)[:, None])
    angles = np.stack([180.0 - np.degrees(np.arccos(np.clip(
        np.einsum("ij,ij->i", normals[i], normals[j]), -1.0, 1.0)))
        for i in range(4) for j in range(i + 1, 4)], axis=1)
    a, b, c = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]
    det = np.einsum("ij,ij->i", a, np.cross(b, c))
    centre = ((a * a).sum(1)[:, None] * np.cross(b, c) + (b * b).sum(1)[:, None] * np.cross(c, a)
              + (c * c).sum(1)[:, None] * np.cross(a, b)) / (2.0 * det[:, None])
    edges = np.stack([np.linalg.norm(p[:, i] - p[:, j], axis=1)
                      for i in range(4) for j in range(i + 1, 4)], axis=1)
    return angles.min(axis=1), np.linalg.norm(centre, axis=1) / edges.min(axis=1), edges.ravel()


def read_bunny():
    reader = vtkPLYReader()
    reader.SetFileName(os.path.join(SOURCE_DIR, "Data", "bunny.ply"))
    reader.Update()
    return reader.GetOutput()


def read_slab():
    reader = vtkSTLReader()
    reader.SetFileName(os.path.join(SOURCE_DIR, "Data", "slab.stl"))
    reader.Update()
    return reader.GetOutput()


def boundary_edge_lengths(grid):
    """Lengths of the edges of the boundary faces (faces of one tet)."""
    tets = tp.tets_of(grid)
    faces = np.sort(np.concatenate([tets[:, [1, 2, 3]], tets[:, [0, 2, 3]], tets[:, [0, 1, 3]],
                                    tets[:, [0, 1, 2]]]), axis=1)
    unique, counts = np.unique(faces, axis=0, return_counts=True)
    boundary = unique[counts == 1]
    edges = np.unique(np.sort(np.concatenate([boundary[:, [0, 1]], boundary[:, [1, 2]],
                                              boundary[:, [0, 2]]]), axis=1), axis=0)
    p = tp.points_of(grid)
    return np.linalg.norm(p[edges[:, 0]] - p[edges[:, 1]], axis=1)


def enclosed_volume(surface):
    p = tp.points_of(surface)
    t = tp.triangles_of(surface)
    return abs(np.einsum("ij,ij->i", p[t[:, 0]], np.cross(p[t[:, 1]], p[t[:, 2]])).sum() / 6.0)


class MesherTest(unittest.TestCase):

    def test_tetgen_crash_is_a_clean_error(self):
        needle = read_bunny()
        x, _, z = needle.GetPoint(422)
        needle.GetPoints().SetPoint(422, x, 143535.0, z)  # was y = 14.16 mm
        grid, errors = tetrahedralize(needle, "tetgen", quality=4, max_volume=1000)
        self.assertEqual(grid.GetNumberOfCells(), 0)
        self.assertEqual(len(errors), 1, errors)
        self.assertIn("TetGen crashed on this surface (signal 6, SIGABRT", errors[0])
        grid, errors = tetrahedralize(read_bunny(), "tetgen", quality=4, max_volume=1000)
        self.assertEqual(errors, [])
        self.assertGreater(grid.GetNumberOfCells(), 1000)

    def test_same_errors_for_bad_surfaces(self):
        tet_coords = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
        tet_faces = [(0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)]
        open_sphere = tp.sphere_surface()
        open_sphere.BuildLinks()
        open_sphere.DeleteCell(0)
        open_sphere.RemoveDeletedCells()
        coords = [(0, 0, 0), (0, 0, 1), (1, 0, 0), (0, 1, 0), (-1, 0, 0), (0, -1, 0)]
        glued = []
        for a, b in ((2, 3), (4, 5)):
            glued += [(0, b, a), (0, a, 1), (0, 1, b), (1, a, b)]
        overlapping = vtkAppendPolyData()
        overlapping.AddInputData(tp.sphere_surface(2.0, (0.0, 0.0, 0.0), 12))
        overlapping.AddInputData(tp.sphere_surface(2.0, (1.0, 0.0, 0.0), 12))
        overlapping.Update()
        infinite = tp.make_polydata([(0, 0, 0), (1, 0, 0), (0, float("inf"), 0), (0, 0, 1)],
                                    tet_faces)
        cases = {
            "open": (open_sphere, "not closed"),
            "non-manifold": (tp.make_polydata(coords, glued), "manifold"),
            "flat": (tp.make_polydata([(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0)],
                                      [(0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)]), "no volume"),
            "degenerate": (tp.make_polydata(tet_coords + [(0.5, 0, 0)],
                                            tet_faces + [(0, 4, 1)]), "degenerate"),
            "self-intersecting": (overlapping.GetOutput(), "intersects itself"),
            "infinite": (infinite, "non-finite"),
            "bad id": (tp.make_polydata(tet_coords, tet_faces[:3] + [(0, 3, 4)]), "out of range"),
            "quads": (tp.cube_polydata(), "triangle"),
            "empty": (vtkPolyData(), "empty"),
        }
        for name, (surface, fragment) in cases.items():
            with self.subTest(case=name):
                messages = {}
                for mesher in MESHERS:
                    grid, errors = tetrahedralize(surface, mesher, target=1000)
                    self.assertEqual(len(errors), 1, "%s: %r" % (mesher, errors))
                    self.assertIn(fragment, errors[0].lower())
                    self.assertEqual(grid.GetNumberOfCells(), 0)
                    # The message without VTK's "ERROR: In file, line / object" header.
                    messages[mesher] = errors[0].split("): ", 1)[-1]
                self.assertEqual(len(set(messages.values())), 1, messages)

    def test_unknown_mesher_and_build_without_gmsh(self):
        grid, errors = tetrahedralize(tp.sphere_surface(), "netgen", target=1000)
        self.assertEqual(len(errors), 1, errors)
        self.assertIn("unknown mesher 'netgen'", errors[0])
        self.assertIn("tetgen or hxt", errors[0])
        # Case-insensitive names.
        grid, errors = tetrahedralize(tp.sphere_surface(radius=3.0, resolution=8), "TetGen",
                                      target=300)
        self.assertEqual(errors, [])
        self.assertGreater(grid.GetNumberOfCells(), 0)
        if not HAS_HXT:
            grid, errors = tetrahedralize(tp.sphere_surface(), "hxt", target=1000)
            self.assertEqual(len(errors), 1, errors)
            self.assertIn("this build has no gmsh", errors[0])

    @unittest.skipUnless(HAS_HXT, "this build has no gmsh")
    def test_hxt_fills_the_bunny(self):
        bunny = read_bunny()
        volume = enclosed_volume(bunny)
        for uniform in (False, True):
            with self.subTest(uniform=uniform):
                grid, errors = tetrahedralize(bunny, "hxt", target=20000, uniform=uniform)
                self.assertEqual(errors, [])
                n = grid.GetNumberOfCells()
                print("hxt %s: %d tets for a target of 20000" % (
                    "uniform" if uniform else "graded", n))
                self.assertLess(abs(n / 20000.0 - 1.0), 0.25)
                volumes = tp.tet_volumes(grid)
                self.assertTrue(np.all(volumes > 0), "VTK orientation")
                bounds = grid.GetBounds()
                diag = np.linalg.norm(np.array(bounds[1::2]) - np.array(bounds[0::2]))
                self.assertGreater(volumes.min(), 1e-14 * diag ** 3, "degenerate tet")
                # Graded: the input triangles are kept, so the volume is exact;
                # uniform re-meshes the surface (a polyhedron inscribed in the
                # same curved surface gmsh interpolates): within 1 %.
                self.assertAlmostEqual(volumes.sum() / volume, 1.0, delta=1e-9 if not uniform else 0.01)
        # A maximum tet volume instead of a count: the edge of the regular tet.
        grid, errors = tetrahedralize(bunny, "hxt", max_volume=volume / 5000.0)
        self.assertEqual(errors, [])
        self.assertGreater(grid.GetNumberOfCells(), 2000)
        self.assertLess(grid.GetNumberOfCells(), 20000)

    def test_target_sizes_honoured_or_explained(self):
        # Issue 33: --target-tets 5000 gave 45,113 tets of the bunny (+802 %)
        # and 30,000 gave 60,412, with no reason. Now each count is within
        # 25 % of the target, or a warning says why (the surface's resolution
        # sets a floor: the coarsest mesh of this surface, checked here by an
        # independent run with no size bound, is itself above the target) and
        # what to do (decimate, or hxt's re-meshing).
        cases = [("tetgen", False, 5000), ("tetgen", False, 30000)]
        if HAS_HXT:
            cases += [("hxt", True, 5000), ("hxt", True, 30000)]
        self.check_target_sizes(cases)

    @unittest.skipUnless(LARGE, "slow tier: Python.TestMeshersLarge")
    def test_large_target_size_honoured(self):
        # Large targets are honoured by TetGen itself (the slow tier's bench
        # goes to 1e6: Apps/BenchMeshers).
        self.check_target_sizes([("tetgen", False, 100000)])

    def check_target_sizes(self, cases):
        bunny = read_bunny()
        coarsest, errors = tetrahedralize(bunny, "tetgen", max_volume=1e9)
        self.assertEqual(errors, [])
        floor = coarsest.GetNumberOfCells()
        print("tetgen's coarsest mesh of the bunny: %d tets" % floor)
        for mesher, uniform, target in cases:
            with self.subTest(mesher=mesher, uniform=uniform, target=target):
                tetra = translucency.vtkTetrahedralizeSurface()
                tetra.SetInputData(bunny)
                tetra.SetMesher(mesher)
                tetra.SetUniformSizing(uniform)
                tetra.SetTargetNumberOfTets(target)
                messages = tp.Messages(tetra)
                try:
                    tetra.Update()
                finally:
                    messages.remove()
                self.assertEqual(messages.errors, [])
                n = tetra.GetOutput().GetNumberOfCells()
                print("%s%s, target %d: %d tets (%+.0f %%)" % (
                    mesher, " uniform" if uniform else "", target, n, 100.0 * (n / target - 1)))
                if abs(n / target - 1.0) <= 0.25:
                    self.assertEqual(messages.warnings, [])
                    continue
                self.assertEqual(len(messages.warnings), 1, messages.warnings)
                warning = messages.warnings[0]
                self.assertIn("TargetNumberOfTets %d: the mesh has %d tets" % (target, n), warning)
                # Only a floor above the target may excuse the miss.
                self.assertEqual(mesher, "tetgen")
                self.assertGreater(floor, 1.25 * target)
                self.assertIn("the coarsest mesh it makes of this surface has %d tets" % floor,
                              warning)
                self.assertIn("3674 triangles", warning)
                self.assertIn("decimate the surface", warning)
                if HAS_HXT:
                    self.assertIn("--mesher hxt --uniform-size", warning)

    def test_uniform_sizing_is_uniform(self):
        sphere = tp.sphere_surface(radius=5.0, resolution=24)
        results = {}
        # hxt graded is not asserted on (uniform sizing is what this checks;
        # TetGen's graded mesh is the contrast): not meshed.
        for mesher, uniform in [(m, u) for m in MESHERS for u in (False, True)
                                if m == "tetgen" or u]:
            grid, errors = tetrahedralize(sphere, mesher, target=30000, uniform=uniform)
            self.assertEqual(errors, [])
            p = tp.points_of(grid)[tp.tets_of(grid)]
            near = (np.linalg.norm(p.mean(axis=1), axis=1) > 4.5).mean()
            _, _, edges = quality(grid)
            cv = edges.std() / edges.mean()
            results[(mesher, uniform)] = (grid.GetNumberOfCells(), near, cv)
            print("%-6s %-7s %6d tets: %.3f of the tets within 0.5 mm of the surface "
                  "(volume fraction %.3f), edge CV %.3f"
                  % (mesher, "uniform" if uniform else "graded", grid.GetNumberOfCells(),
                     near, SHELL_FRACTION, cv))
        for mesher in MESHERS:
            n, near, cv = results[(mesher, True)]
            self.assertLess(abs(near - SHELL_FRACTION), 0.08, mesher)
            self.assertLess(cv, 0.23, mesher)
            self.assertLess(abs(n / 30000.0 - 1.0), 0.2, mesher)
        n, near, cv = results[("tetgen", False)]
        self.assertGreater(near, 0.40, "TetGen's default grading is what uniform sizing removes")
        self.assertGreater(cv, results[("tetgen", True)][2])

    def test_grading_factor(self):
        """GradingFactor g: surface edges g times shorter than interior ones."""
        sphere = tp.sphere_surface(radius=5.0, resolution=24)
        ratios = {}
        for g in (1.0, 3.0):
            tetra = translucency.vtkTetrahedralizeSurface()
            tetra.SetInputData(sphere)
            tetra.SetTargetNumberOfTets(20000)
            tetra.SetGradingFactor(g)
            messages = tp.Messages(tetra)
            tetra.Update()
            messages.remove()
            self.assertEqual(messages.errors, [])
            grid = tetra.GetOutput()
            p = tp.points_of(grid)[tp.tets_of(grid)]
            r = np.linalg.norm(p.mean(axis=1), axis=1)
            dihedral, radius_edge, edges = quality(grid)
            edge = edges.reshape(-1, 6).mean(axis=1)
            ratios[g] = edge[r < 2.5].mean() / edge[r > 4.6].mean()
            above = (radius_edge > 1.414 * (1 + 1e-9)).mean()
            print("tetgen GradingFactor %g: %d tets, interior / surface edge length %.2f, "
                  "%.3f of the tets within 0.5 mm of the surface, %.2f %% above the radius-edge "
                  "bound, min dihedral %.2f deg" % (g, grid.GetNumberOfCells(), ratios[g],
                                                    (r > 4.5).mean(), 100 * above,
                                                    dihedral.min()))
            self.assertLess(abs(grid.GetNumberOfCells() / 20000.0 - 1.0), 0.25)
            self.assertLess(above, 0.01)
            self.assertGreater(dihedral.min(), 1.0)
        # g = 1 is uniform (within the transition's discreteness); g = 3 gives
        # about 3 times the uniform ratio.
        self.assertLess(ratios[1.0], 1.35)
        self.assertGreater(ratios[3.0] / ratios[1.0], 2.2)
        self.assertLess(ratios[3.0] / ratios[1.0], 3.8)

    def test_grading_factor_errors(self):
        sphere = tp.sphere_surface(radius=5.0, resolution=12)
        cases = [(0.5, "tetgen", False, "out of range"), (9.0, "tetgen", False, "out of range"),
                 (float("nan"), "tetgen", False, "out of range"),
                 (2.0, "tetgen", True, "UniformSizing")]
        if HAS_HXT:
            cases.append((2.0, "hxt", False, "tetgen mesher only"))
        for g, mesher, uniform, fragment in cases:
            with self.subTest(g=g, mesher=mesher, uniform=uniform):
                tetra = translucency.vtkTetrahedralizeSurface()
                tetra.SetInputData(sphere)
                tetra.SetMesher(mesher)
                tetra.SetUniformSizing(uniform)
                tetra.SetGradingFactor(g)
                messages = tp.Messages(tetra)
                tetra.Update()
                messages.remove()
                self.assertEqual(tetra.GetOutput().GetNumberOfCells(), 0)
                self.assertTrue(any(fragment in e and "GradingFactor" in e
                                    for e in messages.errors), messages.errors)

    def test_tetgen_quality_bound(self):
        sphere = tp.sphere_surface(radius=5.0, resolution=24)
        largest = {}
        for bound in (1.414, 2.0):
            for uniform in (False, True):
                grid, errors = tetrahedralize(sphere, "tetgen", target=20000, uniform=uniform,
                                              quality=bound)
                self.assertEqual(errors, [])
                dihedral, ratio, _ = quality(grid)
                above = (ratio > bound * (1 + 1e-9)).mean()
                print("tetgen -q%g %s: min dihedral %.2f deg, radius-edge max %.2f, %.3f %% above "
                      "the bound" % (bound, "uniform" if uniform else "graded", dihedral.min(),
                                     ratio.max(), 100 * above))
                self.assertLess(above, 0.01)
                self.assertGreater(dihedral.min(), 1.0)
                largest[(bound, uniform)] = (ratio > 1.414).mean()
        # The bound is what TetGen refines to: the looser one leaves more tets above 1.414.
        for uniform in (False, True):
            self.assertLess(largest[(1.414, uniform)], largest[(2.0, uniform)])

    @unittest.skipUnless(HAS_HXT, "this build has no gmsh")
    def test_hxt_meets_the_quality_criterion(self):
        self.check_hxt_quality((("slab", read_slab(), 20000),
                                ("sphere", tp.sphere_surface(radius=5.0, resolution=24), 20000)))

    @unittest.skipUnless(HAS_HXT and LARGE, "slow tier: Python.TestMeshersLarge (and gmsh)")
    def test_hxt_meets_the_quality_criterion_on_the_bunny(self):
        self.check_hxt_quality((("bunny", read_bunny(), 50000),))

    def check_hxt_quality(self, cases):
        for name, surface, target in cases:
            with self.subTest(surface=name):
                tetra = translucency.vtkTetrahedralizeSurface()
                tetra.SetMesher("hxt")  # with its defaults: the surface refined, optimised
                tetra.SetInputData(surface)
                tetra.SetTargetNumberOfTets(target)
                messages = tp.Messages(tetra)
                try:
                    tetra.Update()
                finally:
                    messages.remove()
                self.assertEqual(messages.errors + messages.warnings, [])
                grid = tetra.GetOutput()
                reference, errors = tetrahedralize(surface, "tetgen", target=target)
                self.assertEqual(errors, [])
                dihedral, ratio, _ = quality(grid)
                tetgen_dihedral, tetgen_ratio, _ = quality(reference)
                n = grid.GetNumberOfCells()
                # The interior edge length of the count model (N = 5.5 V / h^3).
                h = (5.5 * enclosed_volume(surface) / n) ** (1.0 / 3.0)
                edges = boundary_edge_lengths(grid) / h
                print("%s, target %d: %s %d tets, min dihedral %.2f deg, %d tets "
                      "below 5 deg, max radius-edge %.2f, boundary edges median %.2f h, "
                      "99th percentile %.2f h; tetgen %d tets, %.2f deg, %d below 5 deg, %.2f"
                      % (name, target, tetra.GetMesher(), n, dihedral.min(),
                         (dihedral < 5.0).sum(), ratio.max(), np.median(edges),
                         np.percentile(edges, 99), reference.GetNumberOfCells(),
                         tetgen_dihedral.min(), (tetgen_dihedral < 5.0).sum(), tetgen_ratio.max()))
                # The criterion: dihedral angles at least TetGen's and no sliver
                # below 5 degrees; radius-edge ratios within the largest of
                # TetGen's graded meshes of the bunny (7.47 at 1M tets).
                self.assertGreaterEqual(dihedral.min(), tetgen_dihedral.min())
                self.assertGreaterEqual(dihedral.min(), 5.0)
                self.assertLessEqual(ratio.max(), 7.5)
                self.assertLess(abs(n / target - 1.0), 0.25)
                self.assertAlmostEqual(tp.tet_volumes(grid).sum() / enclosed_volume(surface),
                                       1.0, delta=1e-9)
                # The surface refined to about h (bisection leaves edges of
                # 0.68-1.35 h; a flat tet dropped on a planar part exposes
                # the other diagonal of its quad).
                self.assertLess(np.median(edges), 1.1)
                self.assertLess(np.percentile(edges, 99), 1.6)

    @unittest.skipUnless(HAS_HXT, "this build has no gmsh")
    def test_hxt_refuses_several_parts_and_meshes_on(self):
        # HXT failed on two disjoint spheres ("HXT 3D mesh failed") and gmsh
        # 4.8.4 then stayed locked: every later hxt run in the process gave
        # no tets. Now the parts are counted first (a clear error), and a
        # failed gmsh is loaded anew before the next run.
        both = vtkAppendPolyData()
        both.AddInputData(tp.sphere_surface(2.0, (0.0, 0.0, 0.0), 16))
        both.AddInputData(tp.sphere_surface(3.0, (0.0, 8.0, 0.0), 16))
        both.Update()
        grid, errors = tetrahedralize(both.GetOutput(), "hxt", target=3000)
        self.assertEqual(grid.GetNumberOfCells(), 0)
        self.assertEqual(len(errors), 1, errors)
        self.assertIn("this one has 2 separate parts: use the tetgen mesher", errors[0])
        grid, errors = tetrahedralize(tp.sphere_surface(), "hxt", target=3000)
        self.assertEqual(errors, [])
        self.assertGreater(grid.GetNumberOfCells(), 2000)
        grid, errors = tetrahedralize(both.GetOutput(), "tetgen", target=3000)
        self.assertEqual(errors, [])

    def test_quadgraph_on_a_uniform_mesh(self):
        """QuadGraph against the exact solution in a 5 mm sphere, uniform light."""
        eta, radius, irradiance = 1.3, 5.0, 1.0
        mu_a = np.array([0.01, 0.02, 0.04])
        mu_s = np.array([1.0, 1.5, 2.0])
        q = irradiance * tp.hemispherical_transmittance(eta)
        kappa = 1.0 / (3.0 * (mu_a + mu_s))
        k = np.sqrt(mu_a / kappa)
        a = tp.mismatch_a(eta)
        # phi = C sinh(k r) / r; Robin: phi + 2 A kappa dphi/dr = 4 q / (1 - Fdr) at r = R.
        f_r = np.sinh(k * radius) / radius
        df_r = k * np.cosh(k * radius) / radius - np.sinh(k * radius) / radius ** 2
        c = 4.0 * q / (1.0 - tp.fdr(eta)) / (f_r + 2.0 * a * kappa * df_r)
        rms, two_point = {}, {}
        for uniform in (True, False):
            pipe = tp.Pipeline(tp.sphere_surface(radius=radius, resolution=24), target_tets=30000,
                               material="", absorption=tuple(mu_a), scattering=tuple(mu_s),
                               eta=eta)
            pipe.tetra.SetUniformSizing(uniform)
            pipe.irradiance.SetUniformLightIrradiance(irradiance)
            pipe.irradiance.SetUniformLightSamples(0)
            pipe.solve.SetSolver(pipe.solve.SOLVER_QUADGRAPH)
            pipe.solve.SetRelTol(1e-6)
            for weights in ("paper eq. 5", "two-point (not the paper's)"):
                pipe.solve.SetQuadGraphTwoPointFlux(weights != "paper eq. 5")
                pipe.update(self, pipe.solve)
                grid = pipe.solve.GetOutput()
                r = np.linalg.norm(tp.points_of(grid), axis=1)[:, None]
                exact = c * np.sinh(k * r) / r
                phi = tp.array(grid, "Fluence")
                error = np.sqrt(np.mean(((phi - exact) / exact) ** 2, axis=0))
                (rms if weights == "paper eq. 5" else two_point)[uniform] = error
                print("quadgraph, %s weights, %s TetGen mesh, %d tets: RMS error vs the exact "
                      "sphere solution R %.2f %%, G %.2f %%, B %.2f %%" % (
                          weights, "uniform" if uniform else "graded", grid.GetNumberOfCells(),
                          *(100 * error)))
        self.assertTrue(np.all(rms[True] < 0.12), rms[True])
        self.assertTrue(np.all(rms[True] < rms[False]), (rms[True], rms[False]))
        # The opt-in two-point weights conserve light, so the graded surface
        # layer no longer manufactures it: better than eq. 5 on both meshes.
        # Measured: 0.3-1.6 % against 2.4-16 % (uniform and graded alike).
        for uniform in (True, False):
            self.assertTrue(np.all(two_point[uniform] < rms[uniform] / 3), (two_point, rms))
            self.assertTrue(np.all(two_point[uniform] < 0.03), two_point)


class CommandLineTest(unittest.TestCase):

    def run_cli(self, *args):
        import subprocess
        from cli_under_test import find_cli
        return subprocess.run([find_cli("TestMeshers"), *args], capture_output=True, text=True,
                              timeout=300)

    def test_mesher_options_and_the_quadgraph_warning(self):
        import tempfile
        from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter
        with tempfile.TemporaryDirectory() as directory:
            path = os.path.join(directory, "sphere.vtp")
            writer = vtkXMLPolyDataWriter()
            writer.SetInputData(tp.sphere_surface(radius=4.0, resolution=12))
            writer.SetFileName(path)
            writer.Write()
            result = self.run_cli("render", "--mesh", path, "--mesher", "netgen")
            self.assertNotEqual(result.returncode, 0)
            self.assertIn("--mesher: unknown mesher 'netgen': use tetgen or hxt", result.stderr)
            for mesher in MESHERS:
                result = self.run_cli("render", "--mesh", path, "--target-tets", "1500",
                                      "--mesher", mesher, "--uniform-size")
                self.assertEqual(result.returncode, 0, result.stderr)
            warning = "quadgraph on a graded mesh"
            for extra, warned in (([], True), (["--uniform-size"], False)):
                result = self.run_cli("compare", "--mesh", path, "--target-tets", "1500",
                                      "--solvers", "divergence,quadgraph", "--reference",
                                      "divergence", "--output", os.path.join(directory, "out"),
                                      "--no-png", *extra)
                self.assertEqual(result.returncode, 0, result.stderr)
                (self.assertIn if warned else self.assertNotIn)(warning, result.stderr)
            result = self.run_cli("render", "--mesh", path, "--target-tets", "1500",
                                  "--two-point-flux")
            self.assertEqual(result.returncode, 2, result.stderr)
            self.assertIn("--two-point-flux applies to --solver quadgraph only", result.stderr)
            result = self.run_cli("render", "--mesh", path, "--target-tets", "1500",
                                  "--solver", "quadgraph", "--two-point-flux")
            self.assertEqual(result.returncode, 0, result.stderr)


if __name__ == "__main__":
    unittest.main()
