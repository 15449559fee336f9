"""Acquire a heterogeneous material from synthetic measurements (inverse diffusion).

How to run (after `make build`), from any directory (the CLI is found with
translucency.find_cli(); the output directory is created):

    export PYTHONPATH=/path/to/translucency/build/lib/python3.11/site-packages
    xvfb-run -a /usr/bin/python3 acquire_synthetic.py [OUTPUT_PREFIX]

(xvfb-run only for the objective plot; without an X display the command warns
and writes the other pictures.) TRANSLUCENCY_CLI may name the `translucency`
executable (default: translucency.find_cli()).

1. Write a known volume (the "truth"): a marble-like block, 8 x 8 x 2 mm, with
   an absorbing, less scattering inclusion under the measured face.
2. Run `translucency acquire` in synthetic mode: it lights the 4x4 regions of
   the bottom face one at a time, measures the top face (back-lighting, paper
   Fig. 3a), adds 0.2 % noise and recovers kappa and mu_a per voxel.
3. Read the JSON report: objective per channel, fit quality, correlation of
   the recovered coefficients with the truth by depth, cost per gradient.
4. Run the same fit through the VTK filter (vtkInverseDiffusion) on the
   measurement file the command wrote, and print its iteration history.
"""

import json
import os
import subprocess
import sys

import numpy as np
import vtk
import translucency
from vtkmodules.util.numpy_support import numpy_to_vtk

prefix = sys.argv[1] if len(sys.argv) > 1 else "acquire_synthetic"
if os.path.dirname(prefix):
    os.makedirs(os.path.dirname(prefix), exist_ok=True)
cli = translucency.find_cli()  # $TRANSLUCENCY_CLI, this build's or installation's bin/, PATH

# 1. The truth: cell data on a 32 x 32 x 8 image covering [0,8] x [0,8] x [0,2] mm.
n = (32, 32, 8)
image = vtk.vtkImageData()
image.SetDimensions(n[0] + 1, n[1] + 1, n[2] + 1)
image.SetSpacing(8.0 / n[0], 8.0 / n[1], 2.0 / n[2])
k, j, i = np.meshgrid(np.arange(n[2]), np.arange(n[1]), np.arange(n[0]), indexing="ij")
x, y, z = (i + 0.5) * 8.0 / n[0], (j + 0.5) * 8.0 / n[1], (k + 0.5) * 2.0 / n[2]
inside = ((x - 3.0) ** 2 + (y - 4.5) ** 2 < 1.5 ** 2) & (z > 1.0)
mua = np.where(inside[..., None], [0.06, 0.12, 0.2], [0.02, 0.04, 0.07]).reshape(-1, 3)
sigma = np.where(inside[..., None], [0.8, 1.0, 1.2], [1.6, 1.9, 2.2]).reshape(-1, 3)
for name, values in (("AbsorptionCoefficient", mua), ("ReducedScatteringCoefficient", sigma)):
    array = numpy_to_vtk(np.ascontiguousarray(values), deep=True)
    array.SetName(name)
    image.GetCellData().AddArray(array)
writer = vtk.vtkXMLImageDataWriter()
writer.SetFileName(prefix + "_truth.vti")
writer.SetInputData(image)
writer.Write()

# 2. Synthetic acquisition and inverse diffusion on a 16 x 16 x 4 voxel grid.
command = [cli, "acquire", "--synthetic-truth", prefix + "_truth.vti", "--grid", "16x16x4",
           "--patterns", "4x4", "--setup", "back", "--noise", "0.002",
           "--output", prefix, "--json", prefix + ".json"]
print(" ".join(command))
subprocess.run(command, check=True)

# 3. The report.
with open(prefix + ".json") as f:
    report = json.load(f)
for channel in report["channels"]:
    print("channel %s: objective %.3g (%s)" % (channel["channel"], channel["final_objective"],
          "below 1e-4" if channel["converged"] else "iteration limit"))
print("fitted radiance relative RMS: %.4f" % report["fit_relative_rms"])
for depth in report["truth_correlation_by_depth"]:
    if depth["kappa_correlation_G"] is None:
        print("layer %d: the truth is uniform there (no correlation defined)" % depth["layer"])
    else:
        print("layer %d: correlation with the truth, kappa %.2f, mu_a %.2f"
              % (depth["layer"], depth["kappa_correlation_G"], depth["mua_correlation_G"]))
print("%.3f s per gradient (forward + adjoint pass, %s)"
      % (report["seconds_per_gradient"], report["factorization"]))

# 4. The same through the filter, a few iterations, from the written measurements.
reader = vtk.vtkXMLUnstructuredGridReader()
reader.SetFileName(prefix + "_measurements.vtu")
inverse = translucency.vtkInverseDiffusion()
inverse.SetInputConnection(reader.GetOutputPort())
inverse.SetElementArrayName("VoxelId")
inverse.SetMaxIterations(3)
inverse.Update()
history = inverse.GetOutputDataObject(1)
print("filter history: %d rows; last objective per channel:" % history.GetNumberOfRows())
last = {}
for r in range(history.GetNumberOfRows()):
    last[int(history.GetValueByName(r, "Channel").ToDouble())] = \
        history.GetValueByName(r, "Objective").ToDouble()
print("  " + ", ".join("%s %.3g" % ("RGB"[c], v) for c, v in sorted(last.items())))
print("wrote %s.vtu, %s_radiance.png, %s_slices.png and %s_objective.png"
      % (prefix, prefix, prefix, prefix))
