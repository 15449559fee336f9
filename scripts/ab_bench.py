"""Same-run A/B of two builds: the core bench at 1M tets and a pvbatch chain at 200k.

    /usr/bin/python3 scripts/ab_bench.py OLD_BUILD NEW_BUILD [--tets 1000000]
        [--chain-tets 200000] [--rounds 3] [--work DIR]

Issue 30's "must show": the restructuring changed no speed. Each round runs,
alternating OLD and NEW so that a change of machine load hits both alike:
  1. `translucency bench --tets N --runs 3` (3-channel assembly, one SpMV, the
     default cold solve; medians inside each run);
  2. `translucency bench --linear-solvers multigrid-agg --tets N --runs 3
     --no-cut --hypre-ranks 0` (set-up, cold and warm solve to the bench's 1 %
     criterion);
  3. pvbatch: the issue-31 chain Assign (marble) -> Surface Irradiance
     (directional (0,-1,-1) + uniform) -> Solve Diffusion -> Outgoing Radiance
     on a .vtu of the bunny at --chain-tets, cold chain and 3 relights (15
     degrees), each build's plugin in its own pvbatch process.
Prints each figure's median over the rounds for OLD and NEW and NEW/OLD.
Writes only inside --work (a new temporary directory by default); the chain's
mesh is made there once by NEW's plugin and read by both.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))

CHAIN = r'''
import sys, time, statistics
from paraview.simple import *
LoadPlugin(sys.argv[1], ns=globals())
r = XMLUnstructuredGridReader(FileName=[sys.argv[2]])
r.UpdatePipeline()
m = AssignScatteringCoefficients(Input=r, MaterialName='marble')
lit = SurfaceIrradiance(Input=m, DirectionalLights=[0.0, -1.0, -1.0, 1.0])
sol = SolveDiffusion(Input=lit)
rad = OutgoingRadiance(Input=sol)
def step():
    t0 = time.perf_counter()
    for p in (m, lit, sol, rad):
        p.UpdatePipeline()
    return time.perf_counter() - t0
cold = step()
dirs = ([0.0, -1.0, -1.0, 1.0], [0.0, -0.7071, -1.2247, 1.0])
rel = []
for k in range(1, 4):
    lit.DirectionalLights = dirs[k % 2]
    rel.append(step())
print("AB_CHAIN %.6f %.6f" % (cold, statistics.median(rel)))
'''

MESH = r'''
import sys
from paraview.simple import *
LoadPlugin(sys.argv[1], ns=globals())
s = TranslucencySurfaceReader(FileName=sys.argv[3])
t = TetrahedralizeSurface(Input=s, TargetNumberOfTets=int(sys.argv[4]))
SaveData(sys.argv[2], proxy=t)
'''


def plugin(build):
    path = os.path.join(build, "lib", "paraview-plugins", "Translucency", "Translucency.so")
    if not os.path.exists(path):
        sys.exit("ab_bench: no plugin at %s" % path)
    return path


def run(command, build, env=None):
    # The build's own libraries first (a copied build tree keeps working).
    env = dict(env or os.environ)
    env["LD_LIBRARY_PATH"] = os.path.join(build, "lib") + (
        ":" + env["LD_LIBRARY_PATH"] if env.get("LD_LIBRARY_PATH") else "")
    done = subprocess.run(command, cwd=ROOT, env=env, stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True)
    if done.returncode != 0:
        sys.exit("ab_bench: %s failed (%d):\n%s" % (" ".join(command), done.returncode,
                                                     done.stderr[-2000:]))
    return done.stdout


def core(build, tets, work, tag):
    out = {}
    plain = os.path.join(work, "plain-%s.json" % tag)
    run([os.path.join(build, "bin", "translucency"), "bench", "--tets", str(tets), "--runs", "3",
         "--json", plain, "--quiet"], build)
    row = json.load(open(plain))[0]
    os.remove(plain)
    out["assembly 3ch (ms)"] = row["assembly_3ch_ms_median"]
    out["SpMV 1ch (ms)"] = row["spmv_1ch_ms_median"]
    out["default cold solve 3ch (ms)"] = row["solve_3ch_ms_median"]
    linear = os.path.join(work, "linear-%s.json" % tag)
    run([os.path.join(build, "bin", "translucency"), "bench", "--linear-solvers", "multigrid-agg",
         "--tets", str(tets), "--runs", "3", "--no-cut", "--hypre-ranks", "0", "--json", linear,
         "--quiet"], build)
    row = json.load(open(linear))[0]
    os.remove(linear)
    solver = row["solvers"][0]
    for key in ("setup_ms", "values_only_setup_ms", "cold_ms", "warm_ms"):
        out["multigrid-agg %s" % key] = solver[key]
    for key in ("cold_spmv_equivalents", "warm_spmv_equivalents"):
        out["multigrid-agg %s" % key] = solver[key]
    return out


def chain(build, vtu, work, tag):
    script = os.path.join(work, "chain.py")
    with open(script, "w") as f:
        f.write(CHAIN)
    env = dict(os.environ, OMP_WAIT_POLICY=os.environ.get("OMP_WAIT_POLICY", "passive"))
    text = run(["pvbatch", script, plugin(build), vtu], build, env)
    line = [l for l in text.splitlines() if l.startswith("AB_CHAIN")][-1].split()
    return {"pvbatch cold chain (s)": float(line[1]), "pvbatch relight (s)": float(line[2])}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("old")
    parser.add_argument("new")
    parser.add_argument("--tets", type=int, default=1000000)
    parser.add_argument("--chain-tets", type=int, default=200000)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--work")
    parser.add_argument("--skip-core", action="store_true")
    args = parser.parse_args()
    work = args.work or tempfile.mkdtemp(prefix="ab_bench-")
    os.makedirs(work, exist_ok=True)
    vtu = os.path.join(work, "bunny%d.vtu" % args.chain_tets)
    if not os.path.exists(vtu):
        script = os.path.join(work, "mesh.py")
        with open(script, "w") as f:
            f.write(MESH)
        run(["pvbatch", script, plugin(args.new), vtu, os.path.join(ROOT, "Data", "bunny.ply"),
             str(args.chain_tets)], args.new)
    print("load average at the start: %.2f %.2f %.2f" % os.getloadavg(), flush=True)
    figures = {"old": {}, "new": {}}
    for k in range(args.rounds):
        for tag, build in (("old", args.old), ("new", args.new)):
            got = {} if args.skip_core else core(build, args.tets, work, tag)
            got.update(chain(build, vtu, work, tag))
            for key, value in got.items():
                figures[tag].setdefault(key, []).append(value)
            print("round %d %s: %s" % (k + 1, tag, json.dumps(got)), flush=True)
    print("\n%-44s %12s %12s %8s" % ("figure (median of %d rounds)" % args.rounds, "old", "new",
                                      "new/old"))
    for key in figures["new"]:
        if key not in figures["old"]:
            continue
        old = statistics.median(figures["old"][key])
        new = statistics.median(figures["new"][key])
        print("%-44s %12.3f %12.3f %8.3f" % (key, old, new, new / old if old else float("nan")))
    print("load average at the end: %.2f %.2f %.2f" % os.getloadavg())


if __name__ == "__main__":
    main()
