"""The interactive stopping rule's accuracy where the user meets it, under MPI
(issue 32): the 1M-tet chain of scripts/pvbatch_mpi_chain_timing.py (Assign
marble -> Surface Irradiance -> Paint -> Solve Diffusion (defaults) ->
Outgoing Radiance), cold, relit (the key light turned 15 degrees) and painted
(a stroke on the top), each against Solve Diffusion at RelTol 1e-10 on the
same input: the relative RMS of the Outgoing Radiance difference over the
whole surface (every rank's piece, summed over the ranks), per channel.

    mpiexec --allow-run-as-root -n 2 pvbatch --symmetric scripts/pvbatch_mpi_accuracy.py \\
        PLUGIN bunny1m.vtu

Under N ranks the N-piece bunny1m-N.pvtu next to the .vtu is read (made by
scripts/pvbatch_mpi_chain_timing.py); in one process the .vtu. --symmetric:
every rank runs this script (each reads its own piece's Radiance and the sums
are reduced over the ranks). Prints one line per step on rank 0.
"""

import math
import os
import sys

from paraview.simple import (LoadPlugin, XMLPartitionedUnstructuredGridReader,
                             XMLUnstructuredGridReader)
from paraview import servermanager
from vtkmodules.vtkCommonCore import vtkDoubleArray
from vtkmodules.vtkParallelCore import vtkMultiProcessController


def main():
    plugin, vtu = sys.argv[1:3]
    LoadPlugin(plugin, ns=globals())
    import translucency  # noqa: F401  (Solve Diffusion's getters; the build's package on PYTHONPATH)
    ranks = servermanager.vtkProcessModule.GetProcessModule().GetNumberOfLocalPartitions()
    if ranks > 1:
        reader = XMLPartitionedUnstructuredGridReader(
            FileName=[os.path.splitext(vtu)[0] + "-%d.pvtu" % ranks])
    else:
        reader = XMLUnstructuredGridReader(FileName=[vtu])
    reader.UpdatePipeline()
    b = reader.GetDataInformation().GetBounds()
    centre = [0.5 * (b[2 * k] + b[2 * k + 1]) for k in range(3)]
    diag = math.sqrt(sum((b[2 * k + 1] - b[2 * k]) ** 2 for k in range(3)))

    def key(degrees):
        t = math.radians(degrees)
        return [0.0, -math.cos(t) + math.sin(t), -math.sin(t) - math.cos(t), 1.0]

    assign = AssignScatteringCoefficients(Input=reader, MaterialName="marble")  # noqa: F821
    light = SurfaceIrradiance(Input=assign, DirectionalLights=key(0.0),  # noqa: F821
                              UniformLightIrradiance=0.1)
    paint = PaintScatteringCoefficients(Input=light)  # noqa: F821
    paint.StrokePoints = [b[1] + diag, centre[1], centre[2]]
    paint.Width = 0.01 * diag
    solve = SolveDiffusion(Input=paint)  # noqa: F821
    radiance = OutgoingRadiance(Input=solve)  # noqa: F821
    tight = SolveDiffusion(Input=paint, RelTol=1e-10, MaxIter=100000)  # noqa: F821
    reference = OutgoingRadiance(Input=tight)  # noqa: F821
    controller = vtkMultiProcessController.GetGlobalController()

    def compare(step):
        radiance.UpdatePipeline()
        reference.UpdatePipeline()
        a = radiance.GetClientSideObject().GetOutput().GetPointData().GetArray("Radiance")
        r = reference.GetClientSideObject().GetOutput().GetPointData().GetArray("Radiance")
        local = vtkDoubleArray()
        local.SetNumberOfValues(6)
        for c in range(3):
            dd = rr = 0.0
            for i in range(a.GetNumberOfTuples() if a else 0):
                x, y = a.GetComponent(i, c), r.GetComponent(i, c)
                dd += (x - y) ** 2
                rr += y * y
            local.SetValue(c, dd)
            local.SetValue(3 + c, rr)
        total = vtkDoubleArray()
        total.SetNumberOfValues(6)
        if controller and controller.GetNumberOfProcesses() > 1:
            controller.AllReduce(local, total, 2)  # vtkCommunicator::SUM_OP
        else:
            total.DeepCopy(local)
        core = solve.GetClientSideObject()
        errors = [math.sqrt(total.GetValue(c) / total.GetValue(3 + c)) for c in range(3)]
        if not controller or controller.GetLocalProcessId() == 0:
            print("%d rank%s %-8s iterations %s: Outgoing Radiance RMS error vs RelTol 1e-10 "
                  "R %.3f %%, G %.3f %%, B %.3f %%" % (
                      ranks, "s" if ranks > 1 else "", step,
                      "/".join(str(core.GetNumberOfIterations(c)) for c in range(3)),
                      100 * errors[0], 100 * errors[1], 100 * errors[2]), flush=True)

    compare("cold")
    light.DirectionalLights = key(15.0)
    compare("relight")
    paint.StrokePoints = [centre[0], b[3], centre[2]]
    paint.Width = 0.024 * diag
    compare("paint")


main()
