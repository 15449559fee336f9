"""The small plain-VTK chain many Python tests start from (shared by the
tests of Testing/Python that import `translucency`):

    sphere (vtkSphereSource) -> Tetrahedralize Surface -> Assign Scattering
    Coefficients -> Surface Irradiance (one directional light) -> Solve Diffusion

sphere_chain() builds it unexecuted and returns its filters by name, so a
test changes what it studies (a material, a tolerance) before Update()."""

from types import SimpleNamespace

import translucency
from vtkmodules.vtkFiltersSources import vtkSphereSource


def sphere_chain(radius=4.0, resolution=12, tets=1000, material="marble",
                 light=(0.0, -1.0, -1.0, 1.0)):
    """The chain on a sphere of `radius` mm (`resolution` in theta and phi)
    meshed to about `tets` tets, `material` (None: the filter's default) lit
    by one directional light (dx, dy, dz, E). Returns a namespace with
    sphere, tetra, material, light and solve."""
    sphere = vtkSphereSource()
    sphere.SetRadius(radius)
    sphere.SetThetaResolution(resolution)
    sphere.SetPhiResolution(resolution)
    tetra = translucency.vtkTetrahedralizeSurface()
    tetra.SetInputConnection(sphere.GetOutputPort())
    tetra.SetTargetNumberOfTets(tets)
    assign = translucency.vtkAssignScatteringCoefficients()
    assign.SetInputConnection(tetra.GetOutputPort())
    if material is not None:
        assign.SetMaterialName(material)
    irradiance = translucency.vtkSurfaceIrradiance()
    irradiance.SetInputConnection(assign.GetOutputPort())
    irradiance.AddDirectionalLight(*light)
    solve = translucency.vtkSolveDiffusion()
    solve.SetInputConnection(irradiance.GetOutputPort())
    return SimpleNamespace(sphere=sphere, tetra=tetra, material=assign, light=irradiance,
                           solve=solve)


class Messages:
    """ErrorEvent / WarningEvent observers on algorithms and their executives
    (the messages collected instead of printed).

    executive: what becomes of the executive's "returned failure" error, which
    follows every filter error: "pipeline" keeps it apart in pipeline_errors,
    "errors" adds it to errors, "ignore" swallows it (observed, not kept)."""

    def __init__(self, *algorithms, executive="pipeline"):
        from vtkmodules.util.misc import calldata_type
        from vtkmodules.util.vtkConstants import VTK_STRING
        if executive not in ("pipeline", "errors", "ignore"):
            raise ValueError("executive: 'pipeline', 'errors' or 'ignore', not %r" % executive)
        self.errors = []
        self.warnings = []
        self.pipeline_errors = []

        @calldata_type(VTK_STRING)
        def on_error(caller, event, message):
            self.errors.append(message)

        @calldata_type(VTK_STRING)
        def on_warning(caller, event, message):
            self.warnings.append(message)

        @calldata_type(VTK_STRING)
        def on_pipeline_error(caller, event, message):
            if executive == "pipeline":
                self.pipeline_errors.append(message)
            elif executive == "errors":
                self.errors.append(message)

        # Keep the callbacks alive as long as the observers.
        self._callbacks = (on_error, on_warning, on_pipeline_error)
        self._tags = []
        for algorithm in algorithms:
            self._tags.append((algorithm, algorithm.AddObserver("ErrorEvent", on_error)))
            self._tags.append((algorithm, algorithm.AddObserver("WarningEvent", on_warning)))
            chain_executive = algorithm.GetExecutive()
            self._tags.append((chain_executive,
                               chain_executive.AddObserver("ErrorEvent", on_pipeline_error)))

    def remove(self):
        for obj, tag in self._tags:
            obj.RemoveObserver(tag)
        self._tags = []

    def clear(self):
        self.errors.clear()
        self.warnings.clear()
        self.pipeline_errors.clear()
