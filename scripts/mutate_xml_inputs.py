#!/usr/bin/env python3
"""Mutation loop over the file inputs of the `translucency` command line.

Seeded: the same --seed gives the same cases. Base inputs are generated here
(a 48-tet .vtu in four data modes, a sphere .vtp in two, a material table, a
material, a paint stroke, a cut stroke, a small radiosity scene, the cube as
TetGen .node/.ele, acquire's measurements .vtu (made by the CLI) and truth
.vti, and compare's --measured CSV); each case mutates one of them (a TetGen
file next to its intact partner) and runs the CLI in a subprocess with a
timeout:

    /usr/bin/python3 scripts/mutate_xml_inputs.py --cli build/bin/translucency \\
        --cases 3000 --seed 1 --jobs 2 --keep /tmp/mutants

Mutations: numbers replaced by 0, -1, NaN, inf, 2^31, 2^63, 1e308, 1e-320;
XML attributes changed, removed or duplicated; lines deleted, duplicated,
swapped; truncation; bit flips; non-UTF-8 bytes; for JSON also wrong types,
missing and duplicate keys, huge arrays and deep nesting.

Outcomes per input kind: clean error (non-zero exit with a "translucency:
error" message), success, crash (killed by a signal), hang (timeout), exit 0
with non-finite output (NaN/inf in an output array or the JSON report), and
"error without message" (non-zero exit, no message). Crashing and hanging
inputs are kept in --keep for regression cases. Exits 1 if any case crashed,
hung or gave non-finite output.
"""

import argparse
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

SPECIAL_NUMBERS = ["0", "-1", "NaN", "nan", "inf", "-inf", "Infinity", "2147483648",
                   "9223372036854775808", "1e308", "1e-320", "4294967296", "-2147483649"]
TIMEOUT = 30.0
import threading
VTK_LOCK = threading.Lock()  # the output check reads with VTK: one thread at a time


# -- base inputs ------------------------------------------------------------------
def cube_grid():
    from vtkmodules.vtkCommonCore import vtkIntArray, vtkPoints
    from vtkmodules.vtkCommonDataModel import VTK_TETRA, vtkUnstructuredGrid

    def pid(i, j, k):
        return i + 3 * j + 9 * k

    points = vtkPoints()
    for k in range(3):
        for j in range(3):
            for i in range(3):
                points.InsertNextPoint(5.0 * i, 5.0 * j, 5.0 * k)
    grid = vtkUnstructuredGrid()
    grid.SetPoints(points)
    ids = vtkIntArray()
    ids.SetName("Ids")
    for k in range(2):
        for j in range(2):
            for i in range(2):
                v = [pid(i + a, j + b, k + c) for c in (0, 1) for b in (0, 1) for a in (0, 1)]
                for a, b in ((1, 3), (1, 5), (2, 3), (2, 6), (4, 5), (4, 6)):
                    grid.InsertNextCell(VTK_TETRA, 4, [v[0], v[a], v[a | b], v[7]])
                    ids.InsertNextValue(i)
    grid.GetCellData().AddArray(ids)
    return grid


# Files copied next to a mutated base (the other TetGen file): base -> [paths].
COMPANIONS = {}


def write_tetgen(grid, directory):
    """The grid as TetGen cube.node and cube.ele (1-based)."""
    node = os.path.join(directory, "cube.node")
    ele = os.path.join(directory, "cube.ele")
    with open(node, "w") as f:
        f.write("%d 3 0 0\n" % grid.GetNumberOfPoints())
        for i in range(grid.GetNumberOfPoints()):
            f.write("%d %g %g %g\n" % ((i + 1,) + grid.GetPoint(i)))
    with open(ele, "w") as f:
        f.write("%d 4 0\n" % grid.GetNumberOfCells())
        for c in range(grid.GetNumberOfCells()):
            ids = grid.GetCell(c).GetPointIds()
            f.write("%d %s\n" % (c + 1, " ".join(str(ids.GetId(k) + 1) for k in range(4))))
    return node, ele


def write_truth(directory):
    """acquire's --synthetic-truth: a 3 x 3 x 2 image with two materials."""
    from vtkmodules.vtkCommonCore import vtkDoubleArray
    from vtkmodules.vtkCommonDataModel import vtkImageData
    from vtkmodules.vtkIOXML import vtkXMLImageDataWriter
    image = vtkImageData()
    image.SetDimensions(4, 4, 3)
    image.SetSpacing(1.0, 1.0, 0.5)
    for name, values in (("AbsorptionCoefficient", (0.01, 0.05)),
                         ("ReducedScatteringCoefficient", (1.0, 0.7))):
        array = vtkDoubleArray()
        array.SetName(name)
        array.SetNumberOfComponents(3)
        for c in range(image.GetNumberOfCells()):
            v = values[c % 2]
            array.InsertNextTuple3(v, 1.5 * v, 2.0 * v)
        image.GetCellData().AddArray(array)
    path = os.path.join(directory, "truth.vti")
    w = vtkXMLImageDataWriter()
    w.SetInputData(image)
    w.SetFileName(path)
    w.SetDataModeToAscii()
    w.Write()
    return path


ACQUIRE_SYNTHETIC = ["--grid", "3x3x2", "--patterns", "1x2", "--max-iter", "2", "--no-png"]


def write_bases(directory, cli):
    """The base inputs: {kind: [(file name, args builder)]}."""
    from vtkmodules.vtkFiltersSources import vtkSphereSource
    from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter, vtkXMLUnstructuredGridWriter

    bases = {}
    grid = cube_grid()
    vtus = []
    for name, mode, zlib in (("ascii", 0, False), ("binary", 1, False), ("appended", 2, False),
                             ("zlib", 2, True)):
        w = vtkXMLUnstructuredGridWriter()
        w.SetInputData(grid)
        path = os.path.join(directory, "cube_%s.vtu" % name)
        w.SetFileName(path)
        w.SetDataMode(mode)
        if zlib:
            w.SetCompressorTypeToZLib()
        else:
            w.SetCompressorTypeToNone()
        w.SetEncodeAppendedData(False)
        w.Write()
        vtus.append(path)
    sphere = vtkSphereSource()
    sphere.SetRadius(5)
    sphere.SetThetaResolution(8)
    sphere.SetPhiResolution(8)
    sphere.Update()
    vtps = []
    for name, mode in (("ascii", 0), ("appended", 2)):
        w = vtkXMLPolyDataWriter()
        w.SetInputData(sphere.GetOutput())
        path = os.path.join(directory, "sphere_%s.vtp" % name)
        w.SetFileName(path)
        w.SetDataMode(mode)
        w.SetCompressorTypeToNone()
        w.SetEncodeAppendedData(False)
        w.Write()
        vtps.append(path)
    mesh = vtus[0]

    def write_json(name, value):
        path = os.path.join(directory, name)
        with open(path, "w") as f:
            json.dump(value, f, indent=2)
        return path

    table = write_json("table.json", {"units": "1/mm", "materials": [
        {"name": "a", "id": 0, "absorption": [0.01, 0.02, 0.03],
         "reduced_scattering": [1.0, 1.1, 1.2], "refractive_index": 1.3},
        {"name": "b", "id": 1, "preset": "marble"}]})
    material = write_json("material.json", {"absorption": [0.01, 0.02, 0.03],
                                            "reduced_scattering": [1.0, 1.1, 1.2],
                                            "refractive_index": 1.3})
    paint = write_json("paint.json", {"points": [[0, 0, 10], [10, 10, 10]], "width": 2,
                                      "mode": "set", "absorption": [0.1, 0.2, 0.3],
                                      "reduced_scattering": [2, 2, 2], "strength": 1,
                                      "channels": [1, 1, 1], "cutoff_weight": 1e-6})
    stroke = write_json("stroke.json", {"points": [[-1, 5.5, 5], [11, 5.5, 5]],
                                        "view_direction": [0, 0, -1], "inside_out": False})
    scene = write_json("scene.json", {
        "cell_size": 6,
        "objects": [
            {"name": "room", "type": "box", "min": [0, 0, 0], "max": [30, 30, 30],
             "inward": True, "open_face": "-y", "albedo": [0.7, 0.7, 0.7],
             "face_albedo": {"-x": [0.6, 0.1, 0.1]}},
            {"name": "block", "type": "box", "translucent": True, "min": [10, 10, 0.05],
             "max": [18, 18, 8], "material": "marble", "max_tet_volume": 8}],
        "lights": [{"type": "point", "position": [15, 15, 28], "power": [500, 500, 500]}],
        "camera": {"position": [15, -40, 15], "focal_point": [15, 15, 15],
                   "view_up": [0, 0, 1], "view_angle": 32}})

    render = ["render"]
    bases["vtu"] = [(p, lambda f: render + ["--mesh", f]) for p in vtus]
    bases["vtp"] = [(p, lambda f: render + ["--mesh", f, "--target-tets", "200"]) for p in vtps]
    bases["material-table"] = [(table, lambda f: render + ["--mesh", mesh, "--material", f,
                                                           "--material-ids", "Ids"])]
    bases["material"] = [(material, lambda f: render + ["--mesh", mesh, "--material", f])]
    bases["paint"] = [(paint, lambda f: render + ["--mesh", mesh, "--paint", f])]
    bases["stroke"] = [(stroke, lambda f: render + ["--mesh", mesh, "--cut-stroke", f])]
    bases["scene"] = [(scene, lambda f: ["radiosity", "--scene", f, "--rays", "8"])]

    node, ele = write_tetgen(grid, directory)
    COMPANIONS[node], COMPANIONS[ele] = [ele], [node]
    bases["tetgen"] = [(node, lambda f: render + ["--mesh", f]),
                       (ele, lambda f: render + ["--mesh", f[:-len(".ele")] + ".node"])]

    truth = write_truth(directory)
    bases["acquire-truth"] = [(truth, lambda f: ["acquire", "--synthetic-truth", f] +
                               ACQUIRE_SYNTHETIC)]
    made = subprocess.run([cli, "acquire", "--synthetic-truth", truth] + ACQUIRE_SYNTHETIC +
                          ["--output", os.path.join(directory, "syn"), "--quiet"],
                          capture_output=True, text=True, timeout=300)
    if made.returncode != 0:
        raise RuntimeError("acquire's base measurements: " + made.stderr)
    measurements = os.path.join(directory, "syn_measurements.vtu")
    bases["acquire-sample"] = [(measurements, lambda f: ["acquire", "--sample", f, "--patterns",
                                                         f, "--max-iter", "2", "--no-png"])]

    measured = os.path.join(directory, "measured.csv")
    with open(measured, "w") as f:
        f.write("# one fibre, counts\nt_ns, fibre\n0, 1\n0.5, 30\n1.0, 25\n1.5, 8\n2.0, 2.5\n")
    bases["measured-csv"] = [(measured, lambda f: [
        "compare", "--mesh", mesh, "--solvers", "divergence", "--reference", "divergence",
        "--no-png", "--time-gates", "0,0.5,4", "--source", "pencil:5,5,10:0,0,-1",
        "--detector", "5,0,5", "--measured", f])]
    return bases


# -- mutations --------------------------------------------------------------------
NUMBER = re.compile(rb"(?<![A-Za-z_])-?\d+(\.\d+)?([eE][-+]?\d+)?")
ATTRIBUTE = re.compile(rb'([A-Za-z_]+)="([^"]*)"')


def replace_numbers(data, rng):
    matches = list(NUMBER.finditer(data[:200000]))
    if not matches:
        return data
    m = rng.choice(matches)
    return data[:m.start()] + rng.choice(SPECIAL_NUMBERS).encode() + data[m.end():]


def change_attribute(data, rng):
    matches = list(ATTRIBUTE.finditer(data[:100000]))
    if not matches:
        return data
    m = rng.choice(matches)
    choice = rng.randrange(5)
    if choice == 0:  # a special number
        new = m.group(1) + b'="' + rng.choice(SPECIAL_NUMBERS).encode() + b'"'
    elif choice == 1:  # removed
        new = b""
    elif choice == 2:  # duplicated
        new = m.group(0) + b" " + m.group(0)
    elif choice == 3:  # another word
        new = m.group(1) + b'="' + rng.choice([b"", b"ascii", b"binary", b"appended",
                                                b"Float64", b"Int8", b"UInt64", b"BigEndian",
                                                b"vtkZLibDataCompressor", b"x" * 1000,
                                                b"PolyData", b"ImageData"]) + b'"'
    else:  # an attribute of another element
        other = rng.choice(matches)
        new = m.group(0) + b" " + other.group(0)
    return data[:m.start()] + new + data[m.end():]


def line_edit(data, rng):
    lines = data.split(b"\n")
    if len(lines) < 2:
        return data
    i = rng.randrange(len(lines))
    j = rng.randrange(len(lines))
    op = rng.randrange(3)
    if op == 0:
        del lines[i]
    elif op == 1:
        lines.insert(i, lines[j])
    else:
        lines[i], lines[j] = lines[j], lines[i]
    return b"\n".join(lines)


def truncate(data, rng):
    return data[:rng.randrange(len(data) + 1)]


def bit_flips(data, rng):
    data = bytearray(data)
    for _ in range(rng.choice([1, 1, 2, 8, 32])):
        if data:
            i = rng.randrange(len(data))
            data[i] ^= 1 << rng.randrange(8)
    return bytes(data)


def non_utf8(data, rng):
    i = rng.randrange(len(data) + 1)
    return data[:i] + rng.choice([b"\xff\xfe", b"\xc3", b"\x80\x80", b"\x00", b"\xed\xa0\x80"]) + \
        data[i:]


def json_paths(value, path=()):
    yield path
    if isinstance(value, dict):
        for k, v in value.items():
            yield from json_paths(v, path + (k,))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            yield from json_paths(v, path + (i,))


def json_set(root, path, new):
    if not path:
        return new
    node = root
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = new
    return root


def json_mutation(data, rng):
    """A structural JSON mutation; returns bytes."""
    try:
        root = json.loads(data)
    except (ValueError, RecursionError):  # already broken by a text mutation
        return bit_flips(data, rng)
    paths = list(json_paths(root))
    path = rng.choice(paths)
    op = rng.randrange(6)
    if op == 0:  # wrong type
        new = rng.choice([None, True, "text", "", {}, [], [1, 2], {"a": 1}, 1.5, -1,
                          "x" * 100000])
        return json.dumps(json_set(root, path, new)).encode()
    if op == 1 and path:  # missing key / element
        node = root
        for key in path[:-1]:
            node = node[key]
        del node[path[-1]]
        return json.dumps(root).encode()
    if op == 2:  # duplicate key: text level, the last value differs
        text = json.dumps(root)
        keys = [m for m in re.finditer(r'"(\w+)": ', text)]
        if keys:
            m = rng.choice(keys)
            return (text[:m.start()] + '"%s": %s, ' % (m.group(1), rng.choice(
                ['"dup"', "-1", "[]", "null", "1e308"])) + text[m.start():]).encode()
        return text.encode()
    if op == 3:  # huge array
        n = rng.choice([10 ** 5, 10 ** 6])
        new = rng.choice([[0.5] * n, [[1, 2, 3]] * (n // 10), list(range(n))])
        return json.dumps(json_set(root, path, new)).encode()
    if op == 4:  # deep nesting
        depth = rng.choice([65, 1000, 100000])
        marker = "__DEEP__"
        text = json.dumps(json_set(root, path, marker))
        return text.replace('"%s"' % marker, "[" * depth + "1" + "]" * depth, 1).encode()
    # a special number where a number was
    numbers = [p for p in paths if isinstance(get(root, p), (int, float)) and
               not isinstance(get(root, p), bool)]
    if numbers:
        p = rng.choice(numbers)
        text = json.dumps(json_set(root, p, "__NUM__"))
        return text.replace('"__NUM__"', rng.choice(SPECIAL_NUMBERS), 1).encode()
    return json.dumps(root).encode()


def get(root, path):
    for key in path:
        root = root[key]
    return root


TEXT_MUTATIONS = [replace_numbers, line_edit, truncate, bit_flips, non_utf8]


def mutate(kind, data, rng):
    if kind in ("vtu", "vtp", "acquire-truth", "acquire-sample"):
        ops = TEXT_MUTATIONS + [change_attribute, change_attribute, replace_numbers]
    elif kind in ("tetgen", "measured-csv"):
        ops = TEXT_MUTATIONS + [replace_numbers, line_edit]
    else:
        ops = TEXT_MUTATIONS + [json_mutation] * 5
    out = data
    for _ in range(rng.choice([1, 1, 1, 2, 3])):
        out = rng.choice(ops)(out, rng)
    return out


# -- running ----------------------------------------------------------------------
def non_finite_output(prefix, kind):
    """True if an output array or the JSON report holds NaN or inf."""
    import numpy as np
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkIOXML import vtkXMLPolyDataReader, vtkXMLUnstructuredGridReader

    files = []
    if kind == "scene":
        k = 0
        while os.path.exists("%s_%d.vtp" % (prefix, k)):
            files.append("%s_%d.vtp" % (prefix, k))
            k += 1
    else:
        files = [prefix + ".vtu", prefix + ".vtp", prefix + "_measurements.vtu"]
    if kind == "measured-csv":
        table = os.path.join(prefix, "tpsf.csv")  # compare --output DIR
        if os.path.exists(table) and re.search(r"\b(nan|inf)\b", open(table).read(), re.I):
            return table
    for path in files:
        if not os.path.exists(path):
            continue
        reader = vtkXMLUnstructuredGridReader() if path.endswith(".vtu") else \
            vtkXMLPolyDataReader()
        reader.SetFileName(path)
        reader.Update()
        data = reader.GetOutput()
        for attributes in (data.GetPointData(), data.GetCellData()):
            for i in range(attributes.GetNumberOfArrays()):
                array = attributes.GetArray(i)
                if array is not None and array.GetNumberOfTuples() > 0 and \
                        not np.all(np.isfinite(vtk_to_numpy(array))):
                    return "%s: array %s" % (path, array.GetName())
    report = prefix + ".json"
    if os.path.exists(report):
        text = open(report).read()
        if re.search(r"\b(NaN|nan|Infinity|inf)\b", text):
            return report
    return None


def run_case(cli, workdir, index, kind, base, args_of, content, case_seed):
    data = mutate(kind, content, random.Random(case_seed))
    case_dir = os.path.join(workdir, "case_%05d" % index)
    os.makedirs(case_dir, exist_ok=True)
    path = os.path.join(case_dir, os.path.basename(base))
    with open(path, "wb") as f:
        f.write(data)
    for companion in COMPANIONS.get(base, []):
        shutil.copy(companion, case_dir)
    prefix = os.path.join(case_dir, "out")
    args = [cli] + args_of(path) + ["--output", prefix, "--json", prefix + ".json"]
    try:
        proc = subprocess.run(args, capture_output=True, timeout=TIMEOUT,
                              env=dict(os.environ, OMP_NUM_THREADS="1"))
    except subprocess.TimeoutExpired:
        return index, kind, "hang", "", path, args
    stderr = proc.stderr.decode("utf-8", "replace")
    if proc.returncode < 0:
        outcome = "crash"
    elif proc.returncode == 0:
        with VTK_LOCK:
            bad = non_finite_output(prefix, kind)
        outcome = "non-finite output" if bad else "success"
        stderr = bad or stderr
    elif "translucency: error" in stderr or "error:" in stderr.lower():
        outcome = "clean error"
    else:
        outcome = "error without message"
    return index, kind, outcome, stderr[-300:], path, args


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cli", required=True, help="the translucency executable")
    parser.add_argument("--cases", type=int, default=3000)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--keep", help="directory for crashing, hanging and non-finite inputs")
    parser.add_argument("--json", help="write the counts and the bad cases here")
    options = parser.parse_args()

    rng = random.Random(options.seed)
    workdir = tempfile.mkdtemp(prefix="mutate_xml_")
    try:
        bases = write_bases(workdir, options.cli)
        kinds = sorted(bases)
        contents = {p: open(p, "rb").read() for entries in bases.values() for p, _ in entries}
        # Each case mutates with a generator of its own (seeded from --seed), in
        # the worker: the same case is the same whatever the order of the runs.
        cases = []
        for index in range(options.cases):
            kind = kinds[index % len(kinds)]
            base, args_of = rng.choice(bases[kind])
            cases.append((index, kind, base, args_of, contents[base], rng.getrandbits(64)))
        counts = {k: {} for k in kinds}
        bad = []
        with concurrent.futures.ThreadPoolExecutor(options.jobs) as pool:
            futures = [pool.submit(run_case, options.cli, workdir, *c) for c in cases]
            for done, future in enumerate(concurrent.futures.as_completed(futures), 1):
                index, kind, outcome, message, path, args = future.result()
                counts[kind][outcome] = counts[kind].get(outcome, 0) + 1
                if outcome not in ("clean error", "success"):
                    bad.append({"case": index, "kind": kind, "outcome": outcome,
                                "message": message, "args": args[1:]})
                    print("case %d (%s): %s\n  %s" % (index, kind, outcome, message),
                          file=sys.stderr)
                    if options.keep:
                        os.makedirs(options.keep, exist_ok=True)
                        shutil.copy(path, os.path.join(
                            options.keep, "case_%05d_%s" % (index, os.path.basename(path))))
                shutil.rmtree(os.path.dirname(path), ignore_errors=True)
                if done % 250 == 0:
                    print("%d / %d cases" % (done, len(cases)), file=sys.stderr, flush=True)
    finally:
        shutil.rmtree(workdir, ignore_errors=True)

    outcomes = ["clean error", "success", "crash", "hang", "non-finite output",
                "error without message"]
    print("%-16s" % "input" + "".join("%12s" % o.split()[0] for o in outcomes))
    for kind in kinds:
        print("%-16s" % kind + "".join("%12d" % counts[kind].get(o, 0) for o in outcomes))
    print("(columns: %s)" % ", ".join(outcomes))
    if options.json:
        with open(options.json, "w") as f:
            json.dump({"seed": options.seed, "cases": options.cases, "counts": counts,
                       "bad": bad}, f, indent=2)
    failing = sum(1 for b in bad if b["outcome"] in ("crash", "hang", "non-finite output"))
    return 1 if failing else 0


if __name__ == "__main__":
    sys.exit(main())
