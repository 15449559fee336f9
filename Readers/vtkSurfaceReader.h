/**
 * @class   vtkSurfaceReader
 * @brief   read a polygon surface from a PLY, STL or OBJ file, checking every value
 *
 * vtkSurfaceReader reads the simple surface formats with plain C++ (one read
 * of the whole file, std::from_chars), choosing the format by the file name's
 * extension (case-insensitive):
 *
 * - `.ply`: `ascii`, `binary_little_endian` and `binary_big_endian`. The
 *   `vertex` element's `x`, `y`, `z` properties (any numeric type) become the
 *   points; the `face` element's list property `vertex_indices` (or
 *   `vertex_index`; any integer count and index type) the polygons. Other
 *   elements and properties are skipped by their declared sizes.
 * - `.stl`: ASCII (`solid` ... `endsolid`) and binary (80-byte header,
 *   uint32 triangle count, 50 bytes per triangle). Exactly coincident corners
 *   are merged, in the order they first appear (as vtkSTLReader does).
 * - `.obj`: `v x y z [w | r g b]` and `f` lines whose corners are `v`,
 *   `v/vt`, `v/vt/vn` or `v//vn` (1-based; negative indices count back from
 *   the last one defined). Every other line is ignored.
 *
 * The output holds the points (float when every coordinate in the file is
 * stored in at most single precision, as in binary STL, else double) and one
 * polygon per face, in file order, with at least 3 points each. Polygons
 * are not triangulated: the output is the file's content
 * (vtkTetrahedralizeSurface asks for triangles and says so).
 *
 * One class for the three formats rather than one per format: the checks
 * (counts against the file size, finite coordinates, indices in range) and
 * the form of the messages live in one place, the command line and the
 * ParaView plugin register one reader, and a format is a function of a few
 * dozen lines. Set the format explicitly with SetFormat() for a file whose
 * name does not end in the format's extension.
 *
 * Bad input never crashes, hangs or reads silently wrong: every count is
 * compared with the bytes left in the file before anything is allocated (a
 * binary PLY header claiming 9e8 vertices in a 1 KB file is an immediate
 * error), every coordinate must be finite in the precision it is stored in,
 * every index in range, every face must have 3 or more corners, and numbers
 * must fit their declared types. A truncated file, a malformed header or a
 * garbage line is reported with vtkErrorMacro naming the file, the line (or,
 * in binary data, the byte offset) and the problem, and leaves the output
 * empty.
 *
 * @warning
 * Normals, colours and texture coordinates are not read (they are checked
 * only for being numbers, in OBJ for their indices being in range). Only
 * piece 0 is produced.
 *
 * @sa
 * vtkPLYReader vtkSTLReader vtkOBJReader vtkTetrahedralizeSurface
 */
#ifndef vtkSurfaceReader_h
#define vtkSurfaceReader_h

#include "TranslucencyReadersModule.h" // For export macro
#include "vtkPolyDataAlgorithm.h"

#include <string> // For FileName

class TRANSLUCENCYREADERS_EXPORT vtkSurfaceReader : public vtkPolyDataAlgorithm
{
public:
  static vtkSurfaceReader* New();
  vtkTypeMacro(vtkSurfaceReader, vtkPolyDataAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// The formats. FORMAT_FROM_EXTENSION (default) chooses by the file name.
  enum Formats
  {
    FORMAT_FROM_EXTENSION = 0,
    FORMAT_PLY = 1,
    FORMAT_STL = 2,
    FORMAT_OBJ = 3
  };

  ///@{
  /// The file to read. Default: none.
  vtkSetStdStringFromCharMacro(FileName);
  vtkGetCharFromStdStringMacro(FileName);
  ///@}

  ///@{
  /// The format, one of Formats. Default: FORMAT_FROM_EXTENSION.
  vtkSetClampMacro(Format, int, FORMAT_FROM_EXTENSION, FORMAT_OBJ);
  vtkGetMacro(Format, int);
  ///@}

  /// 1 if the name ends in .ply, .stl or .obj (any case) and the file opens.
  static int CanReadFile(const char* fileName);

protected:
  vtkSurfaceReader();
  ~vtkSurfaceReader() override = default;

  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  /// Every piece executes (vtkTranslucencyCommunicator::ExecuteEveryPiece).
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  /// RequestData's body: read this rank's piece (1 on success, 0 on failure).
  int ReadPiece(vtkInformationVector* outputVector);

  std::string FileName;
  int Format = FORMAT_FROM_EXTENSION;

private:
  vtkSurfaceReader(const vtkSurfaceReader&) = delete;
  void operator=(const vtkSurfaceReader&) = delete;
};

#endif
