/**
 * @file   vtkTranslucencyGhosts.h
 * @brief  The one ghost-cell test of the filters: a cell flagged vtkGhostType
 *         DUPLICATECELL is a copy of a cell another piece owns. Every path
 *         that reads a piece leaves such cells out and gives them the
 *         owner's values on the way back. Private to the filters.
 */
#ifndef vtkTranslucencyGhosts_h
#define vtkTranslucencyGhosts_h

#include <vtkCellData.h>
#include <vtkDataSet.h>
#include <vtkDataSetAttributes.h>
#include <vtkUnsignedCharArray.h>

namespace vtkTranslucency
{
/// The piece's cell ghost array (null without one, or for a null piece).
inline vtkUnsignedCharArray* GhostCells(vtkDataSet* piece)
{
  return piece ? vtkUnsignedCharArray::SafeDownCast(
                   piece->GetCellData()->GetArray(vtkDataSetAttributes::GhostArrayName()))
               : nullptr;
}

/// True if cell `c` is a ghost (`ghosts` from GhostCells(), may be null).
inline bool IsGhostCell(vtkUnsignedCharArray* ghosts, vtkIdType c)
{
  return ghosts && (ghosts->GetValue(c) & vtkDataSetAttributes::DUPLICATECELL);
}

/// The number of cells of `piece` that are not ghosts (0 for null).
inline long long OwnedCellCount(vtkDataSet* piece)
{
  const vtkIdType n = piece ? piece->GetNumberOfCells() : 0;
  vtkUnsignedCharArray* ghosts = GhostCells(piece);
  long long owned = 0;
  for (vtkIdType c = 0; c < n; ++c)
  {
    owned += IsGhostCell(ghosts, c) ? 0 : 1;
  }
  return owned;
}

/// True if `piece` has a ghost cell.
inline bool HasGhostCells(vtkDataSet* piece)
{
  const vtkIdType n = piece ? piece->GetNumberOfCells() : 0;
  return OwnedCellCount(piece) != static_cast<long long>(n);
}
}

#endif
