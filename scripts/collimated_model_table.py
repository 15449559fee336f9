#!/usr/bin/env python3
"""The collimated-source models against Monte Carlo, per light kind (issue 33).

How to run (from a configured and built tree; about 10 min of CPU at the
default photon count on one core, less on more):

    PYTHONPATH=build/lib/python3.11/site-packages OMP_NUM_THREADS=2 \\
        /usr/bin/python3 scripts/collimated_model_table.py [--photons N] \\
        [--runs R] [--solver divergence] [--json table.json] [--quick]

It prints the Markdown tables of Documentation/DiffuseOptics.md, "Which
collimated model by default", and writes every number to --json.

1. Two objects, both 10 mm thick, mu_a 0.01 /mm, mu_s' 1 /mm, eta 1.3 (grey:
   the three channels are the same material): the box 20 x 20 x 10 mm (1 mm
   cells) and a slab 60 x 60 x 10 mm (2 mm cells across, 1 mm in depth),
   both the Kuhn split of a regular grid (6 tets per cell); light on the top
   face (z = 10), centred.
2. The light kinds the product has: `directional` (face-on, 1 W/mm^2
   white), `coloured` (the same with R, G, B = 1, 0.6, 0.3), `spot` (20 mm
   above the face, axis straight down, 15 degree cone, 400 W/sr: 1 W/mm^2
   on the axis), `point` (the same without the cone), `pencil` (a pencil
   beam of 1 W entering at the centre of the top face) and `uniform` (the
   environment light of the default lighting, 1 W/mm^2). The extended models
   change the spot, point and uniform lights and the pencil beam only
   through the Robin rule (extended-moments).
3. Per kind, Monte Carlo (`montecarlo`, the project's transport solver,
   g = 0, the same tets) in R runs of N/R photons per channel with different
   seeds, and the diffusion solver (--solver, default divergence, rel-tol
   1e-10) under each collimated model (surface, extended, extended-moments;
   the extended models change the directional lights only, and
   extended-moments the Robin rule of the whole solve).
4. Read-outs, absolute (the same lights for both; the coloured light's
   divided by its colour, so that the channels are replicas):
   - fluence by depth: mean `Fluence` of the vertices within 4 mm of the
     axis (2 mm for the pencil beam) at each depth 1..9 mm; "deep" is the
     mean over 2-7 mm;
   - transmittance: exitance integrated over the bottom face, and
     reflectance: over the top face (detectors of radius 0 at every vertex
     of the face, weighted by a third of the face's triangle area around
     the vertex: the escaped power through the face up to the rim, where a
     vertex also shares the side faces); for the pencil beam also the top
     face's mean exitance 4-8 mm from the entry point (the far field);
   - the radiance read-out along the normal (vtkOutgoingRadiance, the
     default energy-conserving read-out) against Monte Carlo's
     `MonteCarloRadiance`, area-weighted means over the top and the bottom
     face.
5. Errors are diffusion / Monte Carlo - 1 in %; Monte Carlo's standard error
   of each read-out is the spread of the R runs x 3 channels (independent
   random streams per channel and seed) / sqrt(3 R), also in %.
"""

import argparse
import json
import math
import sys
import time

import numpy as np
import translucency
from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray, vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkPoints
from vtkmodules.vtkCommonDataModel import VTK_TETRA, vtkCellArray, vtkUnstructuredGrid

MU_A, MU_S, ETA = 0.01, 1.0, 1.3
THICKNESS = 10.0
MODELS = ["surface", "extended", "extended-moments"]
MODEL_VALUE = {"surface": 0, "extended": 1, "extended-moments": 2}
KINDS = ["directional", "coloured", "spot", "point", "pencil", "uniform"]
COLOUR = (1.0, 0.6, 0.3)


def box_mesh(nx, ny, nz, lx, ly, lz):
    """A regular grid split into 6 tets per cell (Kuhn), with the material."""
    xs, ys, zs = (np.linspace(0.0, l, n + 1) for l, n in ((lx, nx), (ly, ny), (lz, nz)))
    z, y, x = np.meshgrid(zs, ys, xs, indexing="ij")
    points = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    px, py = nx + 1, ny + 1

    def pid(i, j, k):
        return i + px * (j + py * k)

    i, j, k = np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij")
    i, j, k = i.ravel(), j.ravel(), k.ravel()
    tets = []
    for perm in ((0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)):
        corner = [np.zeros_like(i), np.zeros_like(i), np.zeros_like(i)]
        tet = [pid(i, j, k)]
        for axis in perm:
            corner[axis] = corner[axis] + 1
            tet.append(pid(i + corner[0], j + corner[1], k + corner[2]))
        tets.append(np.column_stack(tet))
    tets = np.vstack(tets)
    grid = vtkUnstructuredGrid()
    vpoints = vtkPoints()
    vpoints.SetData(numpy_to_vtk(points, deep=True))
    grid.SetPoints(vpoints)
    cells = vtkCellArray()
    connectivity = np.column_stack([np.full(len(tets), 4), tets]).ravel()
    cells.SetCells(len(tets), numpy_to_vtkIdTypeArray(connectivity.astype(np.int64), deep=True))
    grid.SetCells(VTK_TETRA, cells)
    for name, value, components in (("AbsorptionCoefficient", MU_A, 3),
                                    ("ReducedScatteringCoefficient", MU_S, 3),
                                    ("RefractiveIndex", ETA, 1)):
        array = numpy_to_vtk(np.full((len(tets), components), value), deep=True)
        array.SetName(name)
        grid.GetCellData().AddArray(array)
    return grid, points


def face_weights(points, z, nx, ny):
    """Per vertex of the face z = const: a third of the triangle area around it
    (every face cell is split into 2 triangles of equal area)."""
    on_face = np.abs(points[:, 2] - z) < 1e-9
    ids = np.nonzero(on_face)[0]
    x, y = points[ids, 0], points[ids, 1]
    hx = (x.max() - x.min()) / nx
    hy = (y.max() - y.min()) / ny
    # Interior vertices touch 6 triangles of the Kuhn split, corners 1 or 2,
    # edge vertices 3: count them from the cells instead of guessing.
    weights = np.zeros(len(ids))
    index = {int(v): n for n, v in enumerate(ids)}
    px = nx + 1
    base = ids.min()
    for cj in range(ny):
        for ci in range(nx):
            a = base + ci + px * cj
            b, c, d = a + 1, a + px, a + px + 1
            for tri in ((a, b, d), (a, d, c)):
                for v in tri:
                    weights[index[v]] += hx * hy / 2.0 / 3.0
    return ids, weights


class Scene:
    def __init__(self, name, nx, ny, nz, lx, ly):
        self.name = name
        self.mesh, self.points = box_mesh(nx, ny, nz, lx, ly, THICKNESS)
        self.centre = (lx / 2.0, ly / 2.0)
        self.top_ids, self.top_w = face_weights(self.points, THICKNESS, nx, ny)
        self.bottom_ids, self.bottom_w = face_weights(self.points, 0.0, nx, ny)
        self.depths = np.round(THICKNESS - self.points[:, 2], 9)
        self.rho = np.hypot(self.points[:, 0] - self.centre[0], self.points[:, 1] - self.centre[1])
        self.half = np.maximum(np.abs(self.points[:, 0] - self.centre[0]),
                               np.abs(self.points[:, 1] - self.centre[1]))


def irradiance_filter(scene, kind, model):
    light = translucency.vtkSurfaceIrradiance()
    light.SetInputData(scene.mesh)
    light.SetShadows(False)
    cx, cy = scene.centre
    if kind == "directional":
        light.AddDirectionalLight(0.0, 0.0, -1.0, 1.0)
    elif kind == "coloured":
        light.AddColouredDirectionalLight(0.0, 0.0, -1.0, *COLOUR)
    elif kind == "spot":
        light.AddSpotLight(cx, cy, THICKNESS + 20.0, 0.0, 0.0, -1.0, 15.0, 0.0, 400.0, 400.0, 400.0)
    elif kind == "point":
        light.AddPointLight(cx, cy, THICKNESS + 20.0, 400.0)
    elif kind == "uniform":
        light.SetUniformLightIrradiance(1.0)
    else:
        light.SetDefaultLights(False)
    light.SetCollimatedModel(MODEL_VALUE[model])
    return light


def solve_filter(scene, kind, light, solver, photons=0, seed=1):
    solve = translucency.vtkSolveDiffusion()
    solve.SetInputConnection(light.GetOutputPort())
    solve.SetSolverByName(solver)
    if solver == "montecarlo":
        solve.SetNumberOfPhotons(photons)
        solve.SetSeed(seed)
    else:
        solve.SetRelTol(1e-10)
        solve.SetMaxIter(100000)
    if kind == "pencil":
        cx, cy = scene.centre
        solve.AddPencilBeam(cx, cy, THICKNESS, 0.0, 0.0, -1.0, 1.0, 1.0, 1.0)
    for ids in (scene.top_ids, scene.bottom_ids):
        for v in ids:
            x = scene.points[v]
            solve.AddDetector(x[0], x[1], x[2], 0.0)
    return solve


def readouts(scene, kind, solve, radiance, power):
    """Every read-out, per channel (an array of 3), per W entering."""
    out = solve.GetOutput()
    fluence = vtk_to_numpy(out.GetPointData().GetArray("Fluence"))
    radius = 2.0 if kind == "pencil" else 4.0
    column = scene.half <= radius + 1e-9
    result = {}
    for depth in range(1, 10):
        sel = column & (np.abs(scene.depths - depth) < 1e-9)
        result["fluence_%d" % depth] = fluence[sel].mean(axis=0) / power
    deep = column & (scene.depths >= 2.0 - 1e-9) & (scene.depths <= 7.0 + 1e-9)
    result["deep"] = fluence[deep].mean(axis=0) / power
    n_top = len(scene.top_ids)
    exitance = np.array([[solve.GetDetectorExitance(k, c) for c in range(3)]
                         for k in range(n_top + len(scene.bottom_ids))])
    result["reflectance"] = (scene.top_w[:, None] * exitance[:n_top]).sum(axis=0) / power
    result["transmittance"] = (scene.bottom_w[:, None] * exitance[n_top:]).sum(axis=0) / power
    ring = (scene.rho[scene.top_ids] >= 4.0 - 1e-9) & (scene.rho[scene.top_ids] <= 8.0 + 1e-9)
    result["far_exitance"] = exitance[:n_top][ring].mean(axis=0) / power
    for face, ids, weights in (("top", scene.top_ids, scene.top_w),
                               ("bottom", scene.bottom_ids, scene.bottom_w)):
        if radiance is None:  # Monte Carlo's own radiance
            values = vtk_to_numpy(out.GetPointData().GetArray("MonteCarloRadiance"))[ids]
        else:
            surface = radiance.GetOutput()
            original = vtk_to_numpy(surface.GetPointData().GetArray("vtkOriginalPointIds"))
            lookup = {int(v): n for n, v in enumerate(original)}
            rad = vtk_to_numpy(surface.GetPointData().GetArray("Radiance"))
            values = rad[[lookup[int(v)] for v in ids]]
        result["radiance_" + face] = (weights[:, None] * values).sum(axis=0) / weights.sum() / power
    return result


def channel_scale(kind):
    """The light's power per channel relative to white (the read-outs are
    divided by it, so that the three channels are replicas)."""
    return np.array(COLOUR) if kind == "coloured" else np.ones(3)


def run_kind(scene, kind, args):
    record = {"monte_carlo": {}, "models": {}}
    replicas = []
    start = time.time()
    for run in range(args.runs):
        light = irradiance_filter(scene, kind, "surface")
        solve = solve_filter(scene, kind, light, "montecarlo", args.photons // args.runs, 11 + run)
        translucency.update(solve)
        power = channel_scale(kind)
        values = readouts(scene, kind, solve, None, power)
        for c in range(3):
            replicas.append({key: float(v[c]) for key, v in values.items()})
    record["monte_carlo_seconds"] = time.time() - start
    keys = list(replicas[0])
    for key in keys:
        samples = np.array([r[key] for r in replicas])
        mean = samples.mean()
        se = samples.std(ddof=1) / math.sqrt(len(samples))
        record["monte_carlo"][key] = {"mean": mean, "se_percent": 100.0 * se / abs(mean)}
    for model in MODELS:
        light = irradiance_filter(scene, kind, model)
        solve = solve_filter(scene, kind, light, args.solver)
        radiance = translucency.vtkOutgoingRadiance()
        radiance.SetInputConnection(solve.GetOutputPort())
        translucency.update(radiance)
        power = channel_scale(kind)
        values = readouts(scene, kind, solve, radiance, power)
        record["models"][model] = {
            key: [100.0 * (v[c] / record["monte_carlo"][key]["mean"] - 1.0) for c in range(3)]
            for key, v in values.items()}
    return record


ROWS = [("deep", "deep fluence (2-7 mm)"), ("transmittance", "transmittance"),
        ("reflectance", "reflectance (top-face exitance)"),
        ("far_exitance", "top-face exitance 4-8 mm from the axis"),
        ("radiance_top", "radiance, top face"), ("radiance_bottom", "radiance, bottom face")]


def print_tables(table):
    for scene, kinds in table["scenes"].items():
        print("\n### %s\n" % scene)
        print("| light | read-out | MC SE | " + " | ".join(MODELS) + " |")
        print("|---|---|---|" + "---|" * len(MODELS))
        for kind, record in kinds.items():
            for key, label in ROWS:
                mc = record["monte_carlo"][key]
                cells = ["%+.1f %%" % np.mean(record["models"][m][key]) for m in MODELS]
                print("| %s | %s | %.2f %% | %s |" % (kind, label, mc["se_percent"], " | ".join(cells)))
        print("\nFluence by depth (error in %%, %s):\n" % table["solver"])
        print("| light | model | " + " | ".join("%d mm" % d for d in range(1, 10)) + " |")
        print("|---|---|" + "---|" * 9)
        for kind, record in kinds.items():
            for m in MODELS:
                cells = ["%+.1f" % np.mean(record["models"][m]["fluence_%d" % d]) for d in range(1, 10)]
                print("| %s | %s | %s |" % (kind, m, " | ".join(cells)))
            se = ["%.2f" % record["monte_carlo"]["fluence_%d" % d]["se_percent"] for d in range(1, 10)]
            print("| %s | MC SE | %s |" % (kind, " | ".join(se)))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--photons", type=int, default=1200000,
                        help="Monte Carlo photons per channel, over all runs (1.2e6)")
    parser.add_argument("--runs", type=int, default=4, help="independent Monte Carlo runs (4)")
    parser.add_argument("--solver", default="divergence", help="diffusion solver (divergence)")
    parser.add_argument("--scenes", default="box,slab", help="box,slab")
    parser.add_argument("--kinds", default=",".join(KINDS), help=",".join(KINDS))
    parser.add_argument("--json", help="write every number here")
    args = parser.parse_args()
    scenes = {"box": lambda: Scene("box 20 x 20 x 10 mm", 20, 20, 10, 20.0, 20.0),
              "slab": lambda: Scene("slab 60 x 60 x 10 mm", 30, 30, 10, 60.0, 60.0)}
    table = {"solver": args.solver, "photons_per_channel": args.photons, "runs": args.runs,
             "scenes": {}}
    for name in args.scenes.split(","):
        scene = scenes[name]()
        table["scenes"][scene.name] = {}
        for kind in args.kinds.split(","):
            record = run_kind(scene, kind, args)
            table["scenes"][scene.name][kind] = record
            print("%s, %s: Monte Carlo %.0f s" % (scene.name, kind, record["monte_carlo_seconds"]),
                  file=sys.stderr, flush=True)
            if args.json:
                with open(args.json, "w") as handle:
                    json.dump(table, handle, indent=1)
    print_tables(table)


if __name__ == "__main__":
    main()
