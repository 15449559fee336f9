#!/usr/bin/env python3
"""Rank the steps of a timed build (scripts/profile_build.sh, Documentation/Building.md).

Usage: build_profile.py BUILD_STEPS_LOG [--total BUILD_TIME] [--top N]

Each log line is "user sys wall kind target output" (scripts/time_build_step.sh).
Prints the CPU (user + sys seconds) by group of steps, then the N most expensive steps.
"""
import argparse
import collections
import os
import re
import sys


def group_of(kind, target, output):
    """A readable group for one step: who produced it and what kind of work it is."""
    name = os.path.basename(output)
    if kind == "link":
        return "link"
    if kind == "custom":
        if "Hierarchy" in name:
            return "VTK wrapping: hierarchy (vtkWrapHierarchy)"
        if "ClientServer" in name or name.endswith("CS.cxx") or "CSInit" in name:
            return "VTK wrapping: client-server sources (vtkWrapClientServer)"
        if name.startswith("moc_") or "mocs" in name or "_autogen" in output:
            return "Qt moc/uic/autogen"
        if "Python" in name or name.endswith("Python.cxx"):
            return "VTK wrapping: Python sources (vtkWrapPython)"
        return "other generators (plugin XML, help, headers)"
    # compile steps
    if "_autogen" in output or name.startswith("moc_") or "mocs_compilation" in name:
        return "compile: Qt moc output"
    if name.endswith("ClientServer.cxx") or "CSInit" in name or name.endswith("CS.cxx"):
        return "compile: client-server wrapping (generated)"
    if "Python" in name and "/Python" not in output:
        return "compile: Python wrapping (generated)"
    if "cmake_pch" in name:
        return "compile: precompiled headers"
    if "unity_" in name:
        return "compile: %s (unity)" % target
    m = re.search(r"/(Solvers|Filters|Readers|Apps|Plugin|Testing)/", output)
    where = m.group(1) if m else "generated"
    if where == "Solvers":
        return "compile: Solvers/ (%s)" % target
    if where == "Filters":
        return "compile: Filters/%s" % ("Parallel" if "/Filters/Parallel/" in output else "")
    return "compile: %s/" % where if where != "generated" else "compile: generated (%s)" % target


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("log")
    parser.add_argument("--total", help="build.time: 'user sys wall' of the whole build")
    parser.add_argument("--top", type=int, default=25)
    args = parser.parse_args()
    steps = []
    for line in open(args.log, encoding="utf-8", errors="replace"):
        parts = line.split(None, 5)
        if len(parts) < 6:
            continue  # GNU time's "Command exited with non-zero status" line
        try:
            user, sys_, wall = float(parts[0]), float(parts[1]), float(parts[2])
        except ValueError:
            continue
        steps.append((user + sys_, wall, parts[3], parts[4], parts[5].strip()))
    if not steps:
        sys.exit("build_profile: no timed steps in %s" % args.log)
    total_cpu = sum(s[0] for s in steps)
    groups = collections.defaultdict(lambda: [0.0, 0])
    for cpu, _, kind, target, output in steps:
        g = groups[group_of(kind, target, output)]
        g[0] += cpu
        g[1] += 1
    print("| group | steps | CPU s | share |")
    print("|---|---:|---:|---:|")
    for name, (cpu, n) in sorted(groups.items(), key=lambda kv: -kv[1][0]):
        print("| %s | %d | %.1f | %.1f %% |" % (name, n, cpu, 100.0 * cpu / total_cpu))
    print("| all timed steps | %d | %.1f | 100 %% |" % (len(steps), total_cpu))
    if args.total:
        user, sys_, wall = (float(x) for x in open(args.total).read().split()[:3])
        print("\nwhole build: %.1f s user + %.1f s sys = %.1f s CPU, %.1f s wall "
              "(untimed make/cmake overhead %.1f s)" % (user, sys_, user + sys_, wall,
                                                       user + sys_ - total_cpu))
    print("\n| CPU s | wall s | step | target | output |")
    print("|---:|---:|---|---|---|")
    for cpu, wall, kind, target, output in sorted(steps, key=lambda s: -s[0])[:args.top]:
        short = re.sub(r"^.*?/(Solvers|Filters|Readers|Apps|Plugin|Testing|CMakeFiles)/", r"\1/", output)
        print("| %.1f | %.1f | %s | %s | %s |" % (cpu, wall, kind, target, short))


if __name__ == "__main__":
    main()
