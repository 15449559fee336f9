#!/usr/bin/env python3
"""The test Testing.TierLabels (Testing/TestTiers.cmake):

    /usr/bin/python3 CheckTestTiers.py <ctest> <build tree>

lists the tree's tests as ctest sees them (the discovered GoogleTests
included) and fails naming every test without a tier label, and on a
warning of translucency_gtest_tiers (a SLOW name that is not a test).
Prints the number of tests per tier. (It was a CMake script: CMake's
string(JSON) re-parses the whole listing at every lookup, 8.7 s for ~500
tests; json here reads it once.)
"""

import json
import subprocess
import sys

TIERS = ("unit", "integration", "mpi", "gui", "slow")


def main(ctest, build_dir):
    run = subprocess.run([ctest, "-N", "--show-only=json-v1"], cwd=build_dir,
                         capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit("ctest -N failed (%d):\n%s" % (run.returncode, run.stderr))
    if "translucency_gtest_tiers" in run.stderr:
        sys.exit("a SLOW GoogleTest name is not a test:\n" + run.stderr)
    tests = json.loads(run.stdout).get("tests", [])
    if not tests:
        sys.exit("ctest -N lists no test")
    per_tier = dict.fromkeys(TIERS, 0)
    missing = []
    for test in tests:
        labels = []
        for p in test.get("properties", []):
            if p.get("name") == "LABELS":
                labels += p.get("value", [])
        tiers = [t for t in TIERS if t in labels]
        for t in tiers:
            per_tier[t] += 1
        if not tiers:
            missing.append(test["name"])
    print("-- %d tests: %s" % (len(tests), " ".join("%s %d" % (t, per_tier[t]) for t in TIERS)))
    if missing:
        sys.exit("%d tests have no tier label (%s; Testing/TestTiers.cmake says how to "
                 "choose):\n  %s" % (len(missing), ";".join(TIERS), "\n  ".join(missing)))


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: CheckTestTiers.py <ctest> <build tree>")
    main(sys.argv[1], sys.argv[2])
