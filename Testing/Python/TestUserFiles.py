#!/usr/bin/env python3
"""What a `translucency` run does to the user's files (issue 34, findings 1, 2, 6, 7).

How to run (from a build tree; ctest sets the variable itself):

    TRANSLUCENCY_CLI=<build>/bin/translucency /usr/bin/python3 TestUserFiles.py

1. compare --output DIR keeps what the user had in DIR/compare/ (a file and a
   folder), and leaves no staging folder behind.
2. Symlinks planted at the old fixed temporary names (PREFIX.vtu.part,
   PREFIX.vtp.part) and at PREFIX.vtu itself, all pointing at a victim file:
   the victim is unchanged, PREFIX.vtu/.vtp are new regular files.
3. A run into a prefix whose lock another process holds (flock on
   PREFIX.lock) is refused before any work with a message naming the lock,
   and the old outputs stay as they were; three renders started together
   into one prefix leave a .vtu/.vtp pair of one run (the light power, a
   different one per run, read back from both files agrees) and no
   temporary or lock file; each run either succeeded or was refused.
4. Outputs that overwrite inputs or each other are refused before work
   (exit 2) and the input is unchanged: --json naming the mesh, --output s
   --json s.vtu, bench --plot p.csv (its data file is p.csv too), an output
   that is a folder.
5. SIGTERM while the outputs are being written: no PREFIX.*.part and no lock
   left, the previous outputs untouched, the exit status says SIGTERM.
6. A failed write (the file-size limit of the process, as a full disk)
   keeps every old output and removes the temporaries.
7. bench --tets "" is a usage error (it silently ran the default sizes).
8. Three compares started together into one --output DIR (one broke in 1 of
   3 trials): each succeeds or is refused by the lock; compare.vtm and its
   pieces are one run's (the irradiance of the volume and of both solvers'
   surfaces agree, a different light power per run) and nothing is left
   over.
9. Messages carry no raw bytes of a file: control bytes in a PLY header, a
   TetGen number, a --measured CSV, a JSON key and a file name give one
   line per message on stderr, with no control byte in it.

Exits non-zero on failure (unittest).
"""

import fcntl
import hashlib
import os
import resource
import signal
import subprocess
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_under_test import find_cli  # noqa: E402

CLI = find_cli("TestUserFiles")
TIME_LIMIT = 120

# A 10 mm cube (OBJ): meshed with --max-tet-volume 2 it has a few hundred tets.
CUBE_OBJ = "\n".join(
    ["v 0 0 0", "v 10 0 0", "v 10 10 0", "v 0 10 0", "v 0 0 10", "v 10 0 10", "v 10 10 10",
     "v 0 10 10", "f 1 3 2", "f 1 4 3", "f 5 6 7", "f 5 7 8", "f 1 2 6", "f 1 6 5", "f 2 3 7",
     "f 2 7 6", "f 3 4 8", "f 3 8 7", "f 4 1 5", "f 4 5 8"]) + "\n"
# --collimated surface: the outputs' Irradiance then holds the directional
# light, whose power tells the runs apart (the default by light kind,
# extended-moments, leaves a directional light out of the solved Irradiance).
SMALL = ["--max-tet-volume", "2", "--no-shadows", "--uniform-samples", "1",
         "--collimated", "surface"]


def digest(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def read_xml(path):
    from vtkmodules.vtkIOXML import vtkXMLPolyDataReader, vtkXMLUnstructuredGridReader
    reader = vtkXMLUnstructuredGridReader() if path.endswith(".vtu") else vtkXMLPolyDataReader()
    reader.SetFileName(path)
    reader.Update()
    return reader.GetOutput()


class UserFiles(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.dir = cls.tmp.name
        cls.cube = os.path.join(cls.dir, "cube.obj")
        with open(cls.cube, "w") as f:
            f.write(CUBE_OBJ)

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def run_cli(self, args, **kwargs):
        try:
            return subprocess.run([CLI] + args, capture_output=True, text=True,
                                  timeout=TIME_LIMIT, **kwargs)
        except subprocess.TimeoutExpired:
            self.fail("no answer within %d s: %s" % (TIME_LIMIT, " ".join(args)))

    def render(self, prefix, *extra, **kwargs):
        return self.run_cli(["render", "--mesh", self.cube] + SMALL + ["--output", prefix] +
                            list(extra), **kwargs)

    def folder(self, name):
        path = os.path.join(self.dir, name)
        os.makedirs(path, exist_ok=True)
        return path

    def leftovers(self, folder):
        return sorted(n for n in os.listdir(folder)
                      if n.endswith(".part") or n.endswith(".lock") or n.startswith(".compare-"))

    # 1 ------------------------------------------------------------------------
    def test_compare_keeps_the_users_files(self):
        out = self.folder("compare_out")
        pieces = self.folder(os.path.join("compare_out", "compare"))
        mine = os.path.join(pieces, "my_notes.txt")
        with open(mine, "w") as f:
            f.write("kept by the user\n")
        kept_folder = self.folder(os.path.join("compare_out", "compare", "my_folder"))
        with open(os.path.join(kept_folder, "data.csv"), "w") as f:
            f.write("1,2\n")
        for run in range(2):  # the second run replaces the first's pieces
            result = self.run_cli(["compare", "--mesh", self.cube] + SMALL +
                                  ["--solvers", "fem", "--reference", "divergence", "--no-png",
                                   "--output", out])
            self.assertEqual(result.returncode, 0, result.stderr)
            with open(mine) as f:
                self.assertEqual(f.read(), "kept by the user\n", "run %d" % run)
            self.assertTrue(os.path.isfile(os.path.join(kept_folder, "data.csv")), run)
            self.assertEqual(self.leftovers(out), [], run)
        from vtkmodules.vtkIOXML import vtkXMLMultiBlockDataReader
        reader = vtkXMLMultiBlockDataReader()
        reader.SetFileName(os.path.join(out, "compare.vtm"))
        reader.Update()
        blocks = reader.GetOutput()
        self.assertEqual(blocks.GetNumberOfBlocks(), 3)  # volume, divergence, fem
        self.assertGreater(blocks.GetBlock(0).GetNumberOfCells(), 0)

    # 2 ------------------------------------------------------------------------
    def test_planted_symlinks_are_not_followed(self):
        folder = self.folder("symlinks")
        victim = os.path.join(folder, "victim.txt")
        with open(victim, "w") as f:
            f.write("precious\n")
        prefix = os.path.join(folder, "out")
        for name in ("out.vtu.part", "out.vtp.part", "out.vtu", "out.json.part"):
            os.symlink(victim, os.path.join(folder, name))
        result = self.render(prefix, "--json", prefix + ".json")
        self.assertEqual(result.returncode, 0, result.stderr)
        with open(victim) as f:
            self.assertEqual(f.read(), "precious\n")
        for ext in (".vtu", ".vtp", ".json"):
            self.assertFalse(os.path.islink(prefix + ext), ext)
            self.assertTrue(os.path.isfile(prefix + ext), ext)
        self.assertGreater(read_xml(prefix + ".vtu").GetNumberOfCells(), 0)
        self.assertGreater(read_xml(prefix + ".vtp").GetNumberOfCells(), 0)
        # The planted links at the old temporary names are left alone.
        self.assertTrue(os.path.islink(prefix + ".vtu.part"))

    # 3 ------------------------------------------------------------------------
    def test_a_held_lock_refuses_the_second_run(self):
        folder = self.folder("locked")
        prefix = os.path.join(folder, "out")
        self.assertEqual(self.render(prefix).returncode, 0)
        before = {ext: digest(prefix + ext) for ext in (".vtu", ".vtp")}
        with open(prefix + ".lock", "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            start = time.monotonic()
            result = self.render(prefix, "--light", "directional:0,0,-1:5")
            elapsed = time.monotonic() - start
        self.assertEqual(result.returncode, 1, result.stderr)
        self.assertIn("another translucency run is writing the outputs", result.stderr)
        self.assertIn("out.lock", result.stderr)
        self.assertLess(elapsed, 30.0, "refused only after the work")
        self.assertNotIn("solving", result.stderr, "refused only after the work")
        for ext, value in before.items():
            self.assertEqual(digest(prefix + ext), value, ext)

    def test_concurrent_runs_leave_one_runs_pair(self):
        folder = self.folder("concurrent")
        prefix = os.path.join(folder, "out")
        powers = [1.0, 2.0, 4.0]
        for trial in range(3):
            runs = [subprocess.Popen([CLI, "render", "--mesh", self.cube] + SMALL +
                                     ["--light", "directional:0,0,-1:%g" % p, "--output", prefix],
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
                    for p in powers]
            outcomes = [(r.wait(timeout=TIME_LIMIT), r.communicate()[1]) for r in runs]
            succeeded = 0
            for code, stderr in outcomes:
                if code == 0:
                    succeeded += 1
                else:
                    self.assertEqual(code, 1, stderr)
                    self.assertIn("another translucency run is writing the outputs", stderr)
            self.assertGreaterEqual(succeeded, 1, outcomes)
            self.assertEqual(self.leftovers(folder), [], trial)
            # The pair is one run's: the total irradiance of the surface (.vtp)
            # and of the volume's boundary (.vtu) give the same power.
            volume, surface = read_xml(prefix + ".vtu"), read_xml(prefix + ".vtp")
            a = volume.GetPointData().GetArray("Irradiance").GetRange(0)[1]
            b = surface.GetPointData().GetArray("Irradiance").GetRange(0)[1]
            self.assertAlmostEqual(a / b, 1.0, places=9, msg="mixed pair in trial %d" % trial)

    # 4 ------------------------------------------------------------------------
    def expect_refused(self, args, needles, protected=()):
        before = {p: digest(p) for p in protected}
        result = self.run_cli(args)
        self.assertEqual(result.returncode, 2, result.stderr)
        for needle in needles:
            self.assertIn(needle, result.stderr)
        for p, value in before.items():
            self.assertEqual(digest(p), value, p)

    def test_outputs_that_overwrite_inputs_are_refused(self):
        folder = self.folder("collisions")
        mesh_prefix = os.path.join(folder, "mesh")
        self.assertEqual(self.render(mesh_prefix).returncode, 0)
        mesh = mesh_prefix + ".vtu"
        self.expect_refused(["render", "--mesh", mesh, "--json", mesh],
                            ["--json", "is the input --mesh"], [mesh])
        # The same file by another name (a symlink to the mesh's folder).
        alias = os.path.join(self.dir, "alias")
        os.symlink(folder, alias)
        self.expect_refused(["render", "--mesh", mesh, "--json", os.path.join(alias, "mesh.vtu")],
                            ["is the input --mesh"], [mesh])
        out = os.path.join(folder, "s")
        self.expect_refused(["render", "--mesh", mesh, "--output", out, "--json", out + ".vtu"],
                            ["--json", "is also the output of --output"], [mesh])
        os.mkdir(os.path.join(folder, "report.json"))
        self.expect_refused(["render", "--mesh", mesh, "--json",
                             os.path.join(folder, "report.json")], ["is a folder"])
        plot = os.path.join(folder, "p.csv")
        with open(plot, "w") as f:
            f.write("data\n")
        self.expect_refused(["bench", "--mesh", self.cube, "--linear-solvers", "cg-jacobi",
                             "--tets", "100", "--plot", plot],
                            ["--plot", "is also the output of"], [plot])

    # 5 ------------------------------------------------------------------------
    def test_sigterm_while_writing_leaves_no_temporary(self):
        folder = self.folder("sigterm")
        prefix = os.path.join(folder, "big")
        box = ["--mesh", self.cube, "--max-tet-volume", "0.02", "--no-shadows",
               "--uniform-samples", "1", "--solver", "divergence", "--output", prefix]
        result = self.run_cli(["render"] + box)
        self.assertEqual(result.returncode, 0, result.stderr)
        before = {ext: digest(prefix + ext) for ext in (".vtu", ".vtp")}
        caught = False
        for attempt in range(4):
            run = subprocess.Popen([CLI, "render"] + box, stdout=subprocess.DEVNULL,
                                   stderr=subprocess.PIPE)
            while run.poll() is None:
                if any(n.endswith(".part") for n in os.listdir(folder)):
                    run.send_signal(signal.SIGTERM)
                    caught = True
                    break
                time.sleep(0.0005)
            code = run.wait(timeout=TIME_LIMIT)
            run.stderr.close()
            if caught:
                self.assertEqual(code, -signal.SIGTERM)
                break
        if not caught:
            self.skipTest("the write was never seen in progress (machine too fast)")
        self.assertEqual(self.leftovers(folder), [])
        for ext, value in before.items():
            self.assertEqual(digest(prefix + ext), value, ext)
        # And a SIGTERM during the solve removes the lock.
        run = subprocess.Popen([CLI, "render"] + box, stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL)
        deadline = time.monotonic() + 60
        while not os.path.exists(prefix + ".lock") and time.monotonic() < deadline:
            time.sleep(0.001)
        run.send_signal(signal.SIGTERM)
        self.assertEqual(run.wait(timeout=TIME_LIMIT), -signal.SIGTERM)
        self.assertEqual(self.leftovers(folder), [])

    # 6 ------------------------------------------------------------------------
    def test_failed_write_keeps_old_outputs(self):
        folder = self.folder("disk_full")
        prefix = os.path.join(folder, "out")
        self.assertEqual(self.render(prefix, "--json", prefix + ".json").returncode, 0)
        before = {ext: digest(prefix + ext) for ext in (".vtu", ".vtp", ".json")}
        size = os.path.getsize(prefix + ".vtu")

        def limit_file_size():
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # write() fails with EFBIG instead
            resource.setrlimit(resource.RLIMIT_FSIZE, (size // 2, size // 2))

        result = self.render(prefix, "--json", prefix + ".json", "--light", "directional:0,0,-1:3",
                             preexec_fn=limit_file_size)
        self.assertEqual(result.returncode, 1, result.stderr)
        self.assertIn("no output changed", result.stderr)
        for ext, value in before.items():
            self.assertEqual(digest(prefix + ext), value, ext)
        self.assertEqual(self.leftovers(folder), [])

    # 7 ------------------------------------------------------------------------
    def test_bench_empty_tets_is_a_usage_error(self):
        result = self.run_cli(["bench", "--mesh", self.cube, "--tets", ""])
        self.assertEqual(result.returncode, 2, result.stderr)
        self.assertIn("--tets", result.stderr)


    def test_every_command_refuses_an_output_over_its_input(self):
        """compare, acquire and radiosity as render: --json or --output naming
        an input is a usage error before any work, the input unchanged."""
        folder = self.folder("collisions_all")
        mesh_prefix = os.path.join(folder, "mesh")
        self.assertEqual(self.render(mesh_prefix).returncode, 0)
        mesh = mesh_prefix + ".vtu"
        scene = os.path.join(folder, "scene.json")
        csv = os.path.join(folder, "measured.csv")
        with open(scene, "w") as f:
            f.write("{}\n")
        with open(csv, "w") as f:
            f.write("t_ns,a\n0,1\n1,2\n")
        out = os.path.join(folder, "out")
        for args, needle in [
            (["compare", "--mesh", mesh, "--json", mesh, "--no-png", "--output", out],
             "--json '%s' is the input --mesh" % mesh),
            (["compare", "--mesh", mesh, "--measured", csv, "--json", csv, "--no-png",
              "--time-gates", "0,0.5,4", "--source", "pencil:5,5,10:0,0,-1", "--detector",
              "5,0,5", "--output", out], "is the input --measured"),
            (["acquire", "--sample", mesh, "--patterns", mesh, "--output", mesh_prefix,
              "--no-png"], "--output '%s' is the input --sample" % mesh),
            (["acquire", "--sample", mesh, "--patterns", mesh, "--json", mesh, "--output", out,
              "--no-png"], "is the input --sample"),
            (["radiosity", "--scene", scene, "--json", scene, "--output", out],
             "is the input --scene"),
        ]:
            with self.subTest(command=args[0], needle=needle):
                self.expect_refused(args, [needle, "refused"], [mesh, scene, csv])

    # 8 ------------------------------------------------------------------------
    def test_concurrent_compares_into_one_folder(self):
        from vtkmodules.vtkIOXML import vtkXMLMultiBlockDataReader
        out = self.folder("concurrent_compare")
        powers = [1.0, 2.0, 4.0]
        for trial in range(2):
            runs = [subprocess.Popen([CLI, "compare", "--mesh", self.cube] + SMALL +
                                     ["--solvers", "fem,divergence", "--no-png", "--light",
                                      "directional:0,0,-1:%g" % p, "--output", out],
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
                    for p in powers]
            outcomes = [(r.wait(timeout=TIME_LIMIT), r.communicate()[1]) for r in runs]
            succeeded = 0
            for code, stderr in outcomes:
                if code == 0:
                    succeeded += 1
                else:
                    self.assertEqual(code, 1, stderr)
                    self.assertIn("another translucency run is writing the outputs", stderr)
            self.assertGreaterEqual(succeeded, 1, outcomes)
            self.assertEqual(self.leftovers(out), [], trial)
            reader = vtkXMLMultiBlockDataReader()
            reader.SetFileName(os.path.join(out, "compare.vtm"))
            reader.Update()
            blocks = reader.GetOutput()
            self.assertEqual(blocks.GetNumberOfBlocks(), 3, trial)
            peaks = [blocks.GetBlock(i).GetPointData().GetArray("Irradiance").GetRange(0)[1]
                     for i in range(3)]
            for peak in peaks[1:]:
                self.assertAlmostEqual(peak / peaks[0], 1.0, places=9,
                                       msg="pieces of different runs in trial %d" % trial)

    # 9 ------------------------------------------------------------------------
    def test_messages_carry_no_raw_bytes(self):
        folder = self.folder("raw_bytes")

        def write(name, data):
            path = os.path.join(folder, name)
            with open(path, "wb") as f:
                f.write(data)
            return path

        ply = write("esc.ply", b"ply\nformat ascii 1.0\nelement vertex 3\x1b[2J\r\n"
                               b"property float x\nend_header\n")
        node = write("bell.node", b"4 3 0 0\n1 0 0 0\n2 1\x07 0 0\n3 0 1 0\n4 0 0 1\n")
        write("bell.ele", b"1 4 0\n1 1 2 3 4\n")
        key = write("key.json", b'{"absorption\\n\\u001b[31m": [0.1, 0.1, 0.1]}')
        csv = write("measured.csv", b"t_ns,a\n0,1\n0.5,3\x1b[0m\r\n1,2\n")
        mesh_prefix = os.path.join(folder, "mesh")
        self.assertEqual(self.render(mesh_prefix).returncode, 0)
        out = os.path.join(folder, "out")
        cases = [
            ["render", "--mesh", ply, "--output", out],
            ["render", "--mesh", node, "--output", out],
            ["render", "--mesh", mesh_prefix + ".vtu", "--material", key, "--output", out],
            ["compare", "--mesh", mesh_prefix + ".vtu", "--solvers", "divergence", "--no-png",
             "--time-gates", "0,0.5,4", "--source", "pencil:5,5,10:0,0,-1", "--detector",
             "5,0,5", "--measured", csv, "--output", out],
            ["render", "--mesh", os.path.join(folder, "new\nline\x1b.obj"), "--output", out],
        ]
        for args in cases:
            with self.subTest(args=args[:3]):
                result = subprocess.run([CLI] + args, capture_output=True, timeout=TIME_LIMIT)
                self.assertEqual(result.returncode, 1, result.stderr)
                lines = result.stderr.split(b"\n")
                self.assertEqual(lines[-1], b"")
                errors = [line for line in lines if line.startswith(b"translucency: error")]
                self.assertEqual(len(errors), 1, result.stderr)
                for line in lines:
                    self.assertFalse(any(byte < 0x20 or byte == 0x7f for byte in line),
                                     line)


if __name__ == "__main__":
    unittest.main()
