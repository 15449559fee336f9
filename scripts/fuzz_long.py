#!/usr/bin/env python3
"""The long fuzzing campaign (`make fuzz-long`, Documentation/Reliability.md).

Runs, in order, with fixed seeds:

1. the libFuzzer targets of build-fuzz (every reader and loader: TetGen,
   material table, material, paint, stroke, scene, mesh I/O of PLY/STL/OBJ/
   VTP/VTU, compare's measured CSV) for --runs inputs each, starting from
   the seeds and regressions (a finding is counted, its artifact kept, and
   the target restarted for the rest of its inputs); outcomes counted by the
   targets' Tally() (FuzzSupport.h; fuzzMeshIO's also per mesh format, shown
   in a second table), hangs and crashes by libFuzzer's artifacts;
2. the command-line mutation loops of scripts/: mutate_xml_inputs.py (VTU,
   VTP, TetGen, material, table, paint, stroke, scene, acquire's
   measurements and truth, compare's measured CSV),
   mutate_surfaces.py (PLY, STL, OBJ) and mutate_options.py (the numeric
   options of every command), each through the built `translucency`.

    nice -n 10 /usr/bin/python3 scripts/fuzz_long.py --cli build/bin/translucency \\
        --fuzz-dir build-fuzz [--runs 2500] [--xml 1500] [--surfaces 600] [--options 900]

Prints one table (cases, clean errors, successes, crashes, hangs, exit 0 with
non-finite output) per campaign and in total, in Markdown, and writes it to
--summary if given. Exits 1 if any crash, hang or non-finite success was found.
"""

import argparse
import collections
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

SOURCE_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TARGETS = ["TetGenReader", "MaterialTableReader", "MaterialFile", "PaintFile", "StrokeFile",
           "SceneFile", "MeshIO", "MeasuredTpsf"]
# Seconds per input where a target needs more than --timeout (as in
# Testing/Fuzz/CMakeLists.txt: a translucent object is tetrahedralised with
# TetGen under ASan).
TIMEOUTS = {"SceneFile": 30}
COLUMNS = ["cases", "clean error", "success", "crash", "hang", "non-finite"]


def run_fuzzer(fuzz_dir, target, runs, work, timeout, seed=20261129):
    """`runs` inputs of fuzz<target>; returns a Counter of COLUMNS (plus
    "skipped": inputs the target does not run) and {group: Counter} for the
    groups the target tallies (fuzzMeshIO: the mesh format)."""
    binary = os.path.join(fuzz_dir, "bin", "fuzz" + target)
    corpus = os.path.join(work, target, "corpus")
    artifacts = os.path.join(work, target, "artifacts") + os.sep
    os.makedirs(corpus, exist_ok=True)
    os.makedirs(artifacts, exist_ok=True)
    tally = os.path.join(work, target, "tally.txt")
    if os.path.exists(tally):
        os.remove(tally)
    args = ["-rss_limit_mb=2048", "-malloc_limit_mb=16384", "-timeout=%d" % timeout,
            "-print_final_stats=1", "-artifact_prefix=" + artifacts, "-seed=%d" % seed]
    dictionary = os.path.join(SOURCE_DIR, "Testing", "Fuzz", "dictionaries", target + ".dict")
    if os.path.exists(dictionary):
        args.append("-dict=" + dictionary)
    dirs = [corpus, os.path.join(SOURCE_DIR, "Testing", "Fuzz", "corpus", target)]
    regressions = os.path.join(SOURCE_DIR, "Testing", "Fuzz", "regressions", target)
    if os.path.isdir(regressions):
        dirs.append(regressions)
    env = dict(os.environ, TRANSLUCENCY_FUZZ_TALLY=tally, OMP_NUM_THREADS="1",
               ASAN_OPTIONS="detect_leaks=1:abort_on_error=0",
               UBSAN_OPTIONS="print_stacktrace=1",
               LSAN_OPTIONS="suppressions=" + os.path.join(SOURCE_DIR, "Testing", "Fuzz",
                                                          "lsan.supp"))
    counts = collections.Counter()
    left, restarts = runs, 0
    while left > 0 and restarts < 50:
        before = set(os.listdir(artifacts))
        log = subprocess.run([binary, "-runs=%d" % left] + args + dirs, env=env,
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                             errors="replace").stderr
        done = re.findall(r"stat::number_of_executed_units:\s*(\d+)", log)
        executed = int(done[-1]) if done else 0
        new = sorted(set(os.listdir(artifacts)) - before)
        for name in new:
            kind = "hang" if name.startswith(("timeout-", "slow-unit-")) else "crash"
            counts[kind] += 1
            print("  %s: %s %s" % (target, kind, os.path.join(artifacts, name)), flush=True)
        if not new and not done:
            # Died without stats or artifact (e.g. killed): a crash of its own.
            counts["crash"] += 1
            print("  %s: ended without statistics:\n%s" % (target, log[-2000:]), flush=True)
            executed = max(executed, 1)
        left -= max(executed, 1)
        if not new:
            break
        restarts += 1
    groups = collections.defaultdict(collections.Counter)
    if os.path.exists(tally):
        with open(tally) as f:
            for line in f:
                key, _, value = line.partition(":")
                key = key.strip()
                for outcome in ("clean error", "success", "skipped"):
                    if key == outcome:
                        counts[outcome] += int(value)
                    elif key.endswith(" " + outcome):
                        groups[key[:-len(outcome) - 1]][outcome] += int(value)
    counts["cases"] = counts["clean error"] + counts["success"] + counts["crash"] + counts["hang"]
    for c in groups.values():
        c["cases"] = c["clean error"] + c["success"]
    return counts, dict(groups)


def run_script(name, args, timeout_s):
    """A mutation script; returns (exit code, its stdout)."""
    command = [sys.executable, os.path.join(SOURCE_DIR, "scripts", name)] + args
    print("$ " + " ".join(command), flush=True)
    result = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            errors="replace", timeout=timeout_s)
    return result.returncode, result.stdout, result.stderr


def parse_xml(stdout):
    """mutate_xml_inputs.py's table: input, clean, success, crash, hang, non-finite, error(no msg)."""
    rows = {}
    for line in stdout.splitlines():
        parts = line.split()
        if len(parts) == 7 and all(p.isdigit() for p in parts[1:]):
            c = collections.Counter(dict(zip(["clean error", "success", "crash", "hang",
                                              "non-finite", "unclean"],
                                             map(int, parts[1:]))))
            c["crash"] += c.pop("unclean", 0)  # an error without a message is not clean
            c["cases"] = sum(c[k] for k in COLUMNS[1:])
            rows["xml: " + parts[0]] = c
    return rows


def parse_surfaces(stdout):
    """mutate_surfaces.py's table: format, error, success, crash, hang, nan, unclean, total."""
    rows = {}
    for line in stdout.splitlines():
        parts = line.split()
        if len(parts) == 8 and all(p.isdigit() for p in parts[1:]):
            e, s, c, h, n, u, total = map(int, parts[1:])
            rows["surface: " + parts[0]] = collections.Counter(
                {"cases": total, "clean error": e, "success": s, "crash": c + u, "hang": h,
                 "non-finite": n})
    return rows


def parse_options(stdout):
    """mutate_options.py's per-command lines: '  render     clean error 12, success 3'."""
    rows = {}
    for line in stdout.splitlines():
        m = re.match(r"^  (render|compare|radiosity|acquire|bench)\s+(.*)$", line)
        if not m:
            continue
        c = collections.Counter()
        for item in m.group(2).split(", "):
            key, _, value = item.rpartition(" ")
            key = "non-finite" if key.startswith("non-finite") else key
            c[key] += int(value)
        c["cases"] = sum(c[k] for k in COLUMNS[1:])
        rows["options: " + m.group(1)] = c
    return rows


def table(rows):
    lines = ["| campaign | " + " | ".join(COLUMNS) + " |",
             "| --- |" + " ---: |" * len(COLUMNS)]
    total = collections.Counter()
    for name, c in rows.items():
        lines.append("| %s | " % name + " | ".join(str(c[k]) for k in COLUMNS) + " |")
        for k in COLUMNS:
            total[k] += c[k]
    lines.append("| **total** | " + " | ".join("**%d**" % total[k] for k in COLUMNS) + " |")
    return "\n".join(lines), total


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cli", default=os.path.join(SOURCE_DIR, "build", "bin", "translucency"))
    parser.add_argument("--fuzz-dir", default=os.path.join(SOURCE_DIR, "build-fuzz"))
    parser.add_argument("--runs", type=int, default=2500, help="inputs per libFuzzer target")
    parser.add_argument("--xml", type=int, default=1500, help="mutate_xml_inputs.py cases")
    parser.add_argument("--surfaces", type=int, default=600, help="mutate_surfaces.py cases")
    parser.add_argument("--options", type=int, default=900, help="mutate_options.py cases")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--timeout", type=int, default=10, help="seconds per libFuzzer input")
    parser.add_argument("--seed", type=int, default=20261129,
                        help="libFuzzer's seed (another seed: other inputs)")
    parser.add_argument("--targets", default=",".join(TARGETS),
                        help="comma-separated libFuzzer targets (default: all)")
    parser.add_argument("--summary", help="write the Markdown table here")
    a = parser.parse_args()

    start = time.monotonic()
    rows = collections.OrderedDict()
    sub = collections.OrderedDict()
    work = tempfile.mkdtemp(prefix="fuzz-long-")
    keep = os.path.join(work, "kept")
    for target in a.targets.split(","):
        if a.runs <= 0:
            break
        t0 = time.monotonic()
        counts, groups = run_fuzzer(a.fuzz_dir, target, a.runs, work,
                                    max(a.timeout, TIMEOUTS.get(target, 0)), a.seed)
        rows["libFuzzer: " + target] = counts
        for group in sorted(groups):  # shown, not added to the total again
            sub["libFuzzer: %s, %s" % (target, group)] = groups[group]
        print("libFuzzer %s: %s (%.0f s)" % (target, dict(counts), time.monotonic() - t0),
              flush=True)
    hours = 6 * 3600
    if a.xml > 0:
        _, out, _ = run_script("mutate_xml_inputs.py", ["--cli", a.cli, "--cases", str(a.xml),
                                                         "--seed", "34", "--jobs", str(a.jobs),
                                                         "--keep", keep], hours)
        rows.update(parse_xml(out))
        print(out, flush=True)
    if a.surfaces > 0:
        _, out, _ = run_script("mutate_surfaces.py", ["--cli", a.cli, "--cases", str(a.surfaces),
                                                       "--seed", "34", "--jobs", str(a.jobs),
                                                       "--keep", keep], hours)
        rows.update(parse_surfaces(out))
        print(out, flush=True)
    if a.options > 0:
        _, out, _ = run_script("mutate_options.py", ["--cli", a.cli, "--cases", str(a.options),
                                                      "--seed", "34", "--jobs", str(a.jobs)],
                               hours)
        rows.update(parse_options(out))
        print(out, flush=True)
    text, total = table(rows)
    if sub:
        sub_text, _ = table(sub)
        text += ("\n\nOf which, by group (fuzzMeshIO: the mesh format; included above):\n\n" +
                 sub_text.rsplit("\n", 1)[0])
    skipped = sum(c["skipped"] for c in rows.values())
    if skipped:
        text += ("\n\n%d libFuzzer inputs were not run by their target (no extension line "
                 "for fuzzMeshIO, empty for fuzzMeasuredTpsf): not counted as cases" % skipped)
    text += "\n\n%d cases in %.0f min (kept inputs: %s)\n" % (
        total["cases"], (time.monotonic() - start) / 60.0, keep)
    print(text)
    if a.summary:
        with open(a.summary, "w") as f:
            f.write(text)
    bad = total["crash"] + total["hang"] + total["non-finite"]
    if not bad:
        shutil.rmtree(work, ignore_errors=True)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
