#!/usr/bin/env python3
"""Tests of the `translucency` command line (Apps/translucency.cxx and Apps/*Command.cxx).

How to run (from a build tree; ctest sets the variables itself):

    TRANSLUCENCY_CLI=<build>/bin/translucency \\
    PYTHONPATH=<build>/lib/python3.11/site-packages /usr/bin/python3 TestCommandLine.py

1. `--help` documents every option of the issue.
2. `render` on a small closed sphere written here (.vtp and .stl; no --png, so
   no X display is needed) writes PREFIX.vtu and PREFIX.vtp and a JSON file
   whose counts match the files and whose statistics (stage times, solver,
   iterations and residual per channel) are complete and consistent.
3. The written .vtu is itself a valid --mesh input (no new tetrahedralization);
   --material accepts a preset or a JSON file, and the values reach the output;
   --max-tet-volume bounds every tet's volume; with mu_a = 0 and an unoccluded
   uniform light the fluence is 4 q / (1 - Fdr) (TransCut, eq. 1-2, through
   the command line).
4. Bad input (missing file, open or self-intersecting surface, unknown
   material, malformed --light, unknown option, bad material file) exits
   non-zero with a message naming the problem, and never replaces an existing
   output file.
5. --cut-plane, --cut-stroke and --paint: a plane cut through the centre of
   the sphere keeps exactly the tets with a vertex on the kept side (checked
   against the input .vtu through vtkOriginalCellIds / vtkOriginalPointIds);
   --paint gives every tet the Gaussian blend of SET recomputed here (changed
   near the stroke, bit for bit unchanged far away); bad edit files fail
   naming the file and the field; the JSON report has "cut" and "paint".

Exits non-zero on failure (unittest).
"""

import json
import os
import subprocess
import sys
import tempfile
import unittest

import numpy as np

from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonTransforms import vtkTransform
from vtkmodules.vtkFiltersCore import vtkAppendPolyData, vtkCleanPolyData, vtkTriangleFilter
from vtkmodules.vtkFiltersGeneral import vtkTransformPolyDataFilter
from vtkmodules.vtkFiltersSources import vtkSphereSource
from vtkmodules.vtkIOGeometry import vtkSTLWriter
from vtkmodules.vtkIOXML import (
    vtkXMLPolyDataReader,
    vtkXMLPolyDataWriter,
    vtkXMLUnstructuredGridReader,
)


from cli_under_test import find_cli  # noqa: E402

CLI = find_cli("TestCommandLine")
OPTIONS = ("--mesh", "--target-tets", "--max-tet-volume", "--material", "--material-ids",
           "--light", "--output",
           "--png", "--slice-png", "--json", "--paint", "--cut-plane", "--cut-stroke")
STAGES = ("read", "tetrahedralize", "coefficients", "irradiance", "topology", "assembly", "solve",
          "radiance", "write")


def fdr(eta):
    return -1.440 / eta ** 2 + 0.710 / eta + 0.668 + 0.0636 * eta


def hemispherical_transmittance(eta):
    """2 int_0^1 F_t(mu) mu dmu, exact Fresnel equations (angle form)."""
    x, w = np.polynomial.legendre.leggauss(200)
    mu = 0.5 * (x + 1.0)
    ti = np.arccos(mu)
    tt = np.arcsin(np.sin(ti) / eta)
    r = 0.5 * (np.sin(ti - tt) ** 2 / np.sin(ti + tt) ** 2
               + np.tan(ti - tt) ** 2 / np.tan(ti + tt) ** 2)
    return 2.0 * np.sum(0.5 * w * (1.0 - r) * mu)


def sphere(radius=4.0, resolution=14):
    source = vtkSphereSource()
    source.SetRadius(radius)
    source.SetThetaResolution(resolution)
    source.SetPhiResolution(resolution)
    triangles = vtkTriangleFilter()
    triangles.SetInputConnection(source.GetOutputPort())
    clean = vtkCleanPolyData()
    clean.SetInputConnection(triangles.GetOutputPort())
    clean.Update()
    return clean.GetOutput()


def write_vtp(poly, path):
    writer = vtkXMLPolyDataWriter()
    writer.SetInputData(poly)
    writer.SetFileName(path)
    assert writer.Write() == 1, path


def read(path):
    reader = vtkXMLUnstructuredGridReader() if path.endswith(".vtu") else vtkXMLPolyDataReader()
    reader.SetFileName(path)
    reader.Update()
    return reader.GetOutput()


def cell_array(data, name):
    a = data.GetCellData().GetArray(name)
    assert a is not None, "no cell array %s" % name
    return vtk_to_numpy(a)


def point_array(data, name):
    a = data.GetPointData().GetArray(name)
    assert a is not None, "no point array %s" % name
    return vtk_to_numpy(a)


def tet_volumes(grid):
    p = vtk_to_numpy(grid.GetPoints().GetData()).astype(float)
    t = vtk_to_numpy(grid.GetCells().GetConnectivityArray()).reshape(-1, 4)
    a, b, c, d = (p[t[:, k]] for k in range(4))
    return np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) / 6.0


class CommandLineTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        cls._tmp = tempfile.TemporaryDirectory(prefix="translucency-cli-")
        cls.dir = cls._tmp.name
        cls.sphere_vtp = os.path.join(cls.dir, "sphere.vtp")
        write_vtp(sphere(), cls.sphere_vtp)
        cls.sphere_stl = os.path.join(cls.dir, "sphere.stl")
        writer = vtkSTLWriter()
        writer.SetInputData(sphere())
        writer.SetFileName(cls.sphere_stl)
        writer.Write()
        # An open surface: the sphere without two triangles.
        poly = sphere()
        poly.BuildLinks()
        poly.DeleteCell(0)
        poly.DeleteCell(30)
        poly.RemoveDeletedCells()
        cls.open_vtp = os.path.join(cls.dir, "open.vtp")
        write_vtp(poly, cls.open_vtp)
        # Two overlapping spheres: closed, manifold, self-intersecting.
        both = vtkAppendPolyData()
        both.AddInputData(sphere(2.0, 10))
        shifted = vtkTransformPolyDataFilter()
        transform = vtkTransform()
        transform.Translate(1.0, 0.0, 0.0)
        shifted.SetTransform(transform)
        shifted.SetInputData(sphere(2.0, 10))
        shifted.Update()
        both.AddInputData(shifted.GetOutput())
        both.Update()
        cls.crossing_vtp = os.path.join(cls.dir, "crossing.vtp")
        write_vtp(both.GetOutput(), cls.crossing_vtp)
        # One successful run shared by several tests.
        cls.prefix = os.path.join(cls.dir, "out", "sphere")
        cls.json_path = os.path.join(cls.dir, "out", "sphere.json")
        cls.first = cls.run_cli("render", "--mesh", cls.sphere_vtp, "--target-tets", "2000",
                                "--output", cls.prefix, "--json", cls.json_path)

    @classmethod
    def tearDownClass(cls):
        cls._tmp.cleanup()

    @staticmethod
    def run_cli(*args):
        return subprocess.run([CLI] + list(args), capture_output=True, text=True, timeout=300)

    def assertSucceeded(self, result):
        self.assertEqual(result.returncode, 0,
                         "translucency failed:\nstdout:\n%s\nstderr:\n%s"
                         % (result.stdout, result.stderr))

    def assertFailsNaming(self, result, *fragments):
        self.assertNotEqual(result.returncode, 0, "expected a failure:\n%s" % result.stdout)
        self.assertGreater(result.returncode, 0, "killed by a signal (crash?): %d"
                           % result.returncode)
        for fragment in fragments:
            self.assertIn(fragment.lower(), result.stderr.lower(),
                          "the message does not name %r:\n%s" % (fragment, result.stderr))
        self.assertIn("translucency:", result.stderr)
        # Only the message that names the problem: no VTK pipeline chatter.
        self.assertNotIn("returned failure", result.stderr)
        self.assertNotIn("\x1b[", result.stderr)

    # ---------------------------------------------------------------- help

    def test_help(self):
        result = self.run_cli("--help")
        self.assertSucceeded(result)
        for option in OPTIONS:
            self.assertRegex(result.stdout, r"(?m)^\s+%s\b" % option,
                             "--help does not document %s" % option)
        self.assertIn("render", result.stdout)
        # `render --help` prints the same text.
        self.assertEqual(self.run_cli("render", "--help").stdout, result.stdout)

    # -------------------------------------------------------------- render

    def test_render_writes_consistent_outputs(self):
        self.assertSucceeded(self.first)
        grid = read(self.prefix + ".vtu")
        surface = read(self.prefix + ".vtp")
        with open(self.json_path) as f:
            stats = json.load(f)
        self.assertEqual(stats["points"], grid.GetNumberOfPoints())
        self.assertEqual(stats["tets"], grid.GetNumberOfCells())
        self.assertEqual(stats["boundary_points"], surface.GetNumberOfPoints())
        # A small target: TetGen's count is only roughly controlled here (the
        # demo test checks 25 % at 200000 tets).
        self.assertTrue(1000 <= stats["tets"] <= 4000, stats["tets"])
        self.assertLess(stats["boundary_points"], stats["points"])
        self.assertEqual(stats["solver"], "divergence")
        self.assertIsInstance(stats.get("linear_solver"), str)
        for channel in ("R", "G", "B"):
            entry = stats["channels"][channel]
            self.assertIsInstance(entry["iterations"], int)
            self.assertGreater(entry["iterations"], 0)
            self.assertGreaterEqual(entry["relative_residual"], 0.0)
            self.assertLessEqual(entry["relative_residual"], 1e-6)  # the default --rel-tol
            self.assertTrue(entry["converged"])
        times = stats["times_ms"]
        for stage in STAGES:
            self.assertIn(stage, times)
            self.assertGreaterEqual(times[stage], 0.0)
        self.assertAlmostEqual(times["total"], sum(v for k, v in times.items() if k != "total"),
                               delta=1e-6 * times["total"] + 1e-9)
        # The same figures on stdout.
        self.assertIn("%d tets" % stats["tets"], self.first.stdout)
        # The files hold the data contract.
        for name, components in (("AbsorptionCoefficient", 3), ("ReducedScatteringCoefficient", 3),
                                 ("RefractiveIndex", 1)):
            self.assertEqual(grid.GetCellData().GetArray(name).GetNumberOfComponents(), components)
        self.assertIsNotNone(grid.GetCellData().GetArray("vtkOriginalCellIds"))
        for name in ("Irradiance", "Fluence"):
            self.assertEqual(grid.GetPointData().GetArray(name).GetNumberOfComponents(), 3)
        for name in ("Radiance", "Irradiance", "Fluence"):
            self.assertEqual(surface.GetPointData().GetArray(name).GetNumberOfComponents(), 3)
        self.assertTrue(np.all(point_array(grid, "Fluence") > 0))
        # Default material: marble (Documentation/Materials.md, "Measured presets").
        self.assertTrue(np.allclose(cell_array(grid, "AbsorptionCoefficient"),
                                    [0.0021, 0.0041, 0.0071], rtol=1e-12))
        # No temporary files left behind.
        self.assertEqual(sorted(os.listdir(os.path.dirname(self.prefix))),
                         ["sphere.json", "sphere.vtp", "sphere.vtu"])

    def test_stl_input(self):
        prefix = os.path.join(self.dir, "stl")
        result = self.run_cli("render", "--mesh", self.sphere_stl, "--target-tets", "1000",
                              "--output", prefix)
        self.assertSucceeded(result)
        # STL repeats the points of every triangle: merged, the sphere has
        # 2 + 14 * 12 points, all of them on the boundary.
        surface = read(prefix + ".vtp")
        self.assertGreaterEqual(surface.GetNumberOfPoints(), 2 + 14 * 12)

    def test_vtu_input(self):
        self.assertSucceeded(self.first)
        source = read(self.prefix + ".vtu")
        prefix = os.path.join(self.dir, "again")
        json_path = prefix + ".json"
        result = self.run_cli("render", "--mesh", self.prefix + ".vtu", "--output", prefix,
                              "--json", json_path)
        self.assertSucceeded(result)
        with open(json_path) as f:
            stats = json.load(f)
        self.assertNotIn("tetrahedralize", stats["times_ms"])
        grid = read(prefix + ".vtu")
        self.assertEqual(grid.GetNumberOfCells(), source.GetNumberOfCells())
        self.assertEqual(grid.GetNumberOfPoints(), source.GetNumberOfPoints())
        # Same mesh, same lights, same material kept from the file: same fluence.
        self.assertTrue(np.allclose(point_array(grid, "Fluence"), point_array(source, "Fluence"),
                                    rtol=1e-4, atol=1e-6))

        # A preset given on the command line replaces the file's coefficients.
        result = self.run_cli("render", "--mesh", self.prefix + ".vtu", "--material", "skin1",
                              "--output", prefix)
        self.assertSucceeded(result)
        grid = read(prefix + ".vtu")
        self.assertTrue(np.allclose(cell_array(grid, "AbsorptionCoefficient"), [0.032, 0.17, 0.48],
                                    rtol=1e-12))
        self.assertTrue(np.allclose(cell_array(grid, "ReducedScatteringCoefficient"),
                                    [0.74, 0.88, 1.01], rtol=1e-12))

    def test_material_file_and_uniform_light(self):
        # mu_a = 0 and an unoccluded uniform light: q = E * hemispherical F_t
        # on the boundary and phi = 4 q / (1 - Fdr) everywhere.
        eta = 1.45
        material = os.path.join(self.dir, "clear.json")
        with open(material, "w") as f:
            json.dump({"absorption": [0, 0, 0], "reduced_scattering": [0.8, 1.2, 2.0],
                       "refractive_index": eta}, f)
        prefix = os.path.join(self.dir, "clear")
        result = self.run_cli("render", "--mesh", self.sphere_vtp, "--target-tets", "1500",
                              "--material", material, "--light", "uniform:0.25",
                              # the fit's Robin condition, whose closed form this is
                              "--collimated", "surface",
                              "--uniform-samples", "0", "--rel-tol", "1e-12", "--output", prefix)
        self.assertSucceeded(result)
        grid = read(prefix + ".vtu")
        self.assertTrue(np.all(cell_array(grid, "AbsorptionCoefficient") == 0.0))
        self.assertTrue(np.allclose(cell_array(grid, "ReducedScatteringCoefficient"),
                                    [0.8, 1.2, 2.0], rtol=1e-12))
        self.assertTrue(np.allclose(cell_array(grid, "RefractiveIndex"), eta, rtol=1e-12))
        q = 0.25 * hemispherical_transmittance(eta)
        surface = read(prefix + ".vtp")
        self.assertTrue(np.allclose(point_array(surface, "Irradiance"), q, rtol=1e-9, atol=0))
        self.assertTrue(np.allclose(point_array(grid, "Fluence"), 4 * q / (1 - fdr(eta)),
                                    rtol=1e-6, atol=0))

    def test_max_tet_volume(self):
        prefix = os.path.join(self.dir, "bounded")
        result = self.run_cli("render", "--mesh", self.sphere_vtp, "--max-tet-volume", "0.5",
                              "--output", prefix)
        self.assertSucceeded(result)
        volumes = np.abs(tet_volumes(read(prefix + ".vtu")))
        self.assertLessEqual(volumes.max(), 0.5 * (1 + 1e-9))
        # The sphere's volume (about 250 mm^3) needs more than 500 tets of 0.5 mm^3.
        self.assertGreater(len(volumes), 500)

    def test_lights_and_list(self):
        prefix = os.path.join(self.dir, "lights")
        json_path = prefix + ".json"
        result = self.run_cli("render", "--mesh", self.sphere_vtp, "--target-tets", "1000",
                              "--light", "point:0,0,20:400", "--light", "directional:1,0,0",
                              "--no-shadows", "--output", prefix, "--json", json_path)
        self.assertSucceeded(result)
        q = point_array(read(prefix + ".vtp"), "Irradiance")
        self.assertTrue(np.all(q >= 0) and np.any(q > 0))
        listing = self.run_cli("render", "--list-materials")
        self.assertSucceeded(listing)
        for name in ("marble", "skin1", "ketchup", "wholemilk"):
            self.assertIn(name, listing.stdout)

    # ----------------------------------------------------------- bad input

    def test_missing_file(self):
        missing = os.path.join(self.dir, "no-such-file.ply")
        self.assertFailsNaming(self.run_cli("render", "--mesh", missing), missing)
        self.assertFailsNaming(self.run_cli("render", "--target-tets", "100"), "--mesh")

    def test_open_surface(self):
        self.assertFailsNaming(self.run_cli("render", "--mesh", self.open_vtp,
                                            "--target-tets", "500"),
                               "not closed", "open.vtp")

    def test_self_intersecting_surface(self):
        self.assertFailsNaming(self.run_cli("render", "--mesh", self.crossing_vtp,
                                            "--target-tets", "500"),
                               "intersects itself", "crossing.vtp")

    def test_unknown_material(self):
        result = self.run_cli("render", "--mesh", self.sphere_vtp, "--target-tets", "500",
                              "--material", "unobtainium")
        self.assertFailsNaming(result, "unobtainium", "marble", "skin1", "ketchup", "wholemilk")

    def test_bad_material_file(self):
        bad = os.path.join(self.dir, "bad-material.json")
        with open(bad, "w") as f:
            json.dump({"absorption": [0.1, 0.1], "reduced_scattering": [1, 1, 1]}, f)
        self.assertFailsNaming(self.run_cli("render", "--mesh", self.sphere_vtp, "--target-tets",
                                            "500", "--material", bad), "absorption")
        with open(bad, "w") as f:
            f.write("{ not json")
        self.assertFailsNaming(self.run_cli("render", "--mesh", self.sphere_vtp, "--target-tets",
                                            "500", "--material", bad), "not valid JSON")
        with open(bad, "w") as f:
            json.dump({"absorption": [0.1, -1, 0.1], "reduced_scattering": [1, 1, 1]}, f)
        self.assertFailsNaming(self.run_cli("render", "--mesh", self.sphere_vtp, "--target-tets",
                                            "500", "--material", bad), "AbsorptionCoefficient", "-1")
        for content, fragment in (({"preset": 3}, "preset"), ([1, 2, 3], "object"),
                                  ({"absorption": [0, 0, 0], "reduced_scattering": [1, 1, 1],
                                    "refractive_index": "high"}, "refractive_index")):
            with open(bad, "w") as f:
                json.dump(content, f)
            self.assertFailsNaming(self.run_cli("render", "--mesh", self.sphere_vtp,
                                                "--target-tets", "500", "--material", bad),
                                   "bad-material.json", fragment)
        # A preset named in the file.
        with open(bad, "w") as f:
            json.dump({"preset": "ketchup"}, f)
        prefix = os.path.join(self.dir, "ketchup")
        self.assertSucceeded(self.run_cli("render", "--mesh", self.sphere_vtp, "--target-tets",
                                          "500", "--material", bad, "--output", prefix))
        self.assertTrue(np.allclose(cell_array(read(prefix + ".vtu"), "AbsorptionCoefficient"),
                                    [0.061, 0.97, 1.45], rtol=1e-12))

    def test_malformed_light(self):
        cases = {
            "directional:0,-1": ("--light", "three"),
            "directional:0,x,1": ("--light", "'x'"),
            "laser:1,2,3": ("light type", "laser"),
            "directional:0,0,0": ("--light", "zero"),
            "point:1,2,3:-4": ("--light", "power"),
            "uniform:1:2": ("--light", "uniform"),
            "": ("--light",),
        }
        for spec, fragments in cases.items():
            with self.subTest(light=spec):
                result = self.run_cli("render", "--mesh", self.sphere_vtp, "--light", spec)
                self.assertFailsNaming(result, *fragments)

    def test_unknown_option(self):
        result = self.run_cli("render", "--mesh", self.sphere_vtp, "--frobnicate")
        self.assertFailsNaming(result, "--frobnicate")
        self.assertFailsNaming(self.run_cli("paint"), "paint")
        self.assertFailsNaming(self.run_cli("render", "--target-tets", "many"), "many")

    def test_failure_keeps_existing_outputs(self):
        prefix = os.path.join(self.dir, "keep")
        sentinel = b"sentinel: must survive a failed run\n"
        with open(prefix + ".vtu", "wb") as f:
            f.write(sentinel)
        result = self.run_cli("render", "--mesh", self.sphere_vtp, "--target-tets", "500",
                              "--material", "unobtainium", "--output", prefix,
                              "--json", prefix + ".json")
        self.assertFailsNaming(result, "unobtainium")
        with open(prefix + ".vtu", "rb") as f:
            self.assertEqual(f.read(), sentinel)
        self.assertFalse(os.path.exists(prefix + ".vtp"))
        self.assertFalse(os.path.exists(prefix + ".json"))
        self.assertEqual(sorted(p for p in os.listdir(self.dir) if p.startswith("keep")),
                         ["keep.vtu"])

    # ------------------------------------------------------- cut and paint

    def write_json(self, name, content):
        path = os.path.join(self.dir, name)
        with open(path, "w") as f:
            if isinstance(content, str):
                f.write(content)
            else:
                json.dump(content, f)
        return path

    def test_plane_cut(self):
        self.assertSucceeded(self.first)
        source = read(self.prefix + ".vtu")
        origin, normal = np.array([0.1, 0.2, -0.1]), np.array([1.0, 0.5, 0.25])
        prefix = os.path.join(self.dir, "planecut")
        result = self.run_cli("render", "--mesh", self.prefix + ".vtu", "--cut-plane",
                              ",".join(str(v) for v in list(origin) + list(normal)),
                              "--output", prefix, "--json", prefix + ".json")
        self.assertSucceeded(result)
        cut = read(prefix + ".vtu")
        p0 = vtk_to_numpy(source.GetPoints().GetData()).astype(float)
        t0 = vtk_to_numpy(source.GetCells().GetConnectivityArray()).reshape(-1, 4)
        side0 = (p0 - origin) @ normal  # > 0: the removed side (the normal points to it)
        expected = np.nonzero((side0[t0] <= 0).any(axis=1))[0]
        cell_ids = cell_array(cut, "vtkOriginalCellIds")
        point_ids = point_array(cut, "vtkOriginalPointIds")
        self.assertEqual(sorted(cell_ids.tolist()), expected.tolist())
        # The output tets are the original ones, vertex for vertex.
        t1 = vtk_to_numpy(cut.GetCells().GetConnectivityArray()).reshape(-1, 4)
        self.assertTrue(np.array_equal(point_ids[t1], t0[cell_ids]))
        # Points of the kept side stay; moved points stay on the removed side.
        p1 = vtk_to_numpy(cut.GetPoints().GetData()).astype(float)
        kept = side0[point_ids] <= 0
        self.assertTrue(np.array_equal(p1[kept], p0[point_ids[kept]]))
        self.assertTrue(np.all((p1[~kept] - origin) @ normal >= -1e-9))
        self.assertTrue(np.all(tet_volumes(cut) > 0))
        self.assertTrue(np.all(np.isfinite(point_array(cut, "Fluence"))))
        with open(prefix + ".json") as f:
            stats = json.load(f)
        self.assertEqual(stats["tets"], len(expected))
        self.assertEqual(stats["cut"]["tets_kept"], len(expected))
        self.assertGreaterEqual(stats["cut"]["vertices_moved"], 0)
        self.assertGreaterEqual(stats["cut"]["blocked"], 0)
        self.assertGreaterEqual(stats["cut"]["ms"], 0)
        self.assertIn("cut", stats["times_ms"])
        self.assertNotIn("paint", stats)
        # A plane beyond the sphere removes everything: an error, not an empty result.
        self.assertFailsNaming(self.run_cli("render", "--mesh", self.prefix + ".vtu",
                                            "--cut-plane", "-10,0,0,1,0,0"),
                               "--cut-plane", "whole mesh")
        self.assertFailsNaming(self.run_cli("render", "--mesh", self.prefix + ".vtu",
                                            "--cut-plane", "0,0,0,1,0"), "--cut-plane", "six")

    def test_stroke_cut(self):
        self.assertSucceeded(self.first)
        counts = []
        for inside_out in (False, True):
            stroke = self.write_json("stroke.json", {"points": [[-10, 0.3, 0], [10, 0.3, 0]],
                                                     "view_direction": [0, 0, -1],
                                                     "inside_out": inside_out})
            path = os.path.join(self.dir, "stroke-%d.json" % inside_out)
            self.assertSucceeded(self.run_cli("render", "--mesh", self.prefix + ".vtu",
                                              "--cut-stroke", stroke, "--json", path))
            with open(path) as f:
                counts.append(json.load(f)["cut"]["tets_kept"])
        with open(self.json_path) as f:
            total = json.load(f)["tets"]
        # Each side keeps part of the mesh; together they cover it (a tet
        # straddling the cutting surface is kept by both).
        self.assertLess(max(counts), total)
        self.assertGreaterEqual(sum(counts), total)

    def test_paint(self):
        self.assertSucceeded(self.first)
        source = read(self.prefix + ".vtu")
        p = vtk_to_numpy(source.GetPoints().GetData()).astype(float)
        t = vtk_to_numpy(source.GetCells().GetConnectivityArray()).reshape(-1, 4)
        centroids = p[t].mean(axis=1)
        # The stroke's centre: the tet centroid nearest (3, 0, 0), so that
        # some tets lie within the width whatever the mesher's tet size.
        centre = centroids[np.argmin(np.linalg.norm(centroids - [3.0, 0.0, 0.0], axis=1))]
        width, target = 0.5, np.array([1.0, 2.0, 3.0])
        paint = self.write_json("paint.json", {"points": [centre.tolist()], "width": width,
                                               "mode": "set", "absorption": target.tolist(),
                                               "channels": [1, 1, 0]})
        prefix = os.path.join(self.dir, "painted")
        self.assertSucceeded(self.run_cli("render", "--mesh", self.prefix + ".vtu", "--paint",
                                          paint, "--output", prefix, "--json", prefix + ".json"))
        painted = read(prefix + ".vtu")
        d = np.linalg.norm(centroids - centre, axis=1)
        w = np.exp(-d ** 2 / (2 * width ** 2))
        # The documented cut-off (default weight 1e-6): w(R) = 1e-6.
        w[d ** 2 > 2 * width ** 2 * np.log(1e6)] = 0.0
        before = cell_array(source, "AbsorptionCoefficient")
        after = cell_array(painted, "AbsorptionCoefficient")
        expected = before.copy()
        expected[:, :2] = (1 - w[:, None]) * before[:, :2] + w[:, None] * target[:2]
        self.assertTrue(np.allclose(after, expected, rtol=1e-9, atol=1e-12))
        self.assertTrue(np.array_equal(after[:, 2], before[:, 2]))  # masked channel
        far = d > 10 * width  # w < 2e-22: below the rounding of the old value
        self.assertTrue(far.any() and (d < width).any())
        self.assertTrue(np.array_equal(after[far], before[far]))
        self.assertTrue(np.all(np.abs(after[d < width, 0] - before[d < width, 0]) > 0.1))
        with open(prefix + ".json") as f:
            stats = json.load(f)
        self.assertEqual(stats["paint"]["tets_touched"], int(np.sum(w > 1e-6)))
        self.assertNotIn("cut", stats)
        # Paint before cut: the painted values survive the cut of their tets.
        prefix2 = os.path.join(self.dir, "painted-cut")
        self.assertSucceeded(self.run_cli("render", "--mesh", self.prefix + ".vtu", "--paint",
                                          paint, "--cut-plane", "0,0,0,-1,0,0",
                                          "--output", prefix2))
        both = read(prefix2 + ".vtu")
        ids = cell_array(both, "vtkOriginalCellIds")
        self.assertTrue(np.allclose(cell_array(both, "AbsorptionCoefficient"), after[ids],
                                    rtol=1e-12))

    def test_bad_edit_files(self):
        mesh = ("render", "--mesh", self.prefix + ".vtu")
        self.assertSucceeded(self.first)
        missing = os.path.join(self.dir, "no-such-paint.json")
        self.assertFailsNaming(self.run_cli(*mesh, "--paint", missing), "no-such-paint.json")
        paint_cases = (
            ("{ not json", "not valid JSON"),
            ([1, 2], "object"),
            ({"width": 1}, "points"),
            ({"points": []}, "points"),
            ({"points": [[1, 2]]}, "points"),
            ({"points": [[0, 0, 0]], "width": -1}, "width"),
            ({"points": [[0, 0, 0]], "width": "wide"}, "width"),
            ({"points": [[0, 0, 0]], "mode": "paint"}, "mode"),
            ({"points": [[0, 0, 0]], "absorption": [1, 2]}, "absorption"),
            ({"points": [[0, 0, 0]], "reduced_scattering": "red"}, "reduced_scattering"),
            ({"points": [[0, 0, 0]], "strength": 2}, "strength"),
            ({"points": [[0, 0, 0]], "channels": [1, 1]}, "channels"),
            ({"points": [[0, 0, 0]], "cutoff_weight": -0.5}, "cutoff_weight"),
        )
        for content, field in paint_cases:
            with self.subTest(paint=content):
                path = self.write_json("bad-paint.json", content)
                self.assertFailsNaming(self.run_cli(*mesh, "--paint", path),
                                       "bad-paint.json", field)
        stroke_cases = (
            ("[", "not valid JSON"),
            ({"points": [[0, 0, 0]]}, "points"),
            ({"points": [[0, 0, 0], [1, "a", 0]]}, "points"),
            ({"points": [[0, 0, 0], [1, 0, 0]], "view_direction": [0, 0, 0]}, "view_direction"),
            ({"points": [[0, 0, 0], [1, 0, 0]], "view_direction": [0, 1]}, "view_direction"),
            ({"points": [[0, 0, 0], [1, 0, 0]], "inside_out": "yes"}, "inside_out"),
        )
        for content, field in stroke_cases:
            with self.subTest(stroke=content):
                path = self.write_json("bad-stroke.json", content)
                self.assertFailsNaming(self.run_cli(*mesh, "--cut-stroke", path),
                                       "bad-stroke.json", field)
        stroke = self.write_json("ok-stroke.json", {"points": [[0, 0, 0], [1, 0, 0]]})
        self.assertFailsNaming(self.run_cli(*mesh, "--cut-stroke", stroke, "--cut-plane",
                                            "0,0,0,1,0,0"), "--cut-plane", "--cut-stroke")


if __name__ == "__main__":
    unittest.main(verbosity=2)
