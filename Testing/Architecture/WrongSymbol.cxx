// A Mesh-level library that declares a Physics function by hand (instead of
// including its header, which it cannot see) and calls it: the layer is
// linked with --no-undefined, so the link must fail.
#include "TetMesh.h"

namespace translucency
{
namespace Fresnel
{
double DiffuseReflectance(double eta);
}
}

double ArchitectureWrongSymbol(const translucency::TetMesh& mesh)
{
  return translucency::Fresnel::DiffuseReflectance(1.3) * mesh.GetNumberOfTets();
}
