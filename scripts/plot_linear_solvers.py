#!/usr/bin/env python3
"""Relative L2 error of the boundary fluence vs solve time per linear solver
(TransCut Fig. 7 style; second row: against the work in SpMV-equivalents,
which machine load does not disturb), from the CSV `translucency bench --linear-solvers
--plot FILE.png` writes (columns tets,solver,tolerance,solve_ms,error,
spmv_equivalents; one row per tolerance of the bench's ladder, cold solves
from zero). One panel per mesh size; solvers without multiresolution dashed.

usage: plot_linear_solvers.py DATA.csv OUT.png
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(argv):
    if len(argv) != 3:
        sys.stderr.write(__doc__)
        return 2
    rows = list(csv.DictReader(open(argv[1])))
    if not rows:
        sys.stderr.write("plot_linear_solvers: no data in %s\n" % argv[1])
        return 1
    sizes = sorted({int(r["tets"]) for r in rows})
    floor = 1e-7
    fig, axes = plt.subplots(2, len(sizes), figsize=(5.5 * len(sizes), 9), squeeze=False)
    for col, tets in enumerate(sizes):
        solvers = []
        for r in rows:
            if int(r["tets"]) == tets and r["solver"] not in solvers:
                solvers.append(r["solver"])
        for row, (key, label) in enumerate((("solve_ms", "solve time, 3 channels (ms)"),
                                            ("spmv_equivalents",
                                             "work, 3 channels (SpMV-equivalents)"))):
            ax = axes[row][col]
            for name in solvers:
                # In ladder order (tolerance decreasing): work grows along the line.
                pts = sorted(((float(r["tolerance"]), float(r[key]), float(r["error"]))
                              for r in rows if int(r["tets"]) == tets and r["solver"] == name),
                             reverse=True)
                multires = "multires" in name or "multigrid" in name
                ax.loglog([p[1] for p in pts], [max(p[2], floor) for p in pts],
                          "-o" if multires else "--s", markersize=3, label=name)
            ax.axhline(0.01, color="grey", linewidth=0.8, linestyle=":")
            ax.set_ylim(floor / 2, 1.0)
            ax.set_xlabel(label)
            ax.set_ylabel("relative L2 error of the boundary fluence")
            ax.set_title("bunny, %d tets (errors < %g drawn at %g)" % (tets, floor, floor),
                         fontsize=9)
            ax.grid(True, which="both", linewidth=0.3)
            ax.legend(fontsize=8)
    fig.tight_layout()
    tmp = argv[2] + ".tmp.png"
    fig.savefig(tmp, dpi=110)
    os.replace(tmp, argv[2])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
