// The control case: a Mesh-level library using only Common and Mesh builds.
#include "Error.h"
#include "TetMesh.h"

int ArchitectureRightInclude(const translucency::TetMesh& mesh)
{
  if (mesh.GetNumberOfTets() < 0)
  {
    throw translucency::Error("negative tet count");
  }
  return mesh.GetNumberOfTets();
}
