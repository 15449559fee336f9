#!/usr/bin/env python3
"""Markdown tables from `translucency bench --linear-solvers --json FILE`
(for Documentation/Performance.md).

usage: linear_solvers_table.py BENCH.json
"""
import json
import sys


def tol(v):
    return "direct" if v != v else "%.2g" % v


def its(v):
    return "/".join(str(i) for i in v)


def main(argv):
    if len(argv) != 2:
        sys.stderr.write(__doc__)
        return 2
    sizes = json.load(open(argv[1]))
    for s in sizes:
        print("**%s tets** (%s unknowns, %s nonzeros): topology %.1f ms, 3-channel assembly "
              "%.1f ms, one SpMV %.3f ms vs bandwidth bound %.3f ms (%.0f bytes at %.2f GB/s "
              "STREAM triad), reference residual %.1e.\n"
              % (f"{s['tets']:,}", f"{s['unknowns']:,}", f"{int(s['nonzeros']):,}",
                 s["topology_ms"], s["assembly_3ch_ms"], s["spmv_1ch_ms"],
                 s["spmv_bandwidth_bound_ms"], s["spmv_bytes"], s["stream_triad_gbs"],
                 s["reference_residual"]))
        peers = [r for r in s["solvers"] if r["peer"] and r["cold_reached_1pct"]]
        best_cold = min(peers, key=lambda r: r["setup_ms"] + r["cold_ms"]) if peers else None
        peers_w = [r for r in s["solvers"] if r["peer"] and r["warm_reached_1pct"]]
        best_warm = min(peers_w, key=lambda r: r["warm_ms"]) if peers_w else None
        print("| solver | setup incl. topology (ms) | values-only setup (ms) | cold solve (ms) | "
              "cold tol | cold iters R/G/B | cold SpMV-eq. | cold error | warm solve (ms) | "
              "warm tol | warm iters R/G/B | warm SpMV-eq. | warm error | setup + cold (ms) | "
              "vs best peer | warm vs best peer |")
        print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
        for r in s["solvers"]:
            sc = r["setup_ms"] + r["cold_ms"]
            if max(r["cold_iterations"]) == 0 and max(r["warm_iterations"]) == 0:
                r["cold_tolerance"] = r["warm_tolerance"] = float("nan")  # direct: none
            print("| %s | %.1f | %.1f | %.1f | %s | %s | %.0f | %.2f %% | %.1f | %s | %s | %.0f | "
                  "%.2f %% | %.1f | %s | %s |"
                  % (r["solver"], r["setup_with_topology_ms"], r["values_only_setup_ms"],
                     r["cold_ms"], tol(r["cold_tolerance"]), its(r["cold_iterations"]),
                     r["cold_spmv_equivalents"], 100 * r["cold_error"], r["warm_ms"],
                     tol(r["warm_tolerance"]), its(r["warm_iterations"]), r["warm_spmv_equivalents"],
                     100 * r["warm_error"], sc,
                     "%.2f" % (sc / (best_cold["setup_ms"] + best_cold["cold_ms"]))
                     if best_cold else "-",
                     "%.2f" % (r["warm_ms"] / best_warm["warm_ms"]) if best_warm else "-"))
        if best_cold:
            print("\nBest peer: %s for setup + cold, %s for warm."
                  % (best_cold["solver"], best_warm["solver"] if best_warm else "-"))
        c = s.get("cut")
        if c:
            print("\nCut -> new fluence (%s, tolerance %.2g, warm start from the kept vertices): "
                  "plane cut %.1f + topology %.1f + irradiance %.1f + assembly %.1f + setup %.1f "
                  "+ solve %.1f = %.1f ms (%.1f ms without the irradiance), %s tets kept, "
                  "boundary error %.2f %%.\n"
                  % (c["solver"], c["tolerance"], c["cut_ms"], c["topology_ms"],
                     c["irradiance_ms"], c["assembly_ms"], c["setup_ms"], c["solve_ms"],
                     c["total_ms"], c["total_without_irradiance_ms"], f"{c['tets_kept']:,}",
                     100 * c["error"]))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
