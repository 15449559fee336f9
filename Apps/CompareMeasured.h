/**
 * @file CompareMeasured.h
 * @brief `compare --measured FILE`: a user's measured TPSF, one column per
 * detector, on the TPSF plot (Documentation/DiffuseOptics.md, "Measured
 * curves and the closed form").
 *
 * The file (CSV): a header row, then one row per time sample. Cells are
 * separated by commas; spaces around a cell are ignored; empty lines and
 * lines starting with '#' are skipped. The first column is the time, its
 * header names the unit: `t_ns`, `time_ns`, `t (ns)` or `time (ns)`
 * (nanoseconds) or the same with `ps` (picoseconds; converted to ns). Then
 * one column per `--detector`, in the order they are given (any header: it
 * is the curve's name). Times must increase from row to row; every cell is
 * a finite number (counts in arbitrary units: a negative value, e.g. after
 * background subtraction, is kept but not drawn on the log axis).
 */
#pragma once

#include "CompareTpsf.h"

#include <string>

namespace translucency_app
{

/// The file as read: times in ns, one column per detector.
struct MeasuredFile
{
  std::string Path;
  std::string TimeUnit; ///< "ns" or "ps"
  std::vector<std::string> Columns;        ///< the detector columns' headers
  std::vector<double> Times;               ///< ns
  std::vector<std::vector<double>> Values; ///< [column][row]
};

/**
 * Read `path` as described above. translucency::Error naming the file (and
 * the line, column and cell where it applies) when it cannot be opened, has
 * no header with a time unit, a row with a different number of cells, a
 * cell that is not a finite number, fewer than two rows, times that do not
 * increase, or a number of detector columns other than `detectors`.
 */
MeasuredFile ReadMeasuredTpsf(const std::string& path, std::size_t detectors);

/**
 * Put `file` on `table` (its Measured member): per detector, the values
 * interpolated linearly to the gate centres inside the measured times and
 * scaled by `normalise`:
 *  - "area" (default): the sum over those gates equals that of the
 *    reference solver's exitance (channel `channel`) at the same gates,
 *    i.e. the same area over the overlap (measured counts are in arbitrary
 *    units);
 *  - "peak": the largest of those values equals the reference's largest
 *    there;
 *  - "none": as in the file.
 * `reference` is the solver's name in table.Series. translucency::Error
 * when no gate centre lies within the measured times, or (area, peak) the
 * measured sum or peak over them is not positive.
 */
void AddMeasured(TpsfTable& table, const MeasuredFile& file, const std::string& normalise,
  const std::string& reference, int channel);

} // namespace translucency_app
