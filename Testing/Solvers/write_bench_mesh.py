#!/usr/bin/env python3
"""Tetrahedralise a surface with the project's TetGen filter and write the
raw mesh file read by BenchSolvers' Linear* benchmarks (TRANSLUCENCY_BENCH_MESH):
int32 #points, int32 #tets, float64 xyz per point, int32 4 ids per tet.

    PYTHONPATH=<build>/lib/python3.11/site-packages /usr/bin/python3 \
        write_bench_mesh.py Data/bunny.ply 1000000 /tmp/bunny1M.bin
"""
import os
import sys

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOPLY import vtkPLYReader

import translucency


def main(surface, tets, output):
    reader = vtkPLYReader()
    reader.SetFileName(surface)
    tetra = translucency.vtkTetrahedralizeSurface()
    tetra.SetInputConnection(reader.GetOutputPort())
    tetra.SetTargetNumberOfTets(int(tets))
    tetra.Update()
    grid = tetra.GetOutput()
    points = vtk_to_numpy(grid.GetPoints().GetData()).astype(np.float64)
    cells = vtk_to_numpy(grid.GetCells().GetConnectivityArray()).astype(np.int32).reshape(-1, 4)
    tmp = output + ".tmp"
    with open(tmp, "wb") as f:
        np.array([len(points), len(cells)], dtype=np.int32).tofile(f)
        points.tofile(f)
        cells.tofile(f)
    os.replace(tmp, output)
    print("%s: %d points, %d tets" % (output, len(points), len(cells)))


if __name__ == "__main__":
    main(*sys.argv[1:4])
