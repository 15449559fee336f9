"""The `translucency` executable the Python tests run (shared by the tests of
Testing/Python; ctest sets TRANSLUCENCY_CLI or TRANSLUCENCY_BINARY_DIR)."""

import os
import subprocess
import sys
import tempfile
import unittest


def find_cli(test_name):
    """$TRANSLUCENCY_CLI, else $TRANSLUCENCY_BINARY_DIR/bin/translucency, else
    build/bin/translucency of this source tree (a test run by hand after
    `make build`); exits with a message naming `test_name` when that is not
    an executable."""
    cli = os.environ.get("TRANSLUCENCY_CLI")
    if not cli:
        binary = os.environ.get("TRANSLUCENCY_BINARY_DIR") or os.path.join(
            os.path.dirname(os.path.abspath(__file__)), "..", "..", "build")
        cli = os.path.join(binary, "bin", "translucency")
    if not os.access(cli, os.X_OK):
        sys.exit("%s: set TRANSLUCENCY_CLI to the built translucency executable (got %r)"
                 % (test_name, cli))
    return cli


def write_sphere(name, radius, resolution, clean=False):
    """A closed triangulated sphere (vtkSphereSource, `resolution` in theta
    and phi; merged points if `clean`) written as STL, PLY or VTP by the
    extension of `name`: the surface input of many tests."""
    from vtkmodules.vtkFiltersCore import vtkCleanPolyData, vtkTriangleFilter
    from vtkmodules.vtkFiltersSources import vtkSphereSource
    from vtkmodules.vtkIOGeometry import vtkSTLWriter
    from vtkmodules.vtkIOPLY import vtkPLYWriter
    from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter
    sphere = vtkSphereSource()
    sphere.SetRadius(radius)
    sphere.SetThetaResolution(resolution)
    sphere.SetPhiResolution(resolution)
    surface = vtkTriangleFilter()
    surface.SetInputConnection(sphere.GetOutputPort())
    if clean:
        merged = vtkCleanPolyData()
        merged.SetInputConnection(surface.GetOutputPort())
        surface = merged
    writers = {".stl": vtkSTLWriter, ".ply": vtkPLYWriter, ".vtp": vtkXMLPolyDataWriter}
    writer = writers[os.path.splitext(name)[1].lower()]()
    writer.SetInputConnection(surface.GetOutputPort())
    writer.SetFileName(name)
    writer.Write()


class BenchJsonTest(unittest.TestCase):
    """Tests of one `translucency bench` run on a small sphere (radius 10 mm,
    resolution 16, written as STL): setUpClass runs `bench BENCH_ARGS --mesh
    SPHERE --json FILE` once and keeps the result; setUp asserts the run
    exited 0 and loads the JSON into `self.results` (and, when it holds one
    mesh size, `self.size`). Subclasses set CLI (find_cli), BENCH_ARGS and
    TIMEOUT (seconds)."""

    CLI = None
    BENCH_ARGS = []
    TIMEOUT = 240

    @classmethod
    def extra_args(cls):
        """Arguments that need the class's temporary folder (cls.tmp.name)."""
        return []

    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.json_path = os.path.join(cls.tmp.name, "bench.json")
        cls.mesh = os.path.join(cls.tmp.name, "sphere.stl")
        write_sphere(cls.mesh, 10.0, 16)
        cmd = [cls.CLI, "bench"] + list(cls.BENCH_ARGS) + cls.extra_args() + [
            "--mesh", cls.mesh, "--json", cls.json_path]
        cls.run_result = subprocess.run(cmd, capture_output=True, text=True,
                                        timeout=cls.TIMEOUT)
        print(cls.run_result.stdout)
        print(cls.run_result.stderr, file=sys.stderr)

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def setUp(self):
        import json
        self.assertEqual(self.run_result.returncode, 0, self.run_result.stderr)
        with open(self.json_path) as f:
            self.results = json.load(f)
        if isinstance(self.results, list):
            self.assertEqual(len(self.results), 1)
            self.size = self.results[0]


class BoxRenderTest(unittest.TestCase):
    """Tests of `translucency render` on one 20 x 20 x 10 mm box: setUpClass
    writes it as STL and meshes it once with BOX_TETS tets (no light), so that
    every run of the class sees the same points and tets (`cls.mesh`, .vtu).
    Subclasses set CLI (find_cli) and BOX_TETS."""

    CLI = None
    BOX_TETS = 10000

    @classmethod
    def setUpClass(cls):
        from vtkmodules.vtkFiltersCore import vtkTriangleFilter
        from vtkmodules.vtkFiltersSources import vtkCubeSource
        from vtkmodules.vtkIOGeometry import vtkSTLWriter

        cls.dir = tempfile.TemporaryDirectory()
        cube = vtkCubeSource()
        cube.SetXLength(20)
        cube.SetYLength(20)
        cube.SetZLength(10)
        triangles = vtkTriangleFilter()
        triangles.SetInputConnection(cube.GetOutputPort())
        cls.box = os.path.join(cls.dir.name, "box.stl")
        writer = vtkSTLWriter()
        writer.SetFileName(cls.box)
        writer.SetInputConnection(triangles.GetOutputPort())
        writer.Write()
        cls.mesh = os.path.join(cls.dir.name, "box")
        cls.run_ok(["--mesh", cls.box, "--target-tets", str(cls.BOX_TETS), "--output", cls.mesh,
                    "--light", "none"])
        cls.mesh += ".vtu"

    @classmethod
    def tearDownClass(cls):
        cls.dir.cleanup()

    @classmethod
    def run_cli(cls, args):
        return subprocess.run([cls.CLI, "render"] + args, capture_output=True, text=True,
                              timeout=300)

    @classmethod
    def run_ok(cls, args):
        result = cls.run_cli(args)
        if result.returncode != 0:
            raise AssertionError("render %s failed:\n%s%s" % (" ".join(args), result.stdout,
                                                               result.stderr))
        return result
