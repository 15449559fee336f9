"""Every ```sh block of README.md runs as written, from a fresh checkout.

How to run (ctest does this, under Xvfb's lock; it takes minutes):

    /usr/bin/python3 Testing/Python/TestReadmeBlocks.py <build dir>

Steps:
1. Extract the ```sh blocks of README.md; join backslash-continued lines;
   drop comments.
2. Run each block's commands with bash -e in a scratch directory that looks
   like a fresh checkout after `make build`: `Data/` (the source tree's),
   `build/` (this build tree), nothing else.
3. Every file or directory the commands name with --output, --png, --json,
   --plot or --slice-png must exist afterwards and not be empty.

Three commands are not run, each for a reason another test covers:
`make demo` / `make test` (this test runs under `make test`; Python.TestDemoImage
runs the demo's command), `paraview` (the interactive GUI; ParaView.TestGui),
and `cmake --install ... --prefix /usr/local` (writes into the system;
Python.TestInstall installs into a temporary prefix).

Sizes: the README's sizes (100k to 1M tets) take tens of minutes on two cores,
so by default Data/bunny.ply is a decimated copy (368 of its 3,674 triangles:
TetGen keeps the surface's triangles, so the full bunny has a floor of 45,113
tets whatever --target-tets asks), --target-tets N, --tets LIST and bench --diffuse-optics'
--gate-tets become 3000, its --gates 10, every bench runs once (--runs 1)
and --photons is capped at 200000; TRANSLUCENCY_README_FULL=1 runs the blocks exactly as written.
Exits non-zero on failure (unittest).
"""

import os
import re
import shlex
import subprocess
import sys
import tempfile
import time
import unittest

SOURCE_DIR = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
if len(sys.argv) < 2 or not os.path.isdir(sys.argv[1]):
    sys.exit("usage: TestReadmeBlocks.py <build dir>")
BUILD_DIR = os.path.abspath(sys.argv.pop(1))
FULL = os.environ.get("TRANSLUCENCY_README_FULL") == "1"
# The coarse bunny: 3,674 -> 368 triangles. TetGen keeps the surface's
# triangles, so the full bunny cannot be meshed below 45,113 tets, whatever
# --target-tets asks (the mesher says so); the coarse one reaches ~5k.
COARSE_BUNNY_REDUCTION = 0.9

# (pattern, reason): commands not run here.
SKIPPED = [
    (r"^make (demo|test)\b", "runs the whole build and ctest (this test runs under it)"),
    (r"^paraview\b", "the interactive GUI (ParaView.TestGui)"),
    (r"^cmake --install\b", "installs into the system (Python.TestInstall: a temporary prefix)"),
]
OUTPUT_OPTIONS = ("--output", "--png", "--json", "--plot", "--slice-png")


def sh_blocks(text):
    """The commands of each ```sh block: a list per block, one string per command."""
    blocks = []
    for body in re.findall(r"^```sh\n(.*?)^```", text, re.S | re.M):
        commands, current = [], ""
        for line in body.splitlines():
            line = line.rstrip()
            if line.endswith("\\"):
                current += line[:-1] + " "
                continue
            current += line
            command = current.split("#", 1)[0].strip() if not current.lstrip().startswith(
                "#") else ""
            if command:
                commands.append(command)
            current = ""
        blocks.append(commands)
    return blocks


def smaller(command):
    """The command with the test's sizes (see the module doc)."""
    if FULL:
        return command
    command = re.sub(r"--target-tets \d+", "--target-tets 3000", command)
    command = re.sub(r"--tets [\d,]+", "--tets 3000", command)
    command = re.sub(r"--photons (\d+)",
                     lambda m: "--photons %d" % min(int(m.group(1)), 200000), command)
    if " --photons " not in command and re.search(r"--solvers \S*montecarlo", command):
        command += " --photons 200000"
    if " --diffuse-optics" in command and " --gate-tets " not in command:
        command += " --gate-tets 3000"  # the time-gate table's own size (default 200000)
    if " --diffuse-optics" in command and " --gates " not in command:
        command += " --gates 10"  # of 100: 170 implicit steps, not 1,700
    if re.search(r"translucency bench\b", command) and " --runs " not in command:
        command += " --runs 1"  # one run per figure: this test checks it runs, not its medians
    return command


def make_data(folder):
    """The scratch checkout's Data/: the source tree's files (links), but for the
    test's sizes a coarser bunny.ply (see the module doc)."""
    source = os.path.join(SOURCE_DIR, "Data")
    if FULL:
        os.symlink(source, folder)
        return
    os.mkdir(folder)
    for name in os.listdir(source):
        if name != "bunny.ply":
            os.symlink(os.path.join(source, name), os.path.join(folder, name))
    from vtkmodules.vtkFiltersCore import vtkQuadricDecimation
    from vtkmodules.vtkIOPLY import vtkPLYReader, vtkPLYWriter
    reader = vtkPLYReader()
    reader.SetFileName(os.path.join(source, "bunny.ply"))
    decimate = vtkQuadricDecimation()
    decimate.SetInputConnection(reader.GetOutputPort())
    decimate.SetTargetReduction(COARSE_BUNNY_REDUCTION)
    decimate.VolumePreservationOn()
    writer = vtkPLYWriter()
    writer.SetFileName(os.path.join(folder, "bunny.ply"))
    writer.SetInputConnection(decimate.GetOutputPort())
    if not writer.Write():
        raise RuntimeError("could not write the coarse bunny into " + folder)


def promised_outputs(command):
    """The paths the command writes, by its output options."""
    words = shlex.split(command)
    return [words[i + 1] for i, w in enumerate(words[:-1]) if w in OUTPUT_OPTIONS]


def exists_and_not_empty(path):
    """A file with content, a non-empty directory, or PREFIX.* / PREFIX_* files."""
    if os.path.isdir(path):
        return bool(os.listdir(path))
    if os.path.isfile(path):
        return os.path.getsize(path) > 0
    folder, prefix = os.path.split(path)
    folder = folder or "."
    return os.path.isdir(folder) and any(
        (name.startswith(prefix + ".") or name.startswith(prefix + "_")) and
        os.path.getsize(os.path.join(folder, name)) > 0 for name in os.listdir(folder))


class ReadmeBlocksTest(unittest.TestCase):

    def test_every_sh_block_runs(self):
        with open(os.path.join(SOURCE_DIR, "README.md")) as f:
            blocks = sh_blocks(f.read())
        self.assertGreaterEqual(len(blocks), 8, "README.md lost its command blocks?")
        scratch = tempfile.mkdtemp(prefix="translucency_readme_")
        make_data(os.path.join(scratch, "Data"))
        os.symlink(BUILD_DIR, os.path.join(scratch, "build"))
        env = dict(os.environ, OMP_NUM_THREADS=os.environ.get("OMP_NUM_THREADS", "2"))
        ran, skipped = 0, []
        for number, commands in enumerate(blocks, 1):
            script = ["set -e"]
            outputs = []
            for command in commands:
                reason = next((r for p, r in SKIPPED if re.search(p, command)), None)
                if reason:
                    skipped.append((command, reason))
                    continue
                command = smaller(command)
                script.append(command)
                outputs += promised_outputs(command)
                ran += 1
            if len(script) == 1:
                continue
            with self.subTest(block=number, commands=script[1:]):
                start = time.perf_counter()
                result = subprocess.run(["bash", "-c", "\n".join(script)], cwd=scratch, env=env,
                                        stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                        universal_newlines=True)
                print("block %d: %.1f s (%s)" % (number, time.perf_counter() - start,
                                                 "; ".join(script[1:])[:160]), flush=True)
                self.assertEqual(result.returncode, 0, "block %d failed:\n%s\n%s\n%s" % (
                    number, "\n".join(script[1:]), result.stdout[-3000:], result.stderr[-3000:]))
                for path in outputs:
                    self.assertTrue(exists_and_not_empty(os.path.join(scratch, path)),
                                    "block %d promised %s" % (number, path))
        print("ran %d commands; not run: %s" % (
            ran, "; ".join("%s (%s)" % (c, r) for c, r in skipped)))
        self.assertGreaterEqual(ran, 10)
        # make demo, make test, make test-all, paraview, cmake --install: each says why.
        self.assertEqual(len(skipped), 5, skipped)


if __name__ == "__main__":
    unittest.main(verbosity=2)
