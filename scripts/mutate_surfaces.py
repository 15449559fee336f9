#!/usr/bin/env python3
"""Mutation loop over the surface formats: mutated PLY/STL/OBJ files through `translucency render`.

    /usr/bin/python3 scripts/mutate_surfaces.py --cli build/bin/translucency \
        [--cases 3000] [--seed 21] [--jobs 2] [--timeout 30] [--keep DIR]

Base files (made in a temporary directory with VTK's writers from Data/bunny.ply):
the bunny as ASCII PLY (Data/bunny.ply itself), binary little- and big-endian
PLY, ASCII and binary STL, and OBJ. Each case picks a base file and applies
one to three mutations (seeded: the same --seed gives the same files):
truncation, bit flips, inserted/deleted bytes, header counts set to
0/-1/2^31/2^63/1e10/huge, number tokens set to nan/inf/1e308/-1/huge,
face indices and list counts changed, non-UTF-8 bytes, header lines
duplicated/swapped/deleted, property types changed, body lines
duplicated/swapped/deleted. Then it runs

    translucency render --mesh <case> --quality 4 --max-tet-volume 1000 \
        --no-shadows --uniform-samples 1 --output <tmp>

with a timeout and counts, per format: clean errors (exit status 1, a
`translucency:` message, no traceback), successes (exit 0, finite output),
crashes (killed by a signal), hangs (timeout), exit 0 with NaN/inf in the
output, and unclean errors (another status or a traceback). Crashing, hanging,
NaN and unclean cases are copied to --keep (default: scripts/mutants-failed/)
for regression tests. Exits 1 if any of those was found.
"""

import argparse
import collections
import concurrent.futures
import os
import random
import shutil
import struct
import subprocess
import sys
import tempfile

import numpy as np

SOURCE_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BUNNY = os.path.join(SOURCE_DIR, "Data", "bunny.ply")

SPECIAL_COUNTS = [b"0", b"-1", b"1", b"2147483648", b"9223372036854775808", b"1e10",
                  b"18446744073709551616", b"900000000", b"4294967295"]
SPECIAL_NUMBERS = [b"nan", b"inf", b"-inf", b"1e308", b"-1e308", b"1e200", b"-1", b"0",
                   b"2147483647", b"2147483648", b"9223372036854775807",
                   b"99999999999999999999", b"1e-320", b"", b"x", b"1.5", b"-0", b"+3",
                   b"0x10", b"1e15", b"NaN"]
NON_UTF8 = [b"\xff", b"\xfe\xff", b"\xc3\x28", b"\x80", b"\xed\xa0\x80", b"\x00"]
PLY_TYPES = [b"char", b"uchar", b"short", b"ushort", b"int", b"uint", b"float", b"double",
             b"int8", b"float64", b"int128", b"list"]


def make_bases(directory):
    from vtkmodules.vtkIOGeometry import vtkOBJWriter, vtkSTLWriter
    from vtkmodules.vtkIOPLY import vtkPLYReader, vtkPLYWriter

    reader = vtkPLYReader()
    reader.SetFileName(BUNNY)
    reader.Update()
    bunny = reader.GetOutput()
    bases = {"ply_ascii": BUNNY}
    for name, big in (("ply_le", False), ("ply_be", True)):
        writer = vtkPLYWriter()
        writer.SetFileTypeToBinary()
        if big:
            writer.SetDataByteOrderToBigEndian()
        else:
            writer.SetDataByteOrderToLittleEndian()
        bases[name] = os.path.join(directory, name + ".ply")
        writer.SetFileName(bases[name])
        writer.SetInputData(bunny)
        writer.Write()
    for name, binary in (("stl_ascii", False), ("stl_binary", True)):
        writer = vtkSTLWriter()
        if binary:
            writer.SetFileTypeToBinary()
        else:
            writer.SetFileTypeToASCII()
        bases[name] = os.path.join(directory, name + ".stl")
        writer.SetFileName(bases[name])
        writer.SetInputData(bunny)
        writer.Write()
    writer = vtkOBJWriter()
    bases["obj"] = os.path.join(directory, "obj.obj")
    writer.SetFileName(bases["obj"])
    writer.SetInputData(bunny)
    writer.Write()
    out = {}
    for name, path in bases.items():
        with open(path, "rb") as f:
            out[name] = f.read()
    return out


def header_end(data):
    i = data.find(b"end_header\n")
    return -1 if i < 0 else i + len(b"end_header\n")


# ------------------------------------------------------------------ mutations
def m_truncate(rng, data, kind):
    return data[:rng.randrange(len(data) + 1)]


def m_bitflip(rng, data, kind):
    data = bytearray(data)
    for _ in range(rng.randint(1, 8)):
        if data:
            data[rng.randrange(len(data))] ^= 1 << rng.randrange(8)
    return bytes(data)


def m_bytes(rng, data, kind):
    i = rng.randrange(len(data) + 1)
    if rng.random() < 0.5:
        return data[:i] + bytes(rng.randrange(256) for _ in range(rng.randint(1, 16))) + data[i:]
    return data[:i] + data[i + rng.randint(1, 64):]


def m_count(rng, data, kind):
    if kind.startswith("ply"):
        end = header_end(data)
        head = data[:end if end > 0 else len(data)]
        lines = head.split(b"\n")
        elements = [k for k, l in enumerate(lines) if l.startswith(b"element ")]
        if not elements:
            return data
        k = rng.choice(elements)
        parts = lines[k].split(b" ")
        parts[-1] = rng.choice(SPECIAL_COUNTS + [str(rng.randrange(10**6)).encode()])
        lines[k] = b" ".join(parts)
        return b"\n".join(lines) + data[len(head):]
    if kind == "stl_binary" and len(data) >= 84:
        value = rng.choice([0, 2**32 - 1, 2**31, 3673, 3675, rng.randrange(2**32)])
        return data[:80] + struct.pack("<I", value) + data[84:]
    return m_number(rng, data, kind)


def tokens(data, start):
    """(begin, end) of the blank-separated tokens after `start` (sampled)."""
    spans = []
    i = start
    n = len(data)
    while i < n and len(spans) < 200000:
        while i < n and data[i] in b" \t\r\n":
            i += 1
        j = i
        while j < n and data[j] not in b" \t\r\n":
            j += 1
        if j > i:
            spans.append((i, j))
        i = j
    return spans


def m_number(rng, data, kind):
    if kind in ("ply_le", "ply_be", "stl_binary"):
        # A special float or int at a random aligned place of the binary part.
        start = header_end(data) if kind.startswith("ply") else 84
        if start <= 0 or start >= len(data) - 4:
            return m_bitflip(rng, data, kind)
        i = rng.randrange(start, len(data) - 4)
        order = ">" if kind == "ply_be" else "<"
        value = rng.choice([struct.pack(order + "f", float("nan")),
                            struct.pack(order + "f", float("inf")),
                            struct.pack(order + "f", 3e38), struct.pack(order + "i", -1),
                            struct.pack(order + "i", 2**31 - 1), struct.pack(order + "i", 1839),
                            b"\xff", b"\x00", b"\x02", b"\x04"])
        return data[:i] + value + data[i + len(value):]
    start = max(header_end(data), 0)
    spans = tokens(data, start)
    if not spans:
        return data
    b, e = rng.choice(spans)
    return data[:b] + rng.choice(SPECIAL_NUMBERS) + data[e:]


def m_face(rng, data, kind):
    """A face index or a list count in the text formats."""
    if kind not in ("ply_ascii", "obj"):
        return m_number(rng, data, kind)
    lines = data.split(b"\n")
    faces = [k for k, l in enumerate(lines) if (l.startswith(b"f ") if kind == "obj"
                                                else l.startswith(b"3 "))]
    if not faces:
        return data
    k = rng.choice(faces)
    parts = lines[k].split(b" ")
    j = rng.randrange(len(parts))
    if kind == "obj" and j == 0:
        parts = parts[:rng.randint(1, 3)]
    else:
        parts[j] = rng.choice([b"0", b"-1", b"1839", b"1840", b"-1840", b"2", b"4", b"255",
                               b"256", b"9223372036854775807", b"1/1", b"1//1", b"1/1/1/1",
                               b"1/", b"/1", b"-0", b"1.0", b"3e2"])
    lines[k] = b" ".join(parts)
    return b"\n".join(lines)


def m_non_utf8(rng, data, kind):
    i = rng.randrange(len(data) + 1)
    return data[:i] + rng.choice(NON_UTF8) + data[i:]


def m_header_lines(rng, data, kind):
    if not kind.startswith("ply"):
        return m_lines(rng, data, kind)
    end = header_end(data)
    if end <= 0:
        return m_lines(rng, data, kind)
    lines = data[:end - 1].split(b"\n")
    op = rng.choice(["dup", "swap", "del", "type"])
    i = rng.randrange(len(lines))
    if op == "dup":
        lines.insert(i, lines[i])
    elif op == "swap":
        j = rng.randrange(len(lines))
        lines[i], lines[j] = lines[j], lines[i]
    elif op == "del":
        del lines[i]
    else:
        props = [k for k, l in enumerate(lines) if l.startswith(b"property ")]
        if props:
            k = rng.choice(props)
            parts = lines[k].split(b" ")
            parts[rng.randrange(1, len(parts) - 1) if len(parts) > 2 else 1] = rng.choice(PLY_TYPES)
            lines[k] = b" ".join(parts)
    return b"\n".join(lines) + b"\n" + data[end:]


def m_lines(rng, data, kind):
    if kind in ("ply_le", "ply_be", "stl_binary"):
        return m_bytes(rng, data, kind)
    lines = data.split(b"\n")
    op = rng.choice(["dup", "swap", "del"])
    i = rng.randrange(len(lines))
    if op == "dup":
        lines.insert(i, lines[i])
    elif op == "swap":
        j = rng.randrange(len(lines))
        lines[i], lines[j] = lines[j], lines[i]
    else:
        del lines[i]
    return b"\n".join(lines)


MUTATIONS = [m_truncate, m_bitflip, m_bytes, m_count, m_number, m_face, m_non_utf8,
             m_header_lines, m_lines]


def mutate(rng, data, kind):
    names = []
    for _ in range(rng.choice([1, 1, 1, 2, 3])):
        m = rng.choice(MUTATIONS)
        data = m(rng, data, kind)
        names.append(m.__name__[2:])
    return data, "+".join(names)


# ------------------------------------------------------------------ running
def has_nan(vtu):
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader

    reader = vtkXMLUnstructuredGridReader()
    reader.SetFileName(vtu)
    reader.Update()
    grid = reader.GetOutput()
    data = grid.GetPointData()
    arrays = [vtk_to_numpy(grid.GetPoints().GetData())]
    arrays += [vtk_to_numpy(data.GetArray(i)) for i in range(data.GetNumberOfArrays())]
    return not all(np.all(np.isfinite(a)) for a in arrays)


def run_case(cli, path, out_prefix, timeout):
    args = [cli, "render", "--mesh", path, "--quality", "4", "--max-tet-volume", "1000",
            "--no-shadows", "--uniform-samples", "1", "--output", out_prefix]
    env = dict(os.environ, OMP_NUM_THREADS="1")
    try:
        result = subprocess.run(args, capture_output=True, timeout=timeout, env=env)
    except subprocess.TimeoutExpired:
        return "hang", ""
    stderr = result.stderr.decode("utf-8", "replace")
    if result.returncode < 0:
        return "crash", "signal %d" % -result.returncode
    if result.returncode == 0:
        if not os.path.exists(out_prefix + ".vtu") or has_nan(out_prefix + ".vtu"):
            return "nan", ""
        return "success", ""
    if result.returncode == 1 and "translucency:" in stderr and "Traceback" not in stderr:
        return "error", stderr.strip().splitlines()[-1] if stderr.strip() else ""
    return "unclean", "status %d: %s" % (result.returncode, stderr[-300:])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cli", required=True)
    parser.add_argument("--cases", type=int, default=3000)
    parser.add_argument("--seed", type=int, default=21)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--timeout", type=float, default=30.0)
    parser.add_argument("--keep", default=os.path.join(SOURCE_DIR, "scripts", "mutants-failed"))
    args = parser.parse_args()
    cli = os.path.abspath(args.cli)

    tmp = tempfile.mkdtemp(prefix="mutate_surfaces_")
    bases = make_bases(tmp)
    rng = random.Random(args.seed)
    kinds = sorted(bases)
    cases = []
    for n in range(args.cases):
        kind = kinds[n % len(kinds)]
        data, how = mutate(rng, bases[kind], kind)
        ext = kind[:3]
        path = os.path.join(tmp, "case%05d_%s.%s" % (n, kind, ext))
        with open(path, "wb") as f:
            f.write(data)
        cases.append((n, kind, how, path))

    def work(case):
        n, kind, how, path = case
        prefix = os.path.join(tmp, "out%05d" % n)
        outcome, detail = run_case(cli, path, prefix, args.timeout)
        for ext in (".vtu", ".vtp"):
            if os.path.exists(prefix + ext):
                os.remove(prefix + ext)
        return n, kind, how, path, outcome, detail

    counts = collections.defaultdict(collections.Counter)
    bad = []
    with concurrent.futures.ThreadPoolExecutor(args.jobs) as pool:
        for done, (n, kind, how, path, outcome, detail) in enumerate(pool.map(work, cases), 1):
            counts[kind.split("_")[0]][outcome] += 1
            if outcome in ("crash", "hang", "nan", "unclean"):
                bad.append((n, kind, how, path, outcome, detail))
                os.makedirs(args.keep, exist_ok=True)
                shutil.copy(path, args.keep)
                print("%s: case %d (%s, %s) %s" % (outcome.upper(), n, kind, how, detail),
                      flush=True)
            else:
                os.remove(path)
            if done % 250 == 0:
                print("%d of %d cases" % (done, len(cases)), flush=True)
    shutil.rmtree(tmp, ignore_errors=True)

    outcomes = ["error", "success", "crash", "hang", "nan", "unclean"]
    print("\nseed %d, %d cases" % (args.seed, len(cases)))
    print("%-6s %s %7s" % ("format", " ".join("%8s" % o for o in outcomes), "total"))
    for fmt in sorted(counts):
        c = counts[fmt]
        print("%-6s %s %7d" % (fmt, " ".join("%8d" % c[o] for o in outcomes), sum(c.values())))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
