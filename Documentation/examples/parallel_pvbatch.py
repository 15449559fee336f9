"""Render the bunny with ParaView running on several MPI ranks (pvbatch).

How to run, from the repository root after `make build`:

    mpiexec -n 2 pvbatch Documentation/examples/parallel_pvbatch.py \
        build/lib/paraview-plugins/Translucency/Translucency.so bunny_parallel

(as root, add --allow-run-as-root; on a machine with fewer cores than ranks,
--oversubscribe). Writes <prefix>.pvtu (the solved tets, one piece per rank)
and <prefix>_surface.pvtp (the boundary surface with Radiance). A third
argument meshes that surface file instead of the project's bunny; the script
runs from any directory (it finds the bunny through the plugin's build or
installation).

1. The PLY reader reads on rank 0 (the other ranks get empty pieces);
   Tetrahedralize Surface runs TetGen on rank 0.
2. Redistribute DataSet spreads the tets over the ranks; Assign Scattering
   Coefficients, Surface Irradiance and Solve Diffusion keep that partition:
   Assign runs per piece, Surface Irradiance casts its rays against the
   all-gathered boundary surface, and Solve Diffusion solves one distributed
   system (hypre) with each rank's own tets; no rank holds the whole mesh
   (Documentation/Parallel.md, "What runs where").
3. Outgoing Radiance: the surface of physical boundary faces only (no
   partition faces), each rank the faces of its own tets.
4. The counts printed are over all ranks: a point shared by two pieces is
   counted in each.
"""

import os
import sys

from paraview.simple import *  # noqa: F401,F403

plugin, prefix = sys.argv[1], sys.argv[2]
LoadPlugin(plugin, ns=globals())


def find_bunny():
    """The surface to mesh: the third argument if given (any PLY, OBJ or
    STL), else the project's bunny found by the translucency Python package
    beside the plugin (<lib>/python3.*/site-packages of its build or
    installation: $TRANSLUCENCY_DATA_DIR, the source tree, or the installed
    share/translucency/Data), so that this script runs from any directory."""
    if len(sys.argv) > 3:
        return os.path.abspath(sys.argv[3])
    import glob
    lib = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(plugin))))
    sys.path[:0] = sorted(glob.glob(os.path.join(lib, "python3*", "site-packages")))
    import translucency
    return translucency.find_data("bunny.ply")


bunny = find_bunny()

# 1. Read and mesh (rank 0).
surface = TranslucencySurfaceReader(FileName=bunny)
# (the bunny's 3,674 triangles allow no fewer than ~45,000 tets: a smaller
# target would only warn that the mesh is larger)
tets = TetrahedralizeSurface(Input=surface, TargetNumberOfTets=40000)

# 2. Partition, then the per-tet and per-point stages.
pieces = RedistributeDataSet(Input=tets)
marble = AssignScatteringCoefficients(Input=pieces, MaterialName="marble")
lit = SurfaceIrradiance(Input=marble, DirectionalLights=[0.0, -1.0, -1.0, 1.0])
solved = SolveDiffusion(Input=lit)

# 3. The boundary surface with its radiance.
radiance = OutgoingRadiance(Input=solved)

SaveData(prefix + ".pvtu", proxy=solved)
SaveData(prefix + "_surface.pvtp", proxy=radiance)
tets_info = solved.GetDataInformation()
surface_info = radiance.GetDataInformation()
print("%d tets, %d points in all pieces; boundary surface: %d faces; fluence range %s" % (
    tets_info.GetNumberOfCells(), tets_info.GetNumberOfPoints(), surface_info.GetNumberOfCells(),
    solved.PointData["Fluence"].GetRange(-1)))
print("wrote %s.pvtu and %s_surface.pvtp" % (prefix, prefix))
