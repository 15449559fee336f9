#include "vtkTranslucencyPieceFaces.h"

#ifdef TRANSLUCENCY_HAVE_DISTRIBUTED_SOLVE
#include "Error.h"
#include "TetMesh.h"
#include "vtkTranslucencyMeshConversion.h"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkDataSetAttributes.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkUnstructuredGrid.h>

#include <cstring>
#include <memory>
#include <sstream>
#include <string>

void vtkTranslucency::ExtractPieceFaces(
  vtkUnstructuredGrid* input, PieceFaces& faces, bool readEta)
{
  faces = PieceFaces();
  const vtkIdType numPoints = input ? input->GetNumberOfPoints() : 0;
  const vtkIdType numCells = input ? input->GetNumberOfCells() : 0;
  faces.Used.assign(static_cast<size_t>(numPoints), 0);
  std::string error;
  std::vector<int> cells;
  if (numPoints > 0 && !vtkTranslucency::ToTetArrays(input, faces.Points, cells, error))
  {
    throw translucency::Error(error);
  }
  std::vector<int> tets;
  const std::vector<vtkIdType> kept = vtkTranslucency::OwnedTets(input, cells, tets);
  faces.OwnedTets = static_cast<long long>(kept.size());
  if (kept.empty())
  {
    return;
  }
  std::vector<double> eta;
  if (!readEta)
  {
    eta.assign(static_cast<size_t>(numCells), 1.0);
  }
  else if (!vtkTranslucency::ReadRefractiveIndex(input, eta, error))
  {
    throw translucency::Error(error);
  }
  // The piece's own tets: the cached topology when it has no ghost cells.
  std::shared_ptr<const translucency::TetMesh> mesh;
  if (kept.size() == static_cast<size_t>(numCells))
  {
    mesh = vtkTranslucency::AcquireTetMesh(input, error);
    if (!mesh)
    {
      throw translucency::Error(error);
    }
  }
  else
  {
    auto owned = std::make_shared<translucency::TetMesh>();
    owned->SetGeometry(faces.Points, tets);
    mesh = owned;
  }
  for (int v : mesh->GetTets())
  {
    faces.Used[static_cast<size_t>(v)] = 1;
  }
  faces.Triangles = mesh->GetBoundaryTriangles();
  for (int t : mesh->GetBoundaryTriangleTets())
  {
    const vtkIdType cell = kept[static_cast<size_t>(t)];
    faces.TriangleTets.push_back(static_cast<int>(cell));
    faces.TriangleEta.push_back(eta[static_cast<size_t>(cell)]);
  }
}

bool vtkTranslucency::MakePointKeys(MPI_Comm comm, vtkUnstructuredGrid* input,
  const std::vector<double>& points, bool skip, std::vector<translucency::PointKey>& keys)
{
  const vtkIdType numPoints = input ? input->GetNumberOfPoints() : 0;
  vtkDataArray* globalIds = input ? input->GetPointData()->GetGlobalIds() : nullptr;
  int haveIds = (numPoints == 0 || globalIds) ? 1 : 0, allIds = 0;
  MPI_Allreduce(&haveIds, &allIds, 1, MPI_INT, MPI_MIN, comm);
  keys.assign(skip ? 0 : static_cast<size_t>(numPoints), translucency::PointKey());
  for (vtkIdType i = 0; i < numPoints && !skip; ++i)
  {
    keys[i] = allIds
      ? translucency::PointKeyFromId(static_cast<std::int64_t>(globalIds->GetComponent(i, 0)))
      : translucency::PointKeyFromCoordinates(points.data() + 3 * i);
  }
  return allIds != 0;
}

std::string vtkTranslucency::PieceGeometryKey(vtkUnstructuredGrid* input)
{
  if (!input)
  {
    return "";
  }
  std::ostringstream os;
  auto object = [&os](vtkObject* o) {
    os << static_cast<const void*>(o) << ':' << (o ? o->GetMTime() : 0) << ';';
  };
  vtkPoints* points = input->GetPoints();
  object(points);
  object(points ? points->GetData() : nullptr);
  object(input->GetCells());
  object(input->GetCellTypesArray());
  object(input->GetCellData()->GetArray(vtkDataSetAttributes::GhostArrayName()));
  object(input->GetPointData()->GetGlobalIds());
  os << input->GetNumberOfPoints() << ':' << input->GetNumberOfCells();
  return os.str();
}

vtkTranslucency::PieceIdentity vtkTranslucency::PieceIdentity::Of(vtkUnstructuredGrid* input)
{
  PieceIdentity identity;
  identity.Geometry = PieceGeometryKey(input);
  std::string ignored; // an unreadable index is the caller's error to report
  if (input && input->GetNumberOfCells() > 0)
  {
    identity.HasEta = vtkTranslucency::ReadRefractiveIndex(input, identity.Eta, ignored);
    if (!identity.HasEta)
      identity.Eta.clear();
  }
  return identity;
}

bool vtkTranslucency::PieceIdentity::operator==(const PieceIdentity& other) const
{
  return this->Geometry == other.Geometry && this->HasEta == other.HasEta &&
    this->Eta.size() == other.Eta.size() &&
    (this->Eta.empty() ||
      std::memcmp(this->Eta.data(), other.Eta.data(), this->Eta.size() * sizeof(double)) == 0);
}

bool vtkTranslucency::SameOnEveryRank(MPI_Comm comm, bool same)
{
  int mine = same ? 1 : 0, all = 0;
  MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_MIN, comm);
  return all != 0;
}
#endif
