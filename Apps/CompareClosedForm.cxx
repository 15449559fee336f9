#include "CompareClosedForm.h"

#include "ClosedFormTPSF.h"
#include "Error.h"
#include "Fresnel.h"
#include "InteriorSources.h"
#include "OpticalProperties.h"
#include "TetMesh.h"
#include "TimeResolved.h"

#include "vtkTranslucencyMeshConversion.h"

#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkPointData.h>
#include <vtkUnstructuredGrid.h>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace translucency_app
{
namespace
{

using Vec = std::array<double, 3>;

double Dot(const Vec& a, const Vec& b)
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

Vec Sub(const Vec& a, const Vec& b)
{
  return { a[0] - b[0], a[1] - b[1], a[2] - b[2] };
}

std::string Number(double value)
{
  std::ostringstream text;
  text << value;
  return text.str();
}

/// "" if every tet has the same coefficients (relative 1e-9), else which one differs.
std::string Heterogeneity(const translucency::OpticalProperties& m)
{
  const char* names[3] = { "AbsorptionCoefficient", "ReducedScatteringCoefficient",
    "RefractiveIndex" };
  const std::vector<double>* arrays[3] = { &m.AbsorptionCoefficient,
    &m.ReducedScatteringCoefficient, &m.RefractiveIndex };
  for (int a = 0; a < 3; ++a)
  {
    const std::vector<double>& values = *arrays[a];
    const std::size_t stride = a == 2 ? 1 : 3;
    for (std::size_t c = 0; c < stride; ++c)
    {
      double lo = values[c], hi = values[c];
      for (std::size_t i = c; i < values.size(); i += stride)
      {
        lo = std::min(lo, values[i]);
        hi = std::max(hi, values[i]);
      }
      if (hi - lo > 1e-9 * std::max(std::abs(hi), std::abs(lo)))
      {
        return std::string("the material is heterogeneous (") + names[a] +
          (stride == 3 ? std::string(" ") + "RGB"[c] : std::string()) + " from " + Number(lo) +
          " to " + Number(hi) + ")";
      }
    }
  }
  return "";
}

/// AddClosedForm: per source, the equivalent source's position and the
/// plane the semi-infinite form assumes (pencil beams), or the source
/// (point sources).
struct Placed
{
  Vec Entry{}, Normal{}, Refracted{};
  double Transmitted = 1.0;
  Vec Position{};
  std::array<double, 3> Power{};
};

/// AddClosedForm: the sources placed on the mesh (pencil beams at their
/// entry points); throws translucency::Error naming the source.
std::vector<Placed> PlaceSources(const translucency::TetMesh& mesh,
  const translucency::OpticalProperties& material, const std::vector<SourceSpec>& sources,
  double tolerance)
{
  std::vector<Placed> placed;
  for (std::size_t s = 0; s < sources.size(); ++s)
  {
    Placed p;
    p.Power = sources[s].Power;
    if (sources[s].Pencil)
    {
      translucency::PencilBeam beam;
      beam.Position = sources[s].Position;
      beam.Direction = sources[s].Direction;
      beam.Power = sources[s].Power;
      const translucency::PencilEntry entry = translucency::LocatePencilEntry(
        mesh, material, beam, "pencil beam " + std::to_string(s + 1), tolerance);
      p.Entry = entry.Surface.Position;
      p.Normal = entry.Surface.Normal;
      p.Refracted = entry.Refracted;
      p.Transmitted = entry.Transmitted;
    }
    else
    {
      p.Position = sources[s].Position;
    }
    placed.push_back(p);
  }
  return placed;
}

/// AddClosedForm: the gate averages of the closed form (fluence and
/// exitance at a disc of `radius` around rho, at `depth` from the source),
/// times `power`, added to channel c of every gate.
void AddGateAverages(const translucency::ClosedFormMedium& medium, bool pencils, double depth,
  double zb, double a, double rho, double radius, double power, int c, const TimeGatesSpec& gates,
  std::vector<std::array<double, 3>>& fluence, std::vector<std::array<double, 3>>& exitance)
{
  const double width = (gates.End - gates.Start) / gates.Count;
  for (int g = 0; g < gates.Count; ++g)
  {
    const double t0 = gates.Start + g * width, t1 = gates.Start + (g + 1) * width;
    double phi = 0.0, flux = 0.0;
    if (pencils)
    {
      phi = translucency::DiscAverage(
        [&](double s) {
          return translucency::GateAverage(
            [&](double t) {
              return translucency::SemiInfiniteSurfaceFluenceExtrapolated(
                s, t, medium, depth, zb);
            },
            t0, t1);
        },
        rho, radius);
      flux = translucency::DiscAverage(
        [&](double s) {
          return translucency::GateAverage(
            [&](double t) {
              return translucency::SemiInfiniteReflectanceExtrapolated(
                s, t, medium, depth, zb);
            },
            t0, t1);
        },
        rho, radius);
    }
    else
    {
      phi = translucency::DiscAverage(
        [&](double s) {
          const double distance = std::sqrt(s * s + depth * depth);
          return translucency::GateAverage(
            [&](double t) {
              return translucency::InfiniteMediumFluence(distance, t, medium, 1.0);
            },
            t0, t1);
        },
        rho, radius);
      flux = phi / (2.0 * a);
    }
    fluence[static_cast<std::size_t>(g)][static_cast<std::size_t>(c)] += power * phi;
    exitance[static_cast<std::size_t>(g)][static_cast<std::size_t>(c)] += power * flux;
  }
}

} // namespace

void AddClosedForm(TpsfTable& table, vtkUnstructuredGrid* lit, vtkUnstructuredGrid* solved,
  const std::vector<SourceSpec>& sources, const TimeGatesSpec& gates)
{
  ClosedFormOverlay& overlay = table.ClosedForm;
  overlay = ClosedFormOverlay{};
  const std::size_t detectors = table.DetectorSpecs.size();
  overlay.Fluence.assign(detectors, {});
  overlay.Exitance.assign(detectors, {});
  overlay.DetectorSkipReasons.assign(detectors, "");
  const bool pencils = std::any_of(sources.begin(), sources.end(),
    [](const SourceSpec& s) { return s.Pencil; });
  const bool points = std::any_of(sources.begin(), sources.end(),
    [](const SourceSpec& s) { return !s.Pencil; });
  if (pencils)
  {
    overlay.Name = "Patterson et al. 1989, extrapolated boundary";
    overlay.Assumption = "semi-infinite, homogeneous";
  }
  else
  {
    overlay.Name = "Patterson et al. 1989 eq. 2 as phi/(2A)";
    overlay.Assumption = "infinite, homogeneous, no boundary";
  }
  if (sources.empty())
  {
    overlay.SkipReason = "no --source (the lights alone have no closed form here)";
    return;
  }
  if (pencils && points)
  {
    overlay.SkipReason = "both point sources and pencil beams (one kind at a time)";
    return;
  }
  std::string error;
  const std::shared_ptr<const translucency::TetMesh> mesh =
    vtkTranslucency::AcquireTetMesh(lit, error);
  translucency::OpticalProperties material;
  std::vector<double> irradiance;
  if (!mesh || !vtkTranslucency::ToOpticalProperties(lit, material, error) ||
    !vtkTranslucency::ReadPointArray(lit, vtkTranslucency::IrradianceName, 3, irradiance, error))
  {
    overlay.SkipReason = error;
    return;
  }
  overlay.SkipReason = Heterogeneity(material);
  if (!overlay.SkipReason.empty())
  {
    return;
  }
  if (std::any_of(irradiance.begin(), irradiance.end(), [](double q) { return q != 0.0; }))
  {
    overlay.SkipReason = "lights add boundary irradiance (give --source options only, or "
                         "--light none)";
    return;
  }
  vtkDataArray* positions = solved->GetFieldData()->GetArray("DetectorPosition");
  vtkDataArray* radii = solved->GetFieldData()->GetArray("DetectorRadius");
  if (!positions || !radii || positions->GetNumberOfTuples() != static_cast<vtkIdType>(detectors))
  {
    overlay.SkipReason = "no detector positions in the solver's output";
    return;
  }

  const double eta = material.RefractiveIndex[0];
  const double a = translucency::Fresnel::MismatchA(eta);
  const double cm = translucency::SpeedOfLightMillimetresPerNanosecond / eta;
  const double tolerance = translucency::SurfaceTolerance(*mesh);
  std::vector<Placed> placed;
  try
  {
    placed = PlaceSources(*mesh, material, sources, tolerance);
  }
  catch (const translucency::Error& e)
  {
    overlay.SkipReason = e.what();
    return;
  }

  for (std::size_t d = 0; d < detectors; ++d)
  {
    Vec x{};
    positions->GetTuple(static_cast<vtkIdType>(d), x.data());
    const double radius = radii->GetComponent(static_cast<vtkIdType>(d), 0);
    translucency::SurfacePoint surface;
    try
    {
      surface = translucency::FindSurfacePoint(*mesh, x.data());
    }
    catch (const translucency::Error& e)
    {
      overlay.SkipReason = e.what();
      overlay.Fluence.assign(detectors, {});
      overlay.Exitance.assign(detectors, {});
      return;
    }
    std::vector<std::array<double, 3>> fluence(static_cast<std::size_t>(gates.Count)),
      exitance(static_cast<std::size_t>(gates.Count));
    for (const Placed& p : placed)
    {
      // The axis through the (equivalent) source normal to the plane of the
      // surface, the detector's distance from it (rho) and the source's depth.
      const Vec normal = pencils ? p.Normal : surface.Normal;
      if (pencils)
      {
        const double off = Dot(Sub(x, p.Entry), p.Normal);
        if (std::abs(off) > tolerance)
        {
          overlay.DetectorSkipReasons[d] = "not on the plane of the beam's entry face (" +
            Number(off) + " mm off it): the semi-infinite form does not apply";
          break;
        }
      }
      for (int c = 0; c < 3; ++c)
      {
        const double muA = material.AbsorptionCoefficient[static_cast<std::size_t>(c)];
        const double muT = muA + material.ReducedScatteringCoefficient[static_cast<std::size_t>(c)];
        const translucency::ClosedFormMedium medium{ muA, 1.0 / (3.0 * muT), cm };
        const double zb = 2.0 * a * medium.Kappa;
        Vec source = p.Position;
        if (pencils)
        {
          const double z0 = 1.0 / muT;
          for (int k = 0; k < 3; ++k)
          {
            source[static_cast<std::size_t>(k)] = p.Entry[static_cast<std::size_t>(k)] +
              z0 * p.Refracted[static_cast<std::size_t>(k)];
          }
        }
        const Vec r = Sub(x, source);
        const double depth = std::abs(Dot(r, normal));
        const double rho = std::sqrt(std::max(0.0, Dot(r, r) - depth * depth));
        const double power = p.Power[static_cast<std::size_t>(c)] * p.Transmitted;
        AddGateAverages(
          medium, pencils, depth, zb, a, rho, radius, power, c, gates, fluence, exitance);
      }
    }
    if (overlay.DetectorSkipReasons[d].empty())
    {
      overlay.Fluence[d] = fluence;
      overlay.Exitance[d] = exitance;
    }
  }
}

} // namespace translucency_app
