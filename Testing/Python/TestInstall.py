#!/usr/bin/env python3
"""`cmake --install` gives a user a working tool, package and plugin without
PYTHONPATH or LoadPlugin (issue 20: the plugin loads automatically).

How to run (from a build tree; ctest sets the environment):

    TRANSLUCENCY_BINARY_DIR=<build> /usr/bin/python3 TestInstall.py

1. Installs the build into a fresh prefix (cmake --install --prefix).
2. <prefix>/bin/translucency --version runs (its run path finds lib/).
3. /usr/bin/python3 without PYTHONPATH, given only the prefix's
   lib/python3.X/dist-packages as a site directory (what the prefixes /usr
   and /usr/local are for Debian's Python, where the .pth file goes), imports
   `translucency` from the prefix and runs a filter.
4. An example copied to another directory runs with the installed package:
   render_bunny.py finds the bunny in <prefix>/share/translucency/Data
   (translucency.find_data), and find_cli() names <prefix>/bin/translucency.
5. pvpython without PYTHONPATH, with PV_PLUGIN_PATH set to the installed
   plugin's directory (the README's one line), has the Translucency proxies
   without LoadPlugin, and they run.

Exits non-zero on failure (unittest).
"""

import os
import shutil
import subprocess
import sys
import tempfile
import unittest

BINARY_DIR = os.environ.get("TRANSLUCENCY_BINARY_DIR")
if not BINARY_DIR:
    sys.exit("TestInstall: set TRANSLUCENCY_BINARY_DIR to the build tree")
PYTHON_VERSION = "%d.%d" % sys.version_info[:2]


def clean_environment(**extra):
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "PV_PLUGIN_PATH", "LD_LIBRARY_PATH", "TRANSLUCENCY_CLI",
                        "TRANSLUCENCY_DATA_DIR")}
    env.update(extra)
    return env


class InstallTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.TemporaryDirectory()
        cls.prefix = os.path.join(cls.dir.name, "prefix")
        result = subprocess.run(["cmake", "--install", BINARY_DIR, "--prefix", cls.prefix],
                                capture_output=True, text=True, timeout=300)
        if result.returncode != 0:
            raise AssertionError("cmake --install failed:\n" + result.stdout + result.stderr)
        cls.work = os.path.join(cls.dir.name, "elsewhere")  # not the source or build tree
        os.makedirs(cls.work)

    @classmethod
    def tearDownClass(cls):
        cls.dir.cleanup()

    def run_in_work(self, command, env):
        return subprocess.run(command, capture_output=True, text=True, timeout=300,
                              cwd=self.work, env=env)

    def test_cli_runs_from_the_prefix(self):
        result = self.run_in_work([os.path.join(self.prefix, "bin", "translucency"),
                                   "--version"], clean_environment())
        self.assertEqual(result.returncode, 0, result.stderr)
        self.assertTrue(result.stdout.startswith("translucency "), result.stdout)

    def test_python_package_without_pythonpath(self):
        site_dir = os.path.join(self.prefix, "lib", "python" + PYTHON_VERSION, "dist-packages")
        self.assertTrue(os.path.isfile(os.path.join(site_dir, "translucency.pth")))
        script = (
            "import site, sys\n"
            "site.addsitedir(%r)\n"
            "import translucency\n"
            "from vtkmodules.vtkFiltersSources import vtkSphereSource\n"
            "s = vtkSphereSource(); s.SetRadius(3)\n"
            "t = translucency.vtkTetrahedralizeSurface(); t.SetInputConnection(s.GetOutputPort())\n"
            "t.SetTargetNumberOfTets(500)\n"
            "print(translucency.__file__)\n"
            "print(translucency.update(t).GetNumberOfCells())\n" % site_dir)
        result = self.run_in_work(["/usr/bin/python3", "-c", script], clean_environment())
        self.assertEqual(result.returncode, 0, result.stderr)
        path, cells = result.stdout.split()
        self.assertTrue(path.startswith(self.prefix), path)
        self.assertGreater(int(cells), 100)

    def test_example_copied_elsewhere(self):
        site_dir = os.path.join(self.prefix, "lib", "python" + PYTHON_VERSION, "dist-packages")
        example = os.path.join(self.prefix, "share", "translucency", "examples", "render_bunny.py")
        self.assertTrue(os.path.isfile(example))
        shutil.copy(example, self.work)
        script = (
            "import runpy, site, sys\n"
            "site.addsitedir(%r)\n"
            "import translucency\n"
            "print('data', translucency.find_data('bunny.ply'))\n"
            "print('cli', translucency.find_cli())\n"
            # (The coarsest bunny: what is tested is the installed package
            # and its data, not the solve at 100,000 tets, which
            # Example.RenderBunny runs.)
            "sys.argv = ['render_bunny.py', 'new/dir/bunny.png', '--no-render',"
            " '--target-tets=5000']\n"
            "runpy.run_path('render_bunny.py', run_name='__main__')\n" % site_dir)
        result = self.run_in_work(["/usr/bin/python3", "-c", script], clean_environment())
        self.assertEqual(result.returncode, 0, result.stdout + result.stderr)
        lines = dict(line.split(" ", 1) for line in result.stdout.splitlines()
                     if line.startswith(("data ", "cli ")))
        self.assertEqual(lines["data"], os.path.join(
            self.prefix, "share", "translucency", "Data", "bunny.ply"))
        self.assertEqual(lines["cli"], os.path.join(self.prefix, "bin", "translucency"))
        self.assertIn("surface points:", result.stdout)

    def test_missing_data_names_where_it_looked(self):
        site_dir = os.path.join(self.prefix, "lib", "python" + PYTHON_VERSION, "dist-packages")
        script = ("import site\nsite.addsitedir(%r)\nimport translucency\n"
                  "translucency.find_data('nosuchfile.ply')\n" % site_dir)
        result = self.run_in_work(["/usr/bin/python3", "-c", script], clean_environment())
        self.assertNotEqual(result.returncode, 0)
        self.assertIn("FileNotFoundError", result.stderr)
        self.assertIn(os.path.join(self.prefix, "share", "translucency", "Data", "nosuchfile.ply"),
                      result.stderr)

    def test_plugin_loads_from_pv_plugin_path(self):
        plugin_dir = os.path.join(self.prefix, "lib", "paraview-plugins", "Translucency")
        self.assertTrue(os.path.isfile(os.path.join(plugin_dir, "Translucency.so")))
        script = (
            "from paraview.simple import *\n"
            "sphere = Sphere(Radius=3)\n"
            "tetra = TetrahedralizeSurface(Input=sphere, TargetNumberOfTets=500)\n"
            "light = SurfaceIrradiance(Input=AssignScatteringCoefficients(Input=tetra))\n"
            "solve = SolveDiffusion(Input=light)\n"
            "solve.UpdatePipeline()\n"
            "print(solve.GetDataInformation().GetNumberOfPoints())\n"
            "print(solve.PointData['Fluence'].GetRange(0)[1])\n")
        result = self.run_in_work(
            [shutil.which("pvpython") or "/usr/bin/pvpython", "--force-offscreen-rendering",
             "-c", script], clean_environment(PV_PLUGIN_PATH=plugin_dir))
        self.assertEqual(result.returncode, 0, result.stdout + result.stderr)
        points, peak = result.stdout.split()[-2:]
        self.assertGreater(int(points), 50)
        self.assertGreater(float(peak), 0.0)


if __name__ == "__main__":
    unittest.main()
