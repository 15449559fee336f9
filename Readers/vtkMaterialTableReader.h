/**
 * @class   vtkMaterialTableReader
 * @brief   Read a material table (JSON) into a vtkTable, one row per material.
 *
 * The file format is documented in Documentation/Materials.md:
 *
 * @code{.json}
 * {"units": "1/mm",
 *  "materials": [
 *    {"name": "marble", "id": 1, "absorption": [0.0021, 0.0041, 0.0071],
 *     "reduced_scattering": [2.19, 2.62, 3.00], "refractive_index": 1.3},
 *    {"id": 2, "preset": "skin1"}]}
 * @endcode
 *
 * Each entry has a `name` and/or a non-negative integer `id`, and either
 * explicit coefficients (`absorption` and `reduced_scattering`, R G B;
 * `refractive_index`, default 1.3) or a `preset` (a measured preset of
 * vtkAssignScatteringCoefficients, case-insensitive). `units` (default
 * "1/mm") is one of "1/mm", "1/cm", "1/m"; the output is always in 1/mm.
 *
 * The output vtkTable has the columns `Id` (vtkIntArray, -1 when the entry
 * has none), `Name` (vtkStringArray, "" when none; a preset entry with
 * neither name nor id is named after its preset), `AbsorptionCoefficient` and
 * `ReducedScatteringCoefficient` (vtkDoubleArray, 3 components, 1/mm) and
 * `RefractiveIndex` (vtkDoubleArray, 1 component).
 *
 * The parser itself has a VTK-free C++ API, ReadMaterialTable(), used by
 * vtkAssignScatteringCoefficients (not wrapped for Python: use the table).
 *
 * @warning A missing file, malformed JSON, an entry with neither
 * coefficients nor preset (or with both), an unknown preset, a negative or
 * non-finite value, a non-integer or negative id, or a duplicate id or name
 * is an error naming the file, the entry index (0-based) and the field.
 *
 * @sa vtkAssignScatteringCoefficients
 */
#ifndef vtkMaterialTableReader_h
#define vtkMaterialTableReader_h

#include "TranslucencyReadersModule.h" // for export macro
#include "vtkTableAlgorithm.h"

#include <string>
#include <vector> // for ReadMaterialTable

class TRANSLUCENCYREADERS_EXPORT vtkMaterialTableReader : public vtkTableAlgorithm
{
public:
  static vtkMaterialTableReader* New();
  vtkTypeMacro(vtkMaterialTableReader, vtkTableAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /// Path of the JSON material table. Default "" (an error when read).
  vtkSetStdStringFromCharMacro(FileName);
  vtkGetCharFromStdStringMacro(FileName);
  ///@}

  /// Non-zero when the file's extension is .json (reader factory hint).
  int CanReadFile(const char* fileName);

#ifndef __VTK_WRAP__
  /// One entry of a material table, coefficients in 1/mm.
  struct Material
  {
    int Id = -1;          ///< >= 0, or -1 when the entry has no id
    std::string Name;     ///< "" when the entry has neither name nor preset
    double Absorption[3]; ///< mu_a (R, G, B), 1/mm
    double ReducedScattering[3]; ///< sigma_s' (R, G, B), 1/mm
    double RefractiveIndex = 1.3; ///< eta
  };

  /**
   * Parse a material table file. Throws std::runtime_error with a message
   * naming the file, the entry index and the bad field / value.
   */
  static std::vector<Material> ReadMaterialTable(const std::string& fileName);
#endif

protected:
  vtkMaterialTableReader();
  ~vtkMaterialTableReader() override = default;

  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  /// Every piece executes (vtkTranslucencyCommunicator::ExecuteEveryPiece).
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  /// RequestData's body: read this rank's piece (1 on success, 0 on failure).
  int ReadPiece(vtkInformationVector* outputVector);

  std::string FileName;

private:
  vtkMaterialTableReader(const vtkMaterialTableReader&) = delete;
  void operator=(const vtkMaterialTableReader&) = delete;
};

#endif
