#!/usr/bin/env python3
"""The plugin in a parallel pvserver, driven by a pvpython client (Documentation/Parallel.md).

How to run (ctest does this):

    /usr/bin/python3 TestParallelServer.py <Translucency plugin>

1. Writes a closed sphere surface (PLY) and starts
   `mpiexec --allow-run-as-root --oversubscribe -n 2 pvserver --server-port=P`
   on a free port P.
2. `pvpython TestParallelServer.py <plugin> client <port> <surface>` connects,
   loads the plugin on the server and the client, runs PLY reader ->
   Tetrahedralize Surface -> Assign -> Redistribute DataSet -> Surface
   Irradiance -> Solve Diffusion -> Outgoing Radiance on the 2 server ranks and
   fetches the surface; then disconnects and runs the same chain in its own
   (serial) session.
3. The two surfaces have the same faces and the same Radiance at every point
   (relative 1e-6), the server reports 2 ranks, the client ends within its time
   limit, and the server is shut down (its ranks ended) in every case.

Exits non-zero on failure.
"""

import os
import signal
import socket
import subprocess
import sys
import tempfile
import time

TIME_LIMIT = 140  # seconds for the client (a loaded 2-core machine needs ~4x the 25 s)


def chain(ns, surface):
    reader = ns["TranslucencySurfaceReader"](FileName=surface)
    assign = ns["AssignScatteringCoefficients"](
        Input=ns["TetrahedralizeSurface"](Input=reader, TargetNumberOfTets=1000))
    lit = ns["SurfaceIrradiance"](Input=ns["RedistributeDataSet"](Input=assign),
                                  UniformLightSamples=0)
    solved = ns["SolveDiffusion"](Input=lit, RelTol=1e-12, MaxIter=20000)
    radiance = ns["OutgoingRadiance"](Input=solved)
    radiance.UpdatePipeline()
    return ns["servermanager"].Fetch(radiance)


def by_point(surface):
    from vtkmodules.util.numpy_support import vtk_to_numpy
    x = vtk_to_numpy(surface.GetPoints().GetData())
    radiance = vtk_to_numpy(surface.GetPointData().GetArray("Radiance"))
    return {tuple(p): r for p, r in zip(x, radiance)}


def client(plugin, port, surface):
    import numpy as np
    from paraview import simple
    from paraview import servermanager
    ns = dict(vars(simple))
    ns["servermanager"] = servermanager
    simple.Connect("localhost", port)
    ranks = servermanager.ActiveConnection.GetNumberOfDataPartitions()
    simple.LoadPlugin(plugin, remote=True, ns=ns)
    simple.LoadPlugin(plugin, remote=False, ns=ns)
    print("connected to %d ranks" % ranks, flush=True)
    parallel = chain(ns, surface)
    print("parallel chain done", flush=True)
    simple.Disconnect()
    simple.Connect()
    simple.LoadPlugin(plugin, ns=ns)
    serial = chain(ns, surface)
    print("server ranks %d; faces %d (serial %d)" % (
        ranks, parallel.GetNumberOfCells(), serial.GetNumberOfCells()))
    assert ranks == 2, ranks
    assert parallel.GetNumberOfCells() == serial.GetNumberOfCells() > 0
    got, ref = by_point(parallel), by_point(serial)
    assert set(got) == set(ref), "the serial surface points"
    worst = max(np.max(np.abs(got[x] - ref[x]) / np.maximum(np.abs(ref[x]), 1e-300))
                for x in ref)
    print("max relative Radiance difference %.3g" % worst)
    assert worst <= 1e-6, worst
    print("client-server chain equals serial")


def free_port():
    with socket.socket() as s:
        s.bind(("localhost", 0))
        return s.getsockname()[1]


def main(plugin):
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from cli_under_test import write_sphere
    from mpi_harness import MPIEXEC, run
    with tempfile.TemporaryDirectory() as work:
        surface = os.path.join(work, "sphere.ply")
        write_sphere(surface, 4.0, 12)

        port = free_port()
        log = open(os.path.join(work, "server.log"), "w+")
        server = subprocess.Popen(
            MPIEXEC + ["-n", "2", "pvserver", "--server-port=%d" % port,
                       "--force-offscreen-rendering"],
            stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
        try:
            deadline = time.time() + 60
            while "Accepting connection" not in open(log.name).read():
                if server.poll() is not None or time.time() > deadline:
                    sys.exit("pvserver did not start:\n" + open(log.name).read())
                time.sleep(0.5)
            command = ["pvpython", "--force-offscreen-rendering", os.path.abspath(__file__),
                       plugin, "client", str(port), surface]
            result = run(command, work, TIME_LIMIT)
            if result.returncode is None:
                sys.exit("HUNG: the client did not end within %d s; its output:\n%s\n%s" % (
                    TIME_LIMIT, result.stdout, result.stderr))
            print(result.stdout)
            if result.returncode != 0 or "client-server chain equals serial" not in result.stdout:
                sys.exit("client failed:\n" + result.stderr[-4000:])
        finally:
            server.terminate()
            try:
                server.wait(timeout=10)
            except subprocess.TimeoutExpired:
                pass
            try:
                os.killpg(server.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            server.wait()


if __name__ == "__main__":
    if len(sys.argv) > 2 and sys.argv[2] == "client":
        client(sys.argv[1], int(sys.argv[3]), sys.argv[4])
    else:
        main(sys.argv[1])
