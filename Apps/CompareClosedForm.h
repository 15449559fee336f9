/**
 * @file CompareClosedForm.h
 * @brief The closed-form TPSF on `compare`'s plot when it applies
 * (Solvers/Physics/ClosedFormTPSF.h; Documentation/DiffuseOptics.md,
 * "Measured curves and the closed form"):
 *
 *  - pencil beams only: Patterson, Chance & Wilson 1989's semi-infinite
 *    reflectance with the extrapolated boundary (z_b = 2 A D, the project's
 *    Robin condition) for the equivalent source of each beam (the same
 *    entry, refracted direction, depth 1 / mu_t' and Fresnel transmittance
 *    as the solvers: LocatePencilEntry), the surface the plane of the entry
 *    triangle; the exitance is the dipole's flux, the fluence its surface
 *    value;
 *  - point sources only: the infinite-medium Green's function (Patterson et
 *    al. 1989 eq. 2) as the fluence, and phi / (2 A) (the project's
 *    exitance read-out with q = 0) as the exitance;
 *
 * each averaged over the gate (Simpson) and over a fibre's disc (in the
 * plane of the detector's surface triangle), summed over the sources.
 * Skipped, with the reason in the overlay, when the material is
 * heterogeneous (any coefficient differs between tets), when lights add
 * boundary irradiance, without sources, with both kinds of source, and per
 * detector when a detector is off the plane of a beam's entry face.
 */
#pragma once

#include "CompareTpsf.h"
#include "DiffuseOpticsOptions.h"

class vtkUnstructuredGrid;

namespace translucency_app
{

/**
 * Fill table.ClosedForm for the sources `sources` on the lit mesh `lit`
 * (its coefficient cell arrays and Irradiance), the detectors as read by
 * the solver output `solved` (field arrays DetectorPosition and
 * DetectorRadius) and the gates `gates`. Never throws for a problem the
 * closed form does not fit: it records the reason (SkipReason,
 * DetectorSkipReasons) instead.
 */
void AddClosedForm(TpsfTable& table, vtkUnstructuredGrid* lit, vtkUnstructuredGrid* solved,
  const std::vector<SourceSpec>& sources, const TimeGatesSpec& gates);

} // namespace translucency_app
