#!/usr/bin/env python3
"""Seeded mutation loop over the numeric options of the `translucency` CLI (issue 21).

Each case takes a small valid command line (render, compare, radiosity, acquire
or bench on a cube / a small scene written here) and replaces the value of one
or two numeric options with a hostile one (0, -1, NaN, inf, 2^31, 2^63, 1e308,
1e-320, huge counts, ...), runs it with a timeout and classifies the outcome:

  clean error   exit 1 or 2 with a "translucency: ..." message on stderr
  success       exit 0 and no NaN/inf in the JSON report or the written .vtu/.vtp
  non-finite    exit 0 but a NaN/inf in the outputs (a silently wrong number)
  crash         killed by a signal, or another exit code, or no message
  hang          the timeout was reached

    /usr/bin/python3 scripts/mutate_options.py --cli build/bin/translucency \\
        --cases 2000 --seed 1 --timeout 20 --jobs 2

Prints the counts and every case that is not a clean error or a success;
exits 1 if there is a crash, hang or non-finite output.
"""

import argparse
import collections
import concurrent.futures
import json
import math
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile

CUBE_OBJ = "\n".join(
    ["v 0 0 0", "v 10 0 0", "v 10 10 0", "v 0 10 0", "v 0 0 10", "v 10 0 10", "v 10 10 10",
     "v 0 10 10", "f 1 3 2", "f 1 4 3", "f 5 6 7", "f 5 7 8", "f 1 2 6", "f 1 6 5", "f 2 3 7",
     "f 2 7 6", "f 3 4 8", "f 3 8 7", "f 4 1 5", "f 4 5 8"]) + "\n"

HOSTILE = ["0", "-1", "nan", "NaN", "inf", "-inf", "2147483648", "2147483647", "4294967296",
           "9223372036854775807", "9223372036854775808", "18446744073709551616", "1e308",
           "-1e308", "1e309", "1e-320", "-1e-320", "4.9e-324", "1e-300", "1e9", "1e12", "1e18",
           "1e30", "1e300", "0.5", "2.5", "-0", "1e", "0x10", " 1", "1,2", ""]

# Numeric options per command: name -> how many comma-separated numbers it takes.
OPTIONS = {
    "render": {"--target-tets": 1, "--max-tet-volume": 1, "--quality": 1,
               "--uniform-samples": 1, "--rel-tol": 1, "--max-iter": 1, "--grid-spacing": 1,
               "--photons": 1, "--exposure": 1, "--view": 3, "--up": 3, "--cut-plane": 6,
               "--memory-limit": 1, "--light-power": 1, "--size": 1,
               # Diffuse optics and meshers (session 17): compound values are
               # built in run_case with one hostile part.
               "--frequency": 1, "--uniform-size": 1, "--source-point": 1,
               "--source-pencil": 1, "--detector": 1, "--hxt-target-tets": 1,
               # Time gates T0,dt,T1 with one hostile part, on a pencil beam
               # (issue 34: 0,1e-320,10 and 0,1e308,10 gave exit 0 with NaN).
               "--time-gates": 1},
    "compare": {"--target-tets": 1, "--max-tet-volume": 1, "--uniform-samples": 1,
                "--rel-tol": 1, "--seed": 1, "--photons": 1, "--grid-spacing": 1,
                "--memory-limit": 1, "--light-power": 1, "--time-gates": 1},
    "radiosity": {"--rel-tol": 1, "--rays": 1, "--cell-size": 1, "--bench": 1,
                  "--memory-limit": 1, "cell_size": 1, "rays_per_patch": 1, "max_iter": 1,
                  "power": 1, "max_tet_volume": 1, "target_tets": 1},
    "acquire": {"--lambda": 1, "--max-iter": 1, "--threshold": 1, "--noise": 1, "--seed": 1,
                "--initial-mua": 1, "--initial-sigmas": 1, "--grid": 1, "--patterns": 1,
                "--memory-limit": 1},
    "bench": {"--tets": 1, "--runs": 1, "--hypre-ranks": 1, "--memory-limit": 1},
}


def base_case(command, work):
    """(args, outputs, scene dict or None) of a small valid run."""
    out = os.path.join(work, "out")
    mesh = os.path.join(work, "..", "cube.obj")
    if command == "render":
        return {"--mesh": mesh, "--target-tets": "200", "--output": out,
                "--json": out + ".json", "--max-iter": "2000"}, [out + ".vtu", out + ".json"]
    if command == "compare":
        return {"--mesh": mesh, "--target-tets": "200", "--solvers": "divergence,fem",
                "--no-png": None, "--json": out + ".json", "--output": out,
                "--photons": "2000"}, [out + ".json"]
    if command == "radiosity":
        return {"--scene": os.path.join(work, "scene.json"), "--output": out,
                "--json": out + ".json"}, [out + "_0.vtp", out + ".json"]
    if command == "acquire":
        return {"--synthetic-truth": os.path.join(work, "..", "truth.vti"), "--grid": "3x3x2",
                "--patterns": "2x2", "--output": out, "--json": out + ".json", "--no-png": None,
                "--max-iter": "5"}, [out + ".vtu", out + ".json"]
    return {"--mesh": mesh, "--tets": "200", "--runs": "1", "--json": out + ".json"}, [
        out + ".json"]


def to_json_value(text):
    """The hostile text as a JSON number if it is one (huge integers stay
    exact, 1e309 is read as inf and written as Infinity), else as a string."""
    try:
        return json.loads(text)
    except ValueError:
        try:
            return float(text)
        except ValueError:
            return text


def scene(changes):
    s = {"cell_size": 5.0,
         "objects": [{"name": "room", "type": "box", "min": [0, 0, 0], "max": [20, 20, 20],
                      "inward": True, "albedo": 0.7},
                     {"name": "block", "type": "box", "min": [5, 5, 0.5], "max": [10, 10, 6],
                      "translucent": True, "material": "marble", "target_tets": 200}],
         "lights": [{"type": "point", "position": [10, 10, 15], "power": 100}],
         "radiosity": {"rays_per_patch": 16, "max_iter": 20}}
    for key, value in changes.items():
        number = to_json_value(value)
        if key in ("rays_per_patch", "max_iter"):
            s["radiosity"][key] = number
        elif key == "power":
            s["lights"][0]["power"] = number
        elif key in ("max_tet_volume", "target_tets"):
            s["objects"][1].pop("target_tets", None)
            s["objects"][1][key] = number
        else:
            s[key] = number
    return s


def hostile_value(rng, option, count):
    v = rng.choice(HOSTILE)
    if option in ("--grid",):
        return rng.choice(["100000x100000x100000", "0x1x1", "2147483648x1x1", "1000x1000x1000",
                           "200x200x200", "-1x2x2", v])
    if option == "--patterns":
        return rng.choice(["100000x100000", "1000x1000", "0x1", v])
    if option == "--size":
        return rng.choice(["2147483648x16", "16x99999999999", "0x0", "-16x16", v])
    if count > 1 and v not in ("", "1,2"):
        return ",".join([v] + ["1"] * (count - 1))
    return v


def finite_outputs(paths):
    """False if a written JSON report or VTK file holds a NaN/inf."""
    for path in paths:
        if not os.path.exists(path):
            continue
        if path.endswith(".json"):
            text = open(path).read()
            if re.search(r"\b(NaN|nan|Infinity|inf)\b", text):
                return False
        else:
            try:
                import numpy as np
                from vtkmodules.util.numpy_support import vtk_to_numpy
                from vtkmodules.vtkIOXML import vtkXMLGenericDataObjectReader
            except ImportError:
                continue
            r = vtkXMLGenericDataObjectReader()
            r.SetFileName(path)
            r.Update()
            data = r.GetOutput()
            for attributes in (data.GetPointData(), data.GetCellData()):
                for k in range(attributes.GetNumberOfArrays()):
                    a = attributes.GetArray(k)
                    if a is not None and a.GetDataType() in (10, 11):
                        if not np.all(np.isfinite(vtk_to_numpy(a))):
                            return False
    return True


COMMANDS = []  # --commands: restrict the commands mutated
ONLY = []  # --only: restrict the options mutated


def run_case(args):
    cli, root, index, seed, timeout = args
    rng = random.Random(seed * 1000003 + index)
    command = rng.choice(COMMANDS or list(OPTIONS))
    work = os.path.join(root, f"case{index}")
    os.makedirs(work, exist_ok=True)
    options, outputs = base_case(command, work)
    pool = [o for o in OPTIONS[command] if not ONLY or o in ONLY] or list(OPTIONS[command])
    chosen = rng.sample(pool, k=min(len(pool), rng.choice([1, 1, 2])))
    scene_changes = {}
    mutated = []
    for option in chosen:
        value = hostile_value(rng, option, OPTIONS[command][option])
        mutated.append(f"{option}={value!r}")
        if not option.startswith("--"):
            scene_changes[option] = value
        elif option == "--light-power":
            options["--light"] = f"directional:0,-1,-1:{value}"
        elif option == "--source-point":
            options["--source"] = rng.choice([f"point:5,5,{value}:1", f"point:5,5,5:{value}",
                                              f"point:{value},5,5"])
        elif option == "--source-pencil":
            options["--source"] = rng.choice([f"pencil:5,5,10:0,0,-1:{value}",
                                              f"pencil:5,5,{value}:0,0,-1",
                                              f"pencil:5,5,10:0,0,{value}"])
        elif option == "--detector":
            options["--detector"] = rng.choice([f"5,5,10:{value}", f"5,{value},10"])
        elif option == "--time-gates":
            options["--time-gates"] = rng.choice([f"0,{value},10", f"{value},1,10",
                                                  f"0,1,{value}", f"0,{value},{value}"])
            options["--source"] = "pencil:5,5,10:0,0,-1"
            options["--detector"] = "8,5,10"
            if command == "compare":
                options["--solvers"] = "divergence"
                options.pop("--photons", None)
        elif option == "--hxt-target-tets":
            options["--mesher"] = "hxt"
            options["--target-tets"] = value
        else:
            options[option] = value
    if command == "radiosity":
        with open(options["--scene"], "w") as f:
            json.dump(scene(scene_changes), f)
    argv = [cli, command]
    for k, v in options.items():
        argv += [k] if v is None else [k, v]
    try:
        p = subprocess.run(argv, capture_output=True, text=True, timeout=timeout, cwd=work)
    except subprocess.TimeoutExpired:
        shutil.rmtree(work, ignore_errors=True)
        return "hang", command, mutated, ""
    if p.returncode < 0:
        kind = "crash"
    elif p.returncode in (1, 2) and "translucency:" in p.stderr:
        kind = "clean error"
    elif p.returncode == 0:
        kind = "success" if finite_outputs(outputs) else "non-finite output"
    else:
        kind = "crash"
    shutil.rmtree(work, ignore_errors=True)
    return kind, command, mutated, (p.stderr.strip().splitlines() or [""])[-1][:200]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cli", default="build/bin/translucency")
    parser.add_argument("--cases", type=int, default=2000)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--timeout", type=float, default=20.0)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--commands", default="", help="comma-separated commands to mutate")
    parser.add_argument("--only", default="", help="comma-separated options to mutate")
    a = parser.parse_args()
    COMMANDS[:] = [c for c in a.commands.split(",") if c]
    ONLY[:] = [o for o in a.only.split(",") if o]
    root = tempfile.mkdtemp(prefix="mutate-options-")
    with open(os.path.join(root, "cube.obj"), "w") as f:
        f.write(CUBE_OBJ)
    # A tiny synthetic truth for acquire (a .vti with the two coefficient arrays).
    try:
        from vtkmodules.vtkCommonDataModel import vtkImageData
        from vtkmodules.vtkCommonCore import vtkDoubleArray
        from vtkmodules.vtkIOXML import vtkXMLImageDataWriter
        image = vtkImageData()
        image.SetDimensions(4, 4, 3)
        image.SetSpacing(1, 1, 1)
        for name, value in (("AbsorptionCoefficient", 0.01), ("ReducedScatteringCoefficient", 1.0)):
            arr = vtkDoubleArray()
            arr.SetName(name)
            arr.SetNumberOfComponents(3)
            for _ in range(image.GetNumberOfCells()):
                arr.InsertNextTuple3(value, value, value)
            image.GetCellData().AddArray(arr)
        w = vtkXMLImageDataWriter()
        w.SetFileName(os.path.join(root, "truth.vti"))
        w.SetInputData(image)
        w.Write()
    except ImportError:
        pass
    counts = collections.Counter()
    per_command = collections.defaultdict(collections.Counter)
    bad = []
    jobs = [(os.path.abspath(a.cli), root, i, a.seed, a.timeout) for i in range(a.cases)]
    with concurrent.futures.ThreadPoolExecutor(a.jobs) as pool:
        for kind, command, mutated, last in pool.map(run_case, jobs):
            counts[kind] += 1
            per_command[command][kind] += 1
            if kind not in ("clean error", "success"):
                bad.append((kind, command, mutated, last))
    shutil.rmtree(root, ignore_errors=True)
    print(f"{a.cases} cases (seed {a.seed}, timeout {a.timeout} s):")
    for kind in ("clean error", "success", "crash", "hang", "non-finite output"):
        print(f"  {kind:18s} {counts[kind]}")
    for command, c in sorted(per_command.items()):
        print(f"  {command:10s} " + ", ".join(f"{k} {v}" for k, v in sorted(c.items())))
    for kind, command, mutated, last in bad:
        print(f"{kind}: {command} {' '.join(mutated)}: {last}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
