"""Write the inputs of README.md's examples that are not the bunny, once:

    /usr/bin/python3 Data/make_readme_inputs.py Data

- slab.stl: a 60 x 60 x 20 mm box centred at the origin (12 triangles, ASCII),
  the slab of the TPSF example (a pencil beam on its top face z = 10 mm);
- tissue.json: one material, mu_a 0.01/mm, mu_s' 1/mm, eta 1.4 (a soft-tissue-like
  scatterer; Documentation/DiffuseOptics.md uses the same two files);
- truth.vti: the known volume of the synthetic acquisition, 32 x 32 x 8 cells on
  [0,8] x [0,8] x [0,2] mm with a cylindrical inclusion (the same volume as
  Documentation/examples/acquire_synthetic.py).
"""
import json
import os
import sys

import numpy as np
from vtkmodules.util.numpy_support import numpy_to_vtk
from vtkmodules.vtkCommonDataModel import vtkImageData
from vtkmodules.vtkFiltersCore import vtkTriangleFilter
from vtkmodules.vtkFiltersSources import vtkCubeSource
from vtkmodules.vtkIOGeometry import vtkSTLWriter
from vtkmodules.vtkIOXML import vtkXMLImageDataWriter

target = sys.argv[1] if len(sys.argv) > 1 else "."
os.makedirs(target, exist_ok=True)

cube = vtkCubeSource()
cube.SetBounds(-30.0, 30.0, -30.0, 30.0, -10.0, 10.0)
triangles = vtkTriangleFilter()
triangles.SetInputConnection(cube.GetOutputPort())
stl = vtkSTLWriter()
stl.SetInputConnection(triangles.GetOutputPort())
stl.SetFileTypeToASCII()
stl.SetFileName(os.path.join(target, "slab.stl"))
stl.Write()

with open(os.path.join(target, "tissue.json"), "w") as f:
    json.dump({"absorption": [0.01, 0.01, 0.01], "reduced_scattering": [1, 1, 1],
               "refractive_index": 1.4}, f)
    f.write("\n")

n = (32, 32, 8)
image = vtkImageData()
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
writer = vtkXMLImageDataWriter()
writer.SetFileName(os.path.join(target, "truth.vti"))
writer.SetInputData(image)
writer.Write()
