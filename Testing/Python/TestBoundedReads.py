#!/usr/bin/env python3
"""Endless and damaged inputs through the `translucency` command line (issue 34,
findings 3 and 4).

How to run (from a build tree; ctest sets the variable itself):

    TRANSLUCENCY_CLI=<build>/bin/translucency /usr/bin/python3 TestBoundedReads.py

1. /dev/zero through a symlink, and a FIFO (no writer: opening it would block
   for ever), named as every file input that is read: the mesh in every
   format (.vtu, .vtp, .ply, .stl, .obj, TetGen .node and .ele, and the .ele
   next to a good .node; an optional .face that is not a regular file is not
   read, and the run goes on), through render, compare and acquire; a
   --material JSON (single and table), --paint, --cut-stroke, a radiosity
   --scene, compare's --measured CSV, acquire's --sample, --patterns (a file,
   and a file inside a --patterns folder) and --synthetic-truth. Each run
   must end within seconds with exit 1 and a message that names the file and
   says it is not a regular file.
2. A sparse .vtu larger than a quarter of --memory-limit is refused by its
   size before it is read (in well under the time reading it would take).
3. The project's own binary .vtu output with one line of its <CellData>
   section duplicated (a second <DataArray> of one name made VTK 9.2's XML
   reader segfault) is a clean error naming the file, through render, compare
   and acquire.

Exits non-zero on failure (unittest).
"""

import json
import os
import subprocess
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_under_test import find_cli  # noqa: E402

CLI = find_cli("TestBoundedReads")
TIME_LIMIT = 30  # an endless read ran for minutes (5.1 GB after 12 s)

CUBE_OBJ = "\n".join(
    ["v 0 0 0", "v 10 0 0", "v 10 10 0", "v 0 10 0", "v 0 0 10", "v 10 0 10", "v 10 10 10",
     "v 0 10 10", "f 1 3 2", "f 1 4 3", "f 5 6 7", "f 5 7 8", "f 1 2 6", "f 1 6 5", "f 2 3 7",
     "f 2 7 6", "f 3 4 8", "f 3 8 7", "f 4 1 5", "f 4 5 8"]) + "\n"
SMALL = ["--max-tet-volume", "4", "--no-shadows", "--uniform-samples", "1"]


class BoundedReads(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.dir = cls.tmp.name
        cls.cube = os.path.join(cls.dir, "cube.obj")
        with open(cls.cube, "w") as f:
            f.write(CUBE_OBJ)
        cls.mesh_prefix = os.path.join(cls.dir, "mesh")
        result = subprocess.run([CLI, "render", "--mesh", cls.cube] + SMALL +
                                ["--output", cls.mesh_prefix], capture_output=True, text=True,
                                timeout=120)
        if result.returncode != 0:
            raise AssertionError(result.stderr)
        cls.mesh = cls.mesh_prefix + ".vtu"

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def run_cli(self, args):
        start = time.monotonic()
        try:
            result = subprocess.run([CLI] + args, capture_output=True, text=True,
                                    timeout=TIME_LIMIT, stdin=subprocess.DEVNULL)
        except subprocess.TimeoutExpired:
            self.fail("no answer within %d s (an endless read): %s" % (TIME_LIMIT, " ".join(args)))
        return result, time.monotonic() - start

    def endless(self, name, kind):
        """A path named `name` that is /dev/zero (symlink) or a FIFO."""
        path = os.path.join(self.dir, kind + "_" + name)
        if os.path.lexists(path):
            os.remove(path)
        if kind == "symlink":
            os.symlink("/dev/zero", path)
        else:
            os.mkfifo(path)
        return path

    def expect_refused(self, args, path, case):
        result, _ = self.run_cli(args)
        self.assertEqual(result.returncode, 1, "%s: %s" % (case, result.stderr))
        self.assertIn(os.path.basename(path), result.stderr, case)
        self.assertIn("not a regular file", result.stderr, case)
        self.assertLess(len(result.stderr), 2000, case)

    def test_endless_inputs(self):
        out = os.path.join(self.dir, "out")
        cases = [
            ("mesh.vtu", lambda p: ["render", "--mesh", p, "--output", out]),
            ("mesh.vtp", lambda p: ["render", "--mesh", p, "--output", out]),
            ("material.json", lambda p: ["render", "--mesh", self.mesh, "--material", p]),
            ("table.json", lambda p: ["render", "--mesh", self.mesh, "--material", p,
                                      "--material-ids", "MaterialId"]),
            ("paint.json", lambda p: ["render", "--mesh", self.mesh, "--paint", p]),
            ("stroke.json", lambda p: ["render", "--mesh", self.mesh, "--cut-stroke", p]),
            ("scene.json", lambda p: ["radiosity", "--scene", p, "--output", out]),
            ("measured.csv", lambda p: ["compare", "--mesh", self.mesh, "--no-png", "--solvers",
                                        "divergence", "--time-gates", "0,2,4", "--detector",
                                        "10,5,5", "--source", "point:5,5,5", "--measured", p,
                                        "--output", out]),
            ("sample.vtu", lambda p: ["acquire", "--sample", p, "--patterns", self.mesh,
                                      "--output", out, "--no-png"]),
            ("truth.vti", lambda p: ["acquire", "--synthetic-truth", p, "--grid", "2x2x2",
                                     "--patterns", "1x1", "--output", out, "--no-png"]),
            ("patterns.vtu", lambda p: ["acquire", "--sample", self.mesh, "--patterns", p,
                                        "--output", out, "--no-png"]),
            ("compare.vtu", lambda p: ["compare", "--mesh", p, "--no-png", "--solvers", "fem",
                                       "--output", out]),
            ("acquire_mesh.vtu", lambda p: ["acquire", "--sample", p, "--patterns", p,
                                            "--output", out, "--no-png"]),
        ] + [("mesh." + ext, lambda p: ["render", "--mesh", p, "--output", out])
             for ext in ("ply", "stl", "obj", "node", "ele")]
        for kind in ("symlink", "fifo"):
            for name, args in cases:
                with self.subTest(kind=kind, name=name):
                    path = self.endless(name, kind)
                    self.expect_refused(args(path), path, "%s %s" % (kind, name))

    def test_endless_companions(self):
        """A FIFO or /dev/zero where a reader finds a second file by itself:
        the .ele or .face next to a good TetGen .node, a pattern file inside
        a --patterns folder."""
        out = os.path.join(self.dir, "out")
        for kind in ("symlink", "fifo"):
            for companion in ("ele", "face"):
                with self.subTest(kind=kind, companion=companion):
                    folder = os.path.join(self.dir, "tetgen_%s_%s" % (kind, companion))
                    os.makedirs(folder, exist_ok=True)
                    node = os.path.join(folder, "tet.node")
                    with open(node, "w") as f:
                        f.write("4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n")
                    if companion == "face":
                        with open(os.path.join(folder, "tet.ele"), "w") as f:
                            f.write("1 4 0\n1 1 2 3 4\n")
                    path = os.path.join(folder, "tet." + companion)
                    if kind == "symlink":
                        os.symlink("/dev/zero", path)
                    else:
                        os.mkfifo(path)
                    result, _ = self.run_cli(["render", "--mesh", node, "--output", out])
                    if companion == "face":
                        # Optional (boundary markers): a .face that is not a
                        # regular file is not read; the run goes on.
                        self.assertEqual(result.returncode, 0, result.stderr)
                        continue
                    self.assertEqual(result.returncode, 1, result.stderr)
                    self.assertIn("tet." + companion, result.stderr)
                    self.assertIn("not a regular file", result.stderr)
            with self.subTest(kind=kind, companion="pattern in a folder"):
                folder = os.path.join(self.dir, "patterns_" + kind)
                os.makedirs(folder, exist_ok=True)
                path = os.path.join(folder, "p0.vtu")
                if kind == "symlink":
                    os.symlink("/dev/zero", path)
                else:
                    os.mkfifo(path)
                self.expect_refused(["acquire", "--sample", self.mesh, "--patterns", folder,
                                     "--output", out, "--no-png"], path, "pattern folder " + kind)

    def test_size_bound_before_reading(self):
        sparse = os.path.join(self.dir, "huge.vtu")
        with open(sparse, "wb") as f:
            f.truncate(3 << 30)  # 3 GiB of holes: nothing to read fast
        result, seconds = self.run_cli(["render", "--mesh", sparse, "--memory-limit", "1"])
        self.assertEqual(result.returncode, 1, result.stderr)
        self.assertIn("huge.vtu", result.stderr)
        self.assertIn("3 GiB", result.stderr)
        self.assertIn("--memory-limit", result.stderr)
        self.assertLess(seconds, 10.0)
        os.remove(sparse)

    def test_duplicated_cell_data_line(self):
        with open(self.mesh, "rb") as f:
            lines = f.read().split(b"\n")
        start = next(i for i, line in enumerate(lines) if line.strip().startswith(b"<CellData"))
        end = next(i for i, line in enumerate(lines) if line.strip().startswith(b"</CellData"))
        out = os.path.join(self.dir, "damaged_out")
        # Each line of the section duplicated: <CellData> itself and each
        # <DataArray> (two arrays of one name made VTK 9.2's reader segfault).
        for index in range(start, end + 1):
            damaged = os.path.join(self.dir, "damaged_%d.vtu" % index)
            with open(damaged, "wb") as f:
                f.write(b"\n".join(lines[:index + 1] + [lines[index]] + lines[index + 1:]))
            commands = [["render", "--mesh", damaged, "--output", out]]
            if index == start + 1:
                commands += [["compare", "--mesh", damaged, "--no-png", "--solvers", "fem",
                              "--output", out],
                             ["acquire", "--sample", damaged, "--patterns", self.mesh,
                              "--output", out, "--no-png"]]
            for args in commands:
                with self.subTest(line=index, command=args[0]):
                    result, _ = self.run_cli(args)
                    self.assertEqual(result.returncode, 1, result.stderr)  # not -11 (SIGSEGV)
                    self.assertIn("damaged_%d.vtu" % index, result.stderr)
                    self.assertIn("CellData", result.stderr)


if __name__ == "__main__":
    unittest.main()
