"""Diffuse optics with the Translucency VTK filters: a pencil beam on a slab of
tissue-like material, two fibre detectors, and the same measurement in the
continuous-wave, frequency and time domains (Documentation/DiffuseOptics.md).

How to run (after `make build`), from any directory, no X display needed:

    export PYTHONPATH=/path/to/translucency/build/lib/python3.11/site-packages
    /usr/bin/python3 diffuse_optics.py [OUTPUT.json]

1. A 40 x 40 x 15 mm slab, about 40k tets, mu_a = 0.01 /mm, mu_s' = 1 /mm,
   eta = 1.4 in every channel (Assign Scattering Coefficients, explicit).
2. No boundary light (Surface Irradiance with DefaultLights off): the only
   source is a 1 W pencil beam entering the top face at its centre (Farrell,
   Patterson & Wilson 1992: an isotropic source one transport mean free path
   below the entry point).
3. Two detectors on the top face, 10 and 15 mm from the beam, fibre radius
   1 mm: their fluence and exitance (diffuse reflectance, W/mm^2 per W).
4. The same at 100 MHz (amplitude and phase) and time-resolved (40 gates
   over 0..4 ns: the temporal point-spread functions).
5. The power balance of the continuous-wave solve: absorbed + escaped =
   injected, and the model-range check (none: albedo 0.99).
Writes the readings to OUTPUT.json (default diffuse_optics.json).
"""

import json
import math
import os
import sys

import vtk  # ParaView's VTK 9.2 (python3-paraview)
import translucency

out_json = next((a for a in sys.argv[1:] if not a.startswith("--")), "diffuse_optics.json")

# 1. The slab (mm) and its tets.
box = vtk.vtkTessellatedBoxSource()
box.SetBounds(-20, 20, -20, 20, -15, 0)
box.SetLevel(8)
box.QuadsOff()
tets = translucency.vtkTetrahedralizeSurface()
tets.SetInputConnection(box.GetOutputPort())
tets.SetTargetNumberOfTets(40000)
tissue = translucency.vtkAssignScatteringCoefficients()
tissue.SetInputConnection(tets.GetOutputPort())
tissue.SetAbsorptionCoefficient(0.01, 0.01, 0.01)        # mu_a, 1/mm
tissue.SetReducedScatteringCoefficient(1.0, 1.0, 1.0)    # mu_s', 1/mm
tissue.SetRefractiveIndex(1.4)

# 2. No boundary light: the sources alone.
dark = translucency.vtkSurfaceIrradiance()
dark.SetInputConnection(tissue.GetOutputPort())
dark.SetDefaultLights(False)

solve = translucency.vtkSolveDiffusion()
solve.SetInputConnection(dark.GetOutputPort())
solve.SetSolverByName("fem")
solve.SetRelTol(1e-8)
solve.AddPencilBeam(0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 1.0, 1.0, 1.0)  # entry, direction, W

# 3. Two fibre detectors on the top face.
distances = (10.0, 15.0)
for rho in distances:
    solve.AddDetector(rho, 0.0, 0.0, 1.0)  # x, y, z (mm), fibre radius (mm)

report = {"continuous_wave": [], "frequency_100MHz": [], "time_resolved": {}}
translucency.update(solve)
print("continuous wave (per W of beam):")
for k, rho in enumerate(distances):
    fluence, exitance = solve.GetDetectorFluence(k, 0), solve.GetDetectorExitance(k, 0)
    report["continuous_wave"].append(
        {"rho_mm": rho, "fluence_W_mm2": fluence, "reflectance_W_mm2": exitance})
    print(f"  rho = {rho:4.1f} mm: fluence {fluence:.4e} W/mm^2, "
          f"diffuse reflectance {exitance:.4e} W/mm^2")

# 5. Power balance and the model's range.
injected, absorbed, escaped = [0.0] * 3, [0.0] * 3, [0.0] * 3
solve.ComputePowerBalance(injected, absorbed, escaped)
report["power_W"] = {"injected": injected[0], "absorbed": absorbed[0], "escaped": escaped[0]}
print(f"power: injected {injected[0]:.4f} W = absorbed {absorbed[0]:.4f} W "
      f"+ escaped {escaped[0]:.4f} W (imbalance "
      f"{(absorbed[0] + escaped[0] - injected[0]) / injected[0]:.1e})")
print("model range:", solve.GetModelRangeWarning() or "in range")

# 4a. Frequency domain: amplitude and phase at 100 MHz.
solve.SetModulationFrequency(100e6)
translucency.update(solve)
print("100 MHz:")
for k, rho in enumerate(distances):
    amplitude = solve.GetDetectorFluence(k, 0)
    phase = math.degrees(solve.GetDetectorFluencePhase(k, 0))
    report["frequency_100MHz"].append(
        {"rho_mm": rho, "fluence_amplitude_W_mm2": amplitude, "fluence_phase_deg": phase})
    print(f"  rho = {rho:4.1f} mm: amplitude {amplitude:.4e} W/mm^2, phase {phase:.1f} deg")
solve.SetModulationFrequency(0.0)

# 4b. Time-resolved: 40 gates over 0..4 ns.
solve.SetTimeGates(0.0, 4.0, 40)
translucency.update(solve)
times = [solve.GetTimeGateCentre(g) for g in range(solve.GetNumberOfTimeGates())]
report["time_resolved"]["gate_centres_ns"] = times
print("time-resolved (40 gates, 0..4 ns):")
for k, rho in enumerate(distances):
    tpsf = [solve.GetDetectorFluenceTPSF(k, g, 0) for g in range(len(times))]
    peak = max(range(len(times)), key=lambda g: tpsf[g])
    report["time_resolved"][f"rho_{rho:g}mm_J_mm2_ns"] = tpsf
    print(f"  rho = {rho:4.1f} mm: TPSF peak at {times[peak]:.2f} ns")

if os.path.dirname(out_json):
    os.makedirs(os.path.dirname(out_json), exist_ok=True)
with open(out_json, "w") as f:
    json.dump(report, f, indent=1)
print("wrote", out_json)
