/**
 * @file vtkTranslucencyRanges.h
 * @brief The value ranges of a filter's new output arrays, computed once in
 * parallel where the filter hands its output on (vtkTranslucencyDispatch),
 * into VTK's own range cache.
 *
 * Why (issue 31, "where the user meets it"): ParaView gathers the data
 * information of every output that re-executes (vtkPVDataInformation: the
 * range, the finite range and, for vectors, the magnitude range of every
 * array). The GUI always does; pvbatch does too, as soon as a filter
 * downstream has a BoundsDomain (Surface Irradiance's, Paint's and Solve
 * Diffusion's widgets). VTK computes each of those in its own serial pass
 * over the array: 0.8 s of CPU after Assign Scattering Coefficients at 1M
 * tets, ten times the filter itself (perf: vtkSMBoundsDomain::Update ->
 * vtkPVArrayInformation::CopyFromArray -> vtkDataArray::ComputeRange and
 * ComputeFiniteRange). Here the same numbers come from one OpenMP pass per
 * array and are stored under the keys vtkDataArray::GetRange() and
 * GetFiniteRange() read (vtkAbstractArray::PER_COMPONENT() and
 * PER_FINITE_COMPONENT() with vtkDataArray::COMPONENT_RANGE(),
 * vtkDataArray::L2_NORM_RANGE() and L2_NORM_FINITE_RANGE()); VTK keeps
 * them while the array is not modified after (its MTime check).
 *
 * When: only under ParaView's executive (vtkPVCompositeDataPipeline, by
 * class name: the filters do not link ParaView), where every execution is
 * followed by that gather. A plain VTK pipeline (Python VTK, the command
 * line) is left as it was: nothing there asks for every range, and an XML
 * writer stores the cached magnitude ranges in the file (as it does after
 * any GetRange() call).
 *
 * Which arrays: the point and cell arrays of type double of each output data
 * set that have no valid cached component ranges yet (an array passed
 * through keeps the one computed upstream; one modified since its ranges
 * were cached gets new ones), all of whose values are finite (then
 * the range and the finite range are the same numbers; an array with a NaN
 * or an infinity is left to VTK). The values equal VTK's own computation bit
 * for bit (the component minima and maxima; the magnitude as the square root
 * of the extreme sums of squares, summed in component order):
 * TestArrayRanges.
 */
#ifndef vtkTranslucencyRanges_h
#define vtkTranslucencyRanges_h

class vtkDataArray;
class vtkDataObject;
class vtkExecutive;
class vtkInformationVector;

namespace vtkTranslucency
{
/// Caches the ranges of `array` (see the file comment); false if it was not
/// eligible (not double, empty, already cached, or a non-finite value).
bool CacheArrayRanges(vtkDataArray* array);

/// CacheArrayRanges() on the point and cell arrays of `data` (a data set;
/// anything else is left alone). Returns how many arrays it cached.
int CacheDataSetRanges(vtkDataObject* data);

/// CacheDataSetRanges() on every output of a filter.
int CacheOutputRanges(vtkInformationVector* outputVector);

/// Whether `executive` is ParaView's (vtkPVCompositeDataPipeline or a subclass).
bool IsParaViewExecutive(vtkExecutive* executive);
}

#endif
