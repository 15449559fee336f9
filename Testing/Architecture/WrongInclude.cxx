// A Mesh-level library may not see the discretisations: this include must
// fail to compile (Testing/Architecture/CMakeLists.txt expects the error).
#include "DiffusionSolver.h"
#include "TetMesh.h"

int ArchitectureWrongInclude(const translucency::TetMesh& mesh)
{
  return mesh.GetNumberOfTets();
}
