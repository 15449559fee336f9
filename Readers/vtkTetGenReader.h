/**
 * @class   vtkTetGenReader
 * @brief   read a tetrahedral mesh from TetGen's .node/.ele (and optional .face) files
 *
 * vtkTetGenReader is a source that reads the ASCII mesh files written by
 * TetGen (https://wias-berlin.de/software/tetgen/fformats.html) and produces
 * a vtkUnstructuredGrid made only of VTK_TETRA cells.
 *
 * A TetGen mesh is split over several files sharing one base name:
 *
 * - `<base>.node` (required): a header line
 *   `<#points> <dimension (3)> <#attributes> <#boundary markers (0 or 1)>`
 *   followed by one line per point `<id> <x> <y> <z> [attributes] [marker]`.
 * - `<base>.ele` (required): a header line
 *   `<#tetrahedra> <nodes per tetrahedron (4 or 10)> <#region attributes (0 or 1)>`
 *   followed by one line per tetrahedron `<id> <n1> <n2> <n3> <n4> [...] [region]`.
 * - `<base>.face` (optional): a header line `<#faces> <#boundary markers (0 or 1)>`
 *   followed by one line per face `<id> <a> <b> <c> [marker]`.
 *
 * In all files `#` starts a comment that runs to the end of the line, blank
 * lines are skipped, and values are separated by blanks, tabs or commas.
 * Trailing header fields may be omitted, as TetGen allows: the dimension then
 * defaults to 3 and every count of attributes or markers to 0.
 *
 * Point ids are numbered consecutively from 0 or 1; the base is taken from
 * the first point id of the .node file and applies to the point indices in
 * the .ele and .face files, as in TetGen. Output point i is the point with
 * TetGen id (i + base); element and face ids are only used in messages.
 *
 * The output holds:
 * - points in double precision, in the units of the file;
 * - one VTK_TETRA cell per element, with the nodes in file order (TetGen and
 *   VTK share the orientation convention, so TetGen's positively oriented
 *   tetrahedra have a positive VTK volume);
 * - point data `NodeAttribute0`, `NodeAttribute1`, ... (vtkDoubleArray, 1
 *   component) for the point attributes, and `BoundaryMarker` (vtkIntArray)
 *   when the .node file has a marker column;
 * - cell data `RegionAttribute` (vtkDoubleArray, 1 component) when the .ele
 *   file has a region attribute column. Files declaring more than one element
 *   attribute (older TetGen versions and other tools write them) also get
 *   `RegionAttribute1`, `RegionAttribute2`, ... for the extra columns;
 * - when ReadFaces is on and `<base>.face` exists, field data
 *   `TetGenFaces` (vtkIntArray, 3 components, one tuple per face, holding
 *   0-based indices of output points, i.e. already shifted by the base) and,
 *   if the .face file has a marker column, `TetGenFaceMarkers` (vtkIntArray,
 *   1 component, one tuple per face).
 *
 * The faces are kept in field data rather than as triangle cells so that the
 * output stays a pure tetrahedral mesh (filters downstream may assume every
 * cell is a tetrahedron) and the reader keeps a single output port, which is
 * what a ParaView reader proxy expects. Use the arrays, for example, to
 * recover the boundary conditions that TetGen attached to the surface.
 *
 * Bad input never crashes the reader: a missing file, a truncated file, a
 * malformed number, a dimension other than 3, a count that is out of range,
 * non-consecutive point ids or an element or face that refers to a point id
 * that does not exist is reported with vtkErrorMacro, naming the file, the
 * line and the offending value, and leaves the output empty.
 *
 * @warning
 * Quadratic (10-node) tetrahedra are read as linear ones: only the first four
 * (corner) nodes of each element are used and a warning is issued. All ten
 * indices are still checked.
 *
 * @warning
 * Extra values at the end of a .node or .ele line are ignored with a single
 * warning per file; extra values at the end of a .face line (such as the two
 * adjacent tetrahedra written by `tetgen -nn`) are ignored silently.
 *
 * @warning
 * Only ASCII files are read (not TetGen's binary .mesh or .vtk output), and
 * the whole mesh is produced as piece 0; other pieces are empty.
 *
 * @warning
 * The output uses vtkIntArray for `TetGenFaces`, so faces are only read when
 * the mesh has fewer than 2^31 points.
 *
 * @sa
 * vtkUnstructuredGridAlgorithm vtkUnstructuredGridReader vtkTetra
 */

#ifndef vtkTetGenReader_h
#define vtkTetGenReader_h

#include "TranslucencyReadersModule.h" // For export macro
#include "vtkUnstructuredGridAlgorithm.h"

class vtkUnstructuredGrid;

class TRANSLUCENCYREADERS_EXPORT vtkTetGenReader : public vtkUnstructuredGridAlgorithm
{
public:
  ///@{
  /**
   * Standard methods for instantiation, obtaining type information, and
   * printing the state of the object.
   */
  static vtkTetGenReader* New();
  vtkTypeMacro(vtkTetGenReader, vtkUnstructuredGridAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;
  ///@}

  ///@{
  /**
   * Set/Get the file to read. Any of `<base>.node`, `<base>.ele`,
   * `<base>.face` or the base name `<base>` alone is accepted (the extension
   * is matched without regard to case); the names of the other files are
   * derived from it. The default is no file (nullptr), which is an error at
   * update time.
   */
  vtkSetFilePathMacro(FileName);
  vtkGetFilePathMacro(FileName);
  ///@}

  ///@{
  /**
   * Set/Get whether `<base>.face` is read when it exists, producing the
   * field data arrays `TetGenFaces` and `TetGenFaceMarkers` (see the class
   * description). A missing .face file is not an error. The default is true.
   */
  vtkSetMacro(ReadFaces, bool);
  vtkGetMacro(ReadFaces, bool);
  vtkBooleanMacro(ReadFaces, bool);
  ///@}

  /**
   * Return 1 if @a fname names (as for SetFileName) a readable TetGen mesh:
   * both the .node and .ele files exist, are regular files, and their header
   * lines are well formed (dimension 3, 4 or 10 nodes per tetrahedron).
   * Return 0 otherwise. Only the header lines are read and no error is
   * reported; this is meant for ParaView's reader factory.
   */
  virtual int CanReadFile(VTK_FILEPATH const char* fname);

protected:
  vtkTetGenReader();
  ~vtkTetGenReader() override;

  int RequestData(vtkInformation* request, vtkInformationVector** inputVector,
                  vtkInformationVector* outputVector) override;
  /// Every piece executes (vtkTranslucencyCommunicator::ExecuteEveryPiece).
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  /// RequestData's body: read this rank's piece (1 on success, 0 on failure).
  int ReadPiece(vtkInformationVector* outputVector);

  /**
   * Reads the files named by FileName into @a output. Returns 1 on success or
   * after an abort (output left empty), 0 after reporting an error.
   */
  int ReadMesh(vtkUnstructuredGrid* output);

  char* FileName = nullptr;
  bool ReadFaces = true;

private:
  vtkTetGenReader(const vtkTetGenReader&) = delete;
  void operator=(const vtkTetGenReader&) = delete;
};

#endif
