#!/usr/bin/env python3
"""Bad sizes and numbers on the `translucency` command line (issue 21).

Each case runs the CLI on a small cube (written here) with one hostile value
and asserts: a non-zero exit (no signal), under 10 s, a message on stderr
naming the option (or field) and the value, and an existing output file left
untouched. Then the values that must work: a denormal light power (1e-320)
parses, and --memory-limit lifts a size limit.

How to run (from a build tree; ctest sets the variables itself):

    TRANSLUCENCY_CLI=<build>/bin/translucency /usr/bin/python3 TestBadNumbers.py
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

CLI = find_cli("TestBadNumbers")
CUBE_OBJ = """v 0 0 0
v 10 0 0
v 10 10 0
v 0 10 0
v 0 0 10
v 10 0 10
v 10 10 10
v 0 10 10
f 1 3 2
f 1 4 3
f 5 6 7
f 5 7 8
f 1 2 6
f 1 6 5
f 2 3 7
f 2 7 6
f 3 4 8
f 3 8 7
f 4 1 5
f 4 5 8
"""
SENTINEL = "existing output: must not be replaced\n"


def scene(**changes):
    s = {
        "cell_size": 5.0,
        "objects": [
            {"name": "room", "type": "box", "min": [0, 0, 0], "max": [20, 20, 20],
             "inward": True, "albedo": 0.7},
        ],
        "lights": [{"type": "point", "position": [10, 10, 15], "power": 100}],
        "radiosity": {"rays_per_patch": 16, "max_iter": 20},
    }
    for key, value in changes.items():
        if key in ("rays_per_patch", "max_iter"):
            s["radiosity"][key] = value
        elif key == "box_max":
            s["objects"][0]["max"] = value
        elif key == "power":
            s["lights"][0]["power"] = value
        elif key == "translucent":
            s["objects"][0]["translucent"] = value
        else:
            s[key] = value
    return s


class BadNumbers(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.mkdtemp(prefix="badnumbers-")
        cls.mesh = os.path.join(cls.dir, "cube.obj")
        with open(cls.mesh, "w") as f:
            f.write(CUBE_OBJ)

    def run_cli(self, args, timeout=10):
        start = time.monotonic()
        p = subprocess.run([CLI] + args, capture_output=True, text=True, timeout=timeout)
        return p, time.monotonic() - start

    def expect_refused(self, args, *needles, outputs=()):
        for path in outputs:
            with open(path, "w") as f:
                f.write(SENTINEL)
        p, seconds = self.run_cli(args)
        message = p.stderr + p.stdout
        self.assertGreater(p.returncode, 0, f"{args}: exit {p.returncode}\n{message}")
        self.assertLess(seconds, 10.0, f"{args}: took {seconds:.1f} s")
        for needle in needles:
            self.assertIn(needle, message, f"{args}: the message does not name '{needle}'")
        for path in outputs:
            with open(path) as f:
                self.assertEqual(f.read(), SENTINEL, f"{args}: {path} was replaced")
        return message

    def render(self, *extra):
        prefix = os.path.join(self.dir, "out")
        target = [] if "--target-tets" in extra or "--max-tet-volume" in extra else [
            "--target-tets", "300"]
        args = ["render", "--mesh", self.mesh, "--output", prefix,
                "--json", prefix + ".json"] + target + list(extra)
        return args, [prefix + ".vtu", prefix + ".json"]

    def test_render_sizes(self):
        for option, value, needles in [
            ("--target-tets", "1e12", ["1e+12 tets", "--memory-limit"]),
            ("--target-tets", "1e30", ["--target-tets", "1e+30"]),
            ("--target-tets", "2.5", ["--target-tets", "2.5"]),
            ("--target-tets", "9223372036854775808", ["--target-tets", "9223372036854775808"]),
            ("--max-tet-volume", "1e-300", ["MaxTetVolume 1e-300", "--memory-limit"]),
            ("--uniform-samples", "1e9", ["--uniform-samples", "4096"]),
            ("--uniform-samples", "1e18", ["--uniform-samples", "1e+18"]),
            ("--max-iter", "1e300", ["--max-iter", "1e+300"]),
        ]:
            with self.subTest(option=option, value=value):
                args, outputs = self.render(option, value)
                self.expect_refused(args, *needles, outputs=outputs)

    def test_photons(self):
        args, outputs = self.render("--solver", "montecarlo", "--photons", "1e18")
        self.expect_refused(args, "photons", "1e+18", outputs=outputs)
        args, outputs = self.render("--solver", "montecarlo", "--photons", "1e12")
        self.expect_refused(args, "1000000000000 photons", "--photons", "--allow-long-runs",
                            outputs=outputs)
        args, outputs = self.render("--solver", "montecarlo", "--photons", "1e30")
        self.expect_refused(args, "--photons", "1e+30", outputs=outputs)

    def test_light_overflow(self):
        args, outputs = self.render("--light", "directional:0,-1,-1:1e300")
        self.expect_refused(args, "not finite", "light power", outputs=outputs)
        args, outputs = self.render("--light", "directional:0,-1,-1:1e309")
        self.expect_refused(args, "--light", "1e309", outputs=outputs)

    def test_denormal_light_parses(self):
        args, _ = self.render("--light", "directional:0,-1,-1:1e-320")
        p, _ = self.run_cli(args, timeout=60)
        self.assertNotIn("is not a number", p.stderr)
        self.assertEqual(p.returncode, 0, p.stderr)

    def test_scaled_model_warns(self):
        # A 10 mm cube scaled by 1e6: tets ~1e6 x the mean free path, the
        # boundary fluence is unresolved and eq. 3 clamps Radiance to 0
        # everywhere: a warning must name the scale.
        scaled = os.path.join(self.dir, "cube_scaled.obj")
        with open(scaled, "w") as f:
            for line in CUBE_OBJ.splitlines():
                if line.startswith("v "):
                    line = "v " + " ".join(str(float(x) * 1e6) for x in line.split()[1:])
                f.write(line + "\n")
        prefix = os.path.join(self.dir, "scaled")
        # The surface model: its eq. 3 clamps to 0 everywhere on such a mesh,
        # which is what the warning detects (the extended models' volume
        # source gives a nonzero, equally meaningless, radiance there).
        p, _ = self.run_cli(["render", "--mesh", scaled, "--target-tets", "300",
                             "--collimated", "surface", "--output", prefix], timeout=60)
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertIn("Radiance is 0 at every boundary point", p.stderr)
        self.assertIn("is the model in mm?", p.stderr)
        # The unscaled cube gives no such warning.
        args, _ = self.render()
        p, _ = self.run_cli(args, timeout=60)
        self.assertNotIn("Radiance is 0", p.stderr)

    def test_memory_limit_override(self):
        # 2e4 tets are ~8 MB by the estimate: refused at 1 MiB, accepted at 0.5 GiB.
        args, outputs = self.render("--memory-limit", "0.0009765625", "--target-tets", "20000")
        message = self.expect_refused(args, "--memory-limit", outputs=outputs)
        self.assertIn("2e+04 tets", message)
        args, _ = self.render("--memory-limit", "0.5", "--target-tets", "20000")
        p, _ = self.run_cli(args, timeout=60)
        self.assertEqual(p.returncode, 0, p.stderr)
        args, outputs = self.render("--memory-limit", "nan")
        self.expect_refused(args, "--memory-limit", "nan", outputs=outputs)

    def write_scene(self, name, data):
        path = os.path.join(self.dir, name)
        with open(path, "w") as f:
            json.dump(data, f)
        return path

    def test_radiosity(self):
        prefix = os.path.join(self.dir, "rad")
        outputs = [prefix + "_0.vtp"]
        for name, data, needles in [
            # Refused by the scene file's own bounds (Apps/SceneFile) before the
            # memory estimate is reached: a patch cap and a +-1e6 mm coordinate range.
            ("cell.json", scene(cell_size=1e-3), ["cell_size 0.001", "patches"]),
            ("huge.json", scene(box_max=[1.5e13, 1.5e13, 1.5e13]), ['"max"', "15000000000000", "1e6"]),
            ("rays.json", scene(rays_per_patch=1e9), ["1000000000 rays per patch",
                                                      "--allow-long-runs"]),
            ("rays2.json", scene(rays_per_patch=1e12), ["rays_per_patch", "1000000000000"]),
            ("iter.json", scene(max_iter=1e300), ["max_iter", "1e+300"]),
            # A fuzzer finding: a value of the wrong JSON type was an uncaught
            # nlohmann exception, not a scene error naming the object.
            ("type.json", scene(translucent=[]), ["type.json", "object 0 'room'", "wrong JSON type"]),
            ("power.json", scene(power=1e308), ["radiosity B", "overflow", "light power"]),
        ]:
            with self.subTest(scene=name):
                path = self.write_scene(name, data)
                self.expect_refused(["radiosity", "--scene", path, "--output", prefix],
                                    *needles, outputs=outputs)

    def test_acquire(self):
        prefix = os.path.join(self.dir, "acq")
        truth = os.path.join(self.dir, "truth.vti")
        with open(truth, "w") as f:
            f.write("{}")
        for grid, patterns, needles in [
            ("200x200x200", "4x4", ["--grid 200x200x200", "--memory-limit"]),
            ("10x10x10", "1000x1000", ["--patterns 1000x1000", "1e+06 patterns", "4096"]),
            ("40x40x40", "64x64", ["--grid 40x40x40", "--patterns 64x64", "--memory-limit"]),
            # Fits in memory, but would run for half an hour: the work budget.
            # The message gives the fit's estimated CPU time (measured here).
            ("100x100x100", "2x2", ["--grid 100x100x100", "above the budget", "of CPU",
                                    "if all 100 iterations run", "--allow-long-runs"]),
        ]:
            with self.subTest(grid=grid, patterns=patterns):
                self.expect_refused(["acquire", "--synthetic-truth", truth, "--grid", grid,
                                     "--patterns", patterns, "--output", prefix],
                                    *needles, outputs=[prefix + ".vtu"])

        # --allow-long-runs lifts the work budget (the run then goes on to read
        # the truth file, which is not a VTK file) but not the memory limit.
        message = self.expect_refused(
            ["acquire", "--allow-long-runs", "--synthetic-truth", truth, "--grid", "100x100x100",
             "--patterns", "2x2", "--output", prefix], "truth.vti", outputs=[prefix + ".vtu"])
        self.assertNotIn("above the budget", message)
        self.expect_refused(
            ["acquire", "--allow-long-runs", "--synthetic-truth", truth, "--grid", "200x200x200",
             "--patterns", "4x4", "--output", prefix], "--memory-limit", outputs=[prefix + ".vtu"])


if __name__ == "__main__":
    unittest.main(argv=sys.argv[:1], verbosity=2)
