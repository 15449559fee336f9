/**
 * @file LightSources.h
 * @brief Boundary irradiance q from simple light sources (TransCut, eq. 2:
 * q(x) = integral of L_i (n . w_i) F_t(w_i) dw_i).
 *
 * DirectIrradiance() and HemisphereDirection() give the unoccluded
 * contribution and the direction to test; ComputeBoundaryIrradiance() adds
 * the visibility (self-shadowing) with a ShadowCaster over the whole boundary.
 */
#pragma once

#include <array>
#include <cstddef>
#include <functional>
#include <vector>

namespace translucency
{

class ShadowCaster;
class TetMesh;

/// A white or coloured light. Units per type:
/// - Directional: irradiance E (W/mm^2) on a surface facing the light;
///   Direction is the direction the light travels (need not be unit length).
/// - Point: radiant intensity I (W/sr) at Position (mm).
/// - Uniform: irradiance E (W/mm^2) an unoccluded flat surface receives from
///   uniform incident radiance L = E / pi from every direction.
/// - Spot: a point light at Position whose radiant intensity (W/sr) is
///   Power * cos(alpha)^SpotExponent inside the cone of half-angle SpotCutoff
///   (degrees) around Direction (alpha the angle to the axis) and 0 outside.
struct LightSource
{
  enum class Kind
  {
    Directional,
    Point,
    Uniform,
    Spot
  };
  Kind Type = Kind::Directional;
  std::array<double, 3> Direction{ 0.0, 0.0, -1.0 };
  std::array<double, 3> Position{ 0.0, 0.0, 0.0 };
  std::array<double, 3> Power{ 1.0, 1.0, 1.0 }; ///< E or I per channel (see above)
  double SpotCutoff = 30.0;  ///< Spot only: cone half-angle (degrees, in (0, 180])
  double SpotExponent = 0.0; ///< Spot only: fall-off exponent (>= 0) inside the cone
};

/// A directional light travelling along `direction` with irradiance E per channel.
inline LightSource DirectionalLight(
  const std::array<double, 3>& direction, const std::array<double, 3>& power)
{
  LightSource light;
  light.Type = LightSource::Kind::Directional;
  light.Direction = direction;
  light.Power = power;
  return light;
}

/// A point light at `position` with intensity I (W/sr) per channel.
inline LightSource PointLight(
  const std::array<double, 3>& position, const std::array<double, 3>& power)
{
  LightSource light;
  light.Type = LightSource::Kind::Point;
  light.Position = position;
  light.Power = power;
  return light;
}

/// A spot light at `position` along `axis`, cone half-angle `cutoff`
/// (degrees), fall-off exponent, intensity I (W/sr) per channel on the axis.
inline LightSource SpotLight(const std::array<double, 3>& position,
  const std::array<double, 3>& axis, double cutoff, double exponent,
  const std::array<double, 3>& power)
{
  LightSource light;
  light.Type = LightSource::Kind::Spot;
  light.Position = position;
  light.Direction = axis;
  light.SpotCutoff = cutoff;
  light.SpotExponent = exponent;
  light.Power = power;
  return light;
}


/**
 * Unoccluded irradiance transmitted into the medium at a boundary point
 * (W/mm^2 per channel) for a directional or point light.
 * @param x point (mm), @param n outward unit normal, @param eta refractive index
 * @param toLight unit direction from x towards the light (output)
 * @param distance distance to the light (mm; infinity for directional) (output)
 * @return false (and q = 0) if the light is behind the surface.
 */
bool DirectIrradiance(const LightSource& light, const double x[3], const double n[3], double eta,
  double q[3], double toLight[3], double& distance);

/**
 * Throw translucency::Error, naming the light by `index`, for a light that
 * cannot be evaluated: a uniform light (pass it as uniformIrradiance), a
 * negative or non-finite power, a zero or non-finite direction (directional,
 * spot), a non-finite position (point, spot), a spot cone outside (0, 180]
 * degrees or a negative exponent.
 */
void ValidateLight(const LightSource& light, size_t index);

/**
 * Cosine-weighted direction number k of `count` on the hemisphere around n
 * (stratified over a Fibonacci spiral, rotated by `rotation` in [0, 1) to
 * decorrelate neighbouring points). Returns the cosine to n.
 */
double HemisphereDirection(const double n[3], int k, int count, double rotation, double w[3]);

/**
 * The uniform light's sample rotation, in [0, 1), of the surface point at x
 * (mm): a hash (SplitMix64) of the bits of its three coordinates (-0 taken
 * as +0). It depends on the point alone, not on its index, so the sampled
 * uniform light is the same whatever the point order or the partition of the
 * mesh over MPI ranks (Documentation/Parallel.md, "Partitions and identity").
 */
double UniformSampleRotation(const double x[3]);

/**
 * Irradiance transmitted into the medium at every boundary point (W/mm^2 per
 * channel): the sum of DirectIrradiance() over `lights` plus the uniform
 * light, with self-shadowing by the mesh's own boundary surface when
 * `shadows` is set.
 *
 * Shadow rays start at x + offset (n + w), offset = 1e-5 times the diagonal
 * of the mesh's bounding box (x the point, n its normal, w the unit direction
 * of the ray), and reach min(distance to the light, 2 * diagonal); they are
 * cast with a ShadowCaster (Embree when the build has it, else RayCaster)
 * built over mesh.GetBoundaryTriangles() (only when a ray is needed).
 *
 * The uniform light, of irradiance uniformIrradiance (W/mm^2, >= 0; 0 means
 * none), gives E * Fresnel::UniformTransmittance(eta) without shadows or with
 * uniformSamples == 0, and otherwise the cosine-weighted estimate
 * E / N * sum_k V(w_k) F_t(w_k) over N = uniformSamples HemisphereDirection()
 * rays (rotation UniformSampleRotation(x) for the point at x), V = 1 if the ray
 * escapes.
 *
 * @param mesh the tet mesh (its boundary triangles, boundary points and
 *   point normals are used)
 * @param pointEta refractive index per mesh point (only boundary points are
 *   read; they must be finite and > 0), e.g. from PointRefractiveIndex()
 * @param lights directional and point lights (Kind::Uniform is not accepted
 *   here: pass it as uniformIrradiance)
 * @param uniformSamples rays per point for the shadowed uniform light (>= 0)
 * @param q output, 3 per mesh point (R, G, B), 0 at interior points
 * @param abort optional; called from the calling thread only, once before
 *   the rays are cast and then about every 64 boundary points that thread
 *   handles; returning true stops the computation
 * @return false if aborted (q is then incomplete), true otherwise.
 *
 * OpenMP-parallel over the boundary points (dynamic schedule); every point is
 * computed independently, so q does not depend on the number of threads.
 * Throws translucency::Error on invalid input (before any work).
 */
bool ComputeBoundaryIrradiance(const TetMesh& mesh, const std::vector<double>& pointEta,
  const std::vector<LightSource>& lights, double uniformIrradiance, int uniformSamples,
  bool shadows, std::vector<double>& q, const std::function<bool()>& abort = {});

/**
 * The boundary irradiance integrated per boundary triangle (issue 19;
 * Documentation/DiffuseOptics.md, "Boundary irradiance per triangle"): the
 * value of q at each corner of each boundary triangle, evaluated with the
 * triangle's own outward normal, so that the load of vertex i,
 *   integral of q phi_i dS ~ sum over its triangles f of (S_f / 3) q_f(x_i)
 * (the vertex rule on each triangle, exact for a q constant on the triangle:
 * a directional light on a flat face), injects exactly E cos F_t S on a lit
 * flat face and exactly 0 on a face parallel to the light (whose triangles
 * see the light at grazing incidence), unlike the vertex normals of
 * ComputeBoundaryIrradiance(), which light the edge vertices of such faces.
 *
 * Directional, point and spot lights: q_f(x_i) = DirectIrradiance() at the
 * point x_i with the normal of f and the refractive index of the tet under
 * f, times the visibility of the light from x_i (one shadow ray per point
 * and light, cast as in ComputeBoundaryIrradiance(), only if some triangle
 * around the point faces the light). The uniform light is the same at all
 * corners of a point: ComputeBoundaryIrradiance()'s value there (its q does
 * not depend on the face orientation of a convex object).
 *
 * @param tetEta refractive index per tet (finite and > 0 under the surface)
 * @param cornerQ output: 9 values per boundary triangle (corner k = 0..2 in
 *   mesh.GetBoundaryTriangles() order, then R, G, B), W/mm^2
 * Other parameters, the abort contract and the errors as in
 * ComputeBoundaryIrradiance(); OpenMP-parallel over the boundary points, the
 * result does not depend on the number of threads.
 */
bool ComputeTriangleCornerIrradiance(const TetMesh& mesh, const std::vector<double>& tetEta,
  const std::vector<LightSource>& lights, double uniformIrradiance, int uniformSamples,
  bool shadows, std::vector<double>& cornerQ, const std::function<bool()>& abort = {});

/// Diagonal (mm) of the bounding box of every mesh point: the scale of the
/// shadow rays' offset (1e-5 of it) and reach (twice it).
double BoundingBoxDiagonal(const TetMesh& mesh);

/// Throw translucency::Error unless `tetEta` has one value per tet and the
/// tets under the boundary triangles have a finite index > 0.
void CheckBoundaryTriangleEta(const TetMesh& mesh, const std::vector<double>& tetEta);

/// Unit outward normals of mesh.GetBoundaryTriangles(), 3 per triangle (0
/// for a triangle of zero area).
std::vector<double> BoundaryTriangleNormals(const TetMesh& mesh);

/**
 * One directional, point or spot light's term of
 * ComputeTriangleCornerIrradiance(): adds to `cornerQ` (9 values per
 * boundary triangle) the light's DirectIrradiance() at each corner with the
 * triangle's normal, times the visibility of the light from the corner's
 * point (one shadow ray per point, cast with `caster`, built over
 * mesh.GetBoundaryTriangles(), when `shadows` is set; it may be null
 * otherwise). `triangleNormals` from BoundaryTriangleNormals(), `diagonal`
 * from BoundingBoxDiagonal(); the light and tetEta must be valid
 * (ValidateLight(), CheckBoundaryTriangleEta()). OpenMP-parallel over the
 * boundary points; abort as in ComputeBoundaryIrradiance(). Returns false if
 * aborted (cornerQ is then incomplete). This is the one implementation of
 * a light's term: the full computation and IrradianceCache both call it.
 */
bool AddLightCornerIrradiance(const TetMesh& mesh, const std::vector<double>& tetEta,
  const std::vector<double>& triangleNormals, const LightSource& light, bool shadows,
  const ShadowCaster* caster, double diagonal, std::vector<double>& cornerQ,
  const std::function<bool()>& abort = {});

/**
 * The point irradiance the solvers read, from corner values:
 *   q_i = sum_f S_f q_f(x_i) / sum_f S_f   (sums over the boundary triangles
 * around i), so that S_i q_i / 3 (S_i = sum_f S_f, TetMesh::GetBoundaryAreas)
 * is the triangle-integrated load of vertex i: the discrete divergence's load
 * is exactly it, and every solver's total, the integral of the P1 q, is the
 * sum of the triangle integrals. 3 values per mesh point, 0 inside.
 */
void ProjectCornerIrradiance(
  const TetMesh& mesh, const std::vector<double>& cornerQ, std::vector<double>& pointQ);

/**
 * ComputeTriangleCornerIrradiance() then ProjectCornerIrradiance(): the
 * `Irradiance` point array vtkSurfaceIrradiance writes (3 per mesh point).
 */
bool ComputeProjectedIrradiance(const TetMesh& mesh, const std::vector<double>& tetEta,
  const std::vector<LightSource>& lights, double uniformIrradiance, int uniformSamples,
  bool shadows, std::vector<double>& q, const std::function<bool()>& abort = {});

} // namespace translucency
