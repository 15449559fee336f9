"""Time the relight of the issue-31 chain where a ParaView user meets it (pvbatch).

    OMP_NUM_THREADS=2 pvbatch scripts/pvbatch_relight_timing.py \
        build/lib/paraview-plugins/Translucency/Translucency.so bunny1m.vtu

Meshes Data/bunny.ply to 1M tets into the given .vtu if it does not exist
(never overwrites it), reads it with VTK's XML reader, then Assign (marble) ->
Surface Irradiance (directional (0,-1,-1) + the default uniform light) ->
Solve Diffusion (defaults) -> Outgoing Radiance, each UpdatePipeline timed:
one cold chain, then five relights alternating the key light between
(0,-1,-1) and that direction turned 15 degrees about x. Prints seconds.
"""
import os, sys, time, statistics
from paraview.simple import *
plugin, vtu = sys.argv[1], sys.argv[2]
LoadPlugin(plugin, ns=globals())
if not os.path.exists(vtu):
    s = TranslucencySurfaceReader(FileName=os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'Data', 'bunny.ply'))
    t = TetrahedralizeSurface(Input=s, TargetNumberOfTets=1000000)
    SaveData(vtu, proxy=t)
    Delete(t); Delete(s)
r = XMLUnstructuredGridReader(FileName=[vtu])
r.UpdatePipeline()
print("tets", r.GetDataInformation().GetNumberOfCells())
m = AssignScatteringCoefficients(Input=r, MaterialName='marble')
lit = SurfaceIrradiance(Input=m, DirectionalLights=[0.0, -1.0, -1.0, 1.0])
sol = SolveDiffusion(Input=lit)
rad = OutgoingRadiance(Input=sol)
def step():
    out = []
    for p in (m, lit, sol, rad):
        t0 = time.perf_counter(); p.UpdatePipeline(); out.append(time.perf_counter() - t0)
    return out
cold = step()
print("cold  assign %.3f irr %.3f solve %.3f rad %.3f total %.3f" % (*cold, sum(cold)))
dirs = ([0.0, -1.0, -1.0, 1.0], [0.0, -0.7071, -1.2247, 1.0])  # (0,-1,-1) turned 15 degrees about x
rel = []
for k in range(1, 6):
    lit.DirectionalLights = dirs[k % 2]
    rel.append(step())
    print("relight assign %.3f irr %.3f solve %.3f rad %.3f total %.3f" % (*rel[-1], sum(rel[-1])))
print("relight median total %.3f s" % statistics.median(sum(x) for x in rel))
