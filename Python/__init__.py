"""Translucency: heterogeneous translucent volumes by light diffusion on tetrahedral meshes.

Every VTK class of the project is available at top level, for example
``translucency.vtkSolveDiffusion``. Importing this package also imports the VTK
modules the classes depend on.
"""

from .TranslucencyFilters import *  # noqa: F401,F403
from .TranslucencyReaders import *  # noqa: F401,F403

__all__ = [name for name in dir() if name.startswith("vtk")]
