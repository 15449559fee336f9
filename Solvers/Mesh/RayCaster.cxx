#include "RayCaster.h"

#include "Error.h"

#include <omp.h>

#include <algorithm>
#include <exception>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>

namespace translucency
{

namespace
{

constexpr int MaxLeafSize = 4;
constexpr int NumberOfBins = 16;
/// Below this depth splits follow the surface area heuristic; deeper, the
/// median split bounds the remaining depth by log2 of the triangle count.
constexpr int SahDepthLimit = 64;
/// Ranges of at least this many triangles build their halves as OpenMP tasks.
constexpr int ParallelGrain = 8192;

/**
 * Moller-Trumbore with the edges e1 = b - a, e2 = c - a already formed.
 * Inclusive barycentric bounds; the comparisons are written so that NaN
 * (from a degenerate triangle) rejects. Both the tree and the public
 * IntersectTriangle() go through this one function so that they agree to the
 * last bit.
 */
inline bool IntersectEdges(const double o[3], const double d[3], const double a[3],
  const double e1[3], const double e2[3], double tMin, double tMax, double& t)
{
  const double p[3] = { d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2],
    d[0] * e2[1] - d[1] * e2[0] };
  const double det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
  if (det == 0.0)
  {
    return false; // ray parallel to the plane, or degenerate triangle
  }
  const double invDet = 1.0 / det;
  const double s[3] = { o[0] - a[0], o[1] - a[1], o[2] - a[2] };
  const double u = (s[0] * p[0] + s[1] * p[1] + s[2] * p[2]) * invDet;
  if (!(u >= 0.0 && u <= 1.0))
  {
    return false;
  }
  const double q[3] = { s[1] * e1[2] - s[2] * e1[1], s[2] * e1[0] - s[0] * e1[2],
    s[0] * e1[1] - s[1] * e1[0] };
  const double v = (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]) * invDet;
  if (!(v >= 0.0 && u + v <= 1.0))
  {
    return false;
  }
  const double tt = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) * invDet;
  if (!(tt > tMin && tt < tMax))
  {
    return false;
  }
  t = tt;
  return true;
}

/// Half the surface area of a box {min x, y, z, max x, y, z}.
inline double HalfArea(const double b[6])
{
  const double dx = b[3] - b[0], dy = b[4] - b[1], dz = b[5] - b[2];
  return dx * dy + dy * dz + dz * dx;
}

/// Largest float <= x (lower box bounds) and smallest float >= x (upper).
inline float FloatDown(double x)
{
  float f = static_cast<float>(x);
  return static_cast<double>(f) > x ? std::nextafter(f, -std::numeric_limits<float>::infinity())
                                    : f;
}
inline float FloatUp(double x)
{
  float f = static_cast<float>(x);
  return static_cast<double>(f) < x ? std::nextafter(f, std::numeric_limits<float>::infinity())
                                    : f;
}

inline void EmptyBox(double b[6])
{
  const double inf = std::numeric_limits<double>::infinity();
  b[0] = b[1] = b[2] = inf;
  b[3] = b[4] = b[5] = -inf;
}

inline void GrowBox(double b[6], const double other[6])
{
  for (int k = 0; k < 3; ++k)
  {
    b[k] = std::min(b[k], other[k]);
    b[k + 3] = std::max(b[k + 3], other[k + 3]);
  }
}

/// Build: the box and centroid of every triangle (in parallel; the first
/// bad triangle in input order, a point id out of range or a non-finite
/// coordinate, is then named by a serial check of it), the scene box
/// (lo, hi) and the largest coordinate magnitude.
void TriangleBoxes(const std::vector<double>& points, const std::vector<int>& triangles,
  std::vector<double>& boxes, std::vector<double>& centroids, double sceneBox[6], double& maxAbsOut)
{
  const long long numPoints = static_cast<long long>(points.size() / 3);
  const int numTriangles = static_cast<int>(triangles.size() / 3);
  boxes.resize(6 * static_cast<size_t>(numTriangles));
  centroids.resize(3 * static_cast<size_t>(numTriangles));
  // Boxes and centroids in parallel; the first bad triangle (in input
  // order) is then named by a serial check of it.
  double lo[3] = { std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
    std::numeric_limits<double>::infinity() };
  double hi[3] = { -lo[0], -lo[1], -lo[2] };
  double maxAbs = 0.0;
  int firstBad = numTriangles;
#pragma omp parallel for schedule(static) reduction(min : lo[:3], firstBad) \
  reduction(max : hi[:3], maxAbs)
  for (int f = 0; f < numTriangles; ++f)
  {
    double* box = &boxes[6 * static_cast<size_t>(f)];
    EmptyBox(box);
    bool bad = false;
    for (int v = 0; v < 3 && !bad; ++v)
    {
      const int id = triangles[3 * static_cast<size_t>(f) + v];
      if (id < 0 || id >= numPoints)
      {
        bad = true;
        break;
      }
      const double* x = &points[3 * static_cast<size_t>(id)];
      for (int k = 0; k < 3; ++k)
      {
        bad = bad || !std::isfinite(x[k]);
        box[k] = std::min(box[k], x[k]);
        box[k + 3] = std::max(box[k + 3], x[k]);
        maxAbs = std::max(maxAbs, std::abs(x[k]));
      }
    }
    if (bad)
    {
      firstBad = std::min(firstBad, f);
      continue;
    }
    for (int k = 0; k < 3; ++k)
    {
      centroids[3 * static_cast<size_t>(f) + k] = 0.5 * (box[k] + box[k + 3]);
      lo[k] = std::min(lo[k], box[k]);
      hi[k] = std::max(hi[k], box[k + 3]);
    }
  }
  if (firstBad < numTriangles)
  {
    const int f = firstBad;
    for (int v = 0; v < 3; ++v)
    {
      const int id = triangles[3 * static_cast<size_t>(f) + v];
      if (id < 0 || id >= numPoints)
      {
        std::ostringstream msg;
        msg << "RayCaster: triangle " << f << " has point id " << id << ", out of range [0, "
            << numPoints << ")";
        throw Error(msg.str());
      }
      const double* x = &points[3 * static_cast<size_t>(id)];
      if (!(std::isfinite(x[0]) && std::isfinite(x[1]) && std::isfinite(x[2])))
      {
        std::ostringstream msg;
        msg << "RayCaster: triangle " << f << " uses point " << id
            << " whose coordinates are not finite";
        throw Error(msg.str());
      }
    }
  }
  for (int k = 0; k < 3; ++k)
  {
    sceneBox[k] = lo[k];
    sceneBox[k + 3] = hi[k];
  }
  maxAbsOut = maxAbs;
}

/**
 * BuildSubtree's split plane by binned SAH (Wald 2007): bins along each
 * axis, cost of each of the NumberOfBins - 1 planes = N_left A_left +
 * N_right A_right. Partitions order[begin, end) at the best plane and
 * returns the split index, or -1 if no plane splits the centroids.
 */
int PartitionBySah(std::vector<int>& order, const std::vector<double>& centroids,
  const std::vector<double>& boxes, int begin, int end, const double centroidBox[6])
{
  double bestCost = std::numeric_limits<double>::infinity();
  int bestAxis = -1, bestPlane = -1;
  double bestScale = 0.0;
  for (int axis = 0; axis < 3; ++axis)
  {
    const double extent = centroidBox[axis + 3] - centroidBox[axis];
    if (!(extent > 0.0))
    {
      continue;
    }
    const double lo = centroidBox[axis];
    const double scale = NumberOfBins / extent;
    int binCount[NumberOfBins] = {};
    double binBox[NumberOfBins][6];
    for (auto& b : binBox)
    {
      EmptyBox(b);
    }
    for (int k = begin; k < end; ++k)
    {
      const size_t f = static_cast<size_t>(order[k]);
      const int bin = std::min(NumberOfBins - 1,
        static_cast<int>((centroids[3 * f + axis] - lo) * scale));
      ++binCount[bin];
      GrowBox(binBox[bin], &boxes[6 * f]);
    }
    // Sweep from the right for the right-hand costs, then from the left.
    double rightArea[NumberOfBins];
    int rightCount[NumberOfBins];
    double acc[6];
    EmptyBox(acc);
    int n = 0;
    for (int b = NumberOfBins - 1; b > 0; --b)
    {
      GrowBox(acc, binBox[b]);
      n += binCount[b];
      rightCount[b] = n;
      rightArea[b] = n > 0 ? HalfArea(acc) : 0.0;
    }
    EmptyBox(acc);
    n = 0;
    for (int plane = 1; plane < NumberOfBins; ++plane)
    {
      GrowBox(acc, binBox[plane - 1]);
      n += binCount[plane - 1];
      if (n == 0 || rightCount[plane] == 0)
      {
        continue;
      }
      const double cost = n * HalfArea(acc) + rightCount[plane] * rightArea[plane];
      if (cost < bestCost)
      {
        bestCost = cost;
        bestAxis = axis;
        bestPlane = plane;
        bestScale = scale;
      }
    }
  }
  if (bestAxis >= 0)
  {
    const double lo = centroidBox[bestAxis];
    const int* splitPoint = std::partition(
      order.data() + begin, order.data() + end, [&](int f) {
        const int bin = std::min(NumberOfBins - 1,
          static_cast<int>((centroids[3 * static_cast<size_t>(f) + bestAxis] - lo) *
            bestScale));
        return bin < bestPlane;
      });
    return static_cast<int>(splitPoint - order.data());
  }
  return -1;
}

} // namespace

/// Scratch data of Build(): per triangle box and centroid, and the order.
struct RayCaster::BuildState
{
  std::vector<double> Boxes;     ///< 6 per input triangle
  std::vector<double> Centroids; ///< 3 per input triangle
  std::vector<int> Order;        ///< input triangle ids, permuted into leaf order
  double Pad = 0.0;              ///< node box padding (mm)
};

//------------------------------------------------------------------------------
void RayCaster::Build(const std::vector<double>& points, const std::vector<int>& triangles)
{
  Nodes_.clear();
  Triangles_.clear();
  TriangleIds_.clear();
  Root_ = Child();
  Depth_ = 0;
  if (points.size() % 3 != 0)
  {
    std::ostringstream msg;
    msg << "RayCaster: the point array has " << points.size()
        << " values, not a multiple of 3 (x, y, z per point)";
    throw Error(msg.str());
  }
  if (triangles.size() % 3 != 0)
  {
    std::ostringstream msg;
    msg << "RayCaster: the triangle array has " << triangles.size()
        << " ids, not a multiple of 3 (3 point ids per triangle)";
    throw Error(msg.str());
  }
  const long long numPoints = static_cast<long long>(points.size() / 3);
  if (triangles.size() / 3 > static_cast<size_t>(std::numeric_limits<int>::max()))
  {
    throw Error("RayCaster: too many triangles (more than 2^31 - 1)");
  }
  const int numTriangles = static_cast<int>(triangles.size() / 3);

  BuildState state;
  double scene[6];
  double maxAbs = 0.0;
  TriangleBoxes(points, triangles, state.Boxes, state.Centroids, scene, maxAbs);
  if (numTriangles == 0)
  {
    return;
  }
  const double diag = std::sqrt((scene[3] - scene[0]) * (scene[3] - scene[0]) +
    (scene[4] - scene[1]) * (scene[4] - scene[1]) + (scene[5] - scene[2]) * (scene[5] - scene[2]));
  // Padding covers the rounding of the intersection t against the box
  // planes (both are ~1e-16 relative to the coordinates).
  state.Pad = 1e-9 * (diag + maxAbs) + std::numeric_limits<double>::min();

  state.Order.resize(numTriangles);
  for (int f = 0; f < numTriangles; ++f)
  {
    state.Order[f] = f;
  }
  Nodes_.reserve(static_cast<size_t>(numTriangles / 2 + 1));
  try
  {
    double box[6];
    std::exception_ptr error;
#pragma omp parallel if (numTriangles >= ParallelGrain)
#pragma omp single
    {
      try
      {
        Root_ = BuildSubtree(state, Nodes_, Depth_, 0, numTriangles, 1, box);
      }
      catch (...)
      {
        error = std::current_exception();
      }
    }
    if (error)
    {
      std::rethrow_exception(error);
    }
    for (int k = 0; k < 3; ++k)
    {
      RootBounds_[k] = box[k] - state.Pad;
      RootBounds_[k + 3] = box[k + 3] + state.Pad;
    }
  }
  catch (...)
  {
    Nodes_.clear();
    Root_ = Child();
    Depth_ = 0;
    throw;
  }

  // Triangles in leaf order, as vertex a and the edges b - a, c - a.
  Triangles_.resize(9 * static_cast<size_t>(numTriangles));
  TriangleIds_ = state.Order;
  for (int k = 0; k < numTriangles; ++k)
  {
    const int f = state.Order[k];
    const double* a = &points[3 * static_cast<size_t>(triangles[3 * static_cast<size_t>(f)])];
    const double* b = &points[3 * static_cast<size_t>(triangles[3 * static_cast<size_t>(f) + 1])];
    const double* c = &points[3 * static_cast<size_t>(triangles[3 * static_cast<size_t>(f) + 2])];
    double* out = &Triangles_[9 * static_cast<size_t>(k)];
    for (int d = 0; d < 3; ++d)
    {
      out[d] = a[d];
      out[3 + d] = b[d] - a[d];
      out[6 + d] = c[d] - a[d];
    }
  }
}

//------------------------------------------------------------------------------
RayCaster::Child RayCaster::BuildSubtree(BuildState& state, std::vector<Node>& nodes,
  int& maxDepth, int begin, int end, int depth, double box[6])
{
  maxDepth = std::max(maxDepth, depth);
  if (depth > MaxDepth)
  {
    throw Error("RayCaster: internal error: tree deeper than the traversal stack");
  }
  double centroidBox[6];
  EmptyBox(box);
  EmptyBox(centroidBox);
  for (int k = begin; k < end; ++k)
  {
    const size_t f = static_cast<size_t>(state.Order[k]);
    GrowBox(box, &state.Boxes[6 * f]);
    const double* c = &state.Centroids[3 * f];
    const double cc[6] = { c[0], c[1], c[2], c[0], c[1], c[2] };
    GrowBox(centroidBox, cc);
  }
  const int count = end - begin;
  if (count <= MaxLeafSize)
  {
    Child leaf;
    leaf.Ref = begin;
    leaf.Count = count;
    return leaf;
  }

  int longest = 0;
  for (int k = 1; k < 3; ++k)
  {
    if (centroidBox[k + 3] - centroidBox[k] > centroidBox[longest + 3] - centroidBox[longest])
    {
      longest = k;
    }
  }
  const double longestExtent = centroidBox[longest + 3] - centroidBox[longest];

  int mid = begin;
  if (!(longestExtent > 0.0))
  {
    // All centroids coincide: any split is as good; halve the range.
    mid = begin + count / 2;
  }
  else
  {
    bool split = false;
    if (depth < SahDepthLimit)
    {
      mid = PartitionBySah(state.Order, state.Centroids, state.Boxes, begin, end, centroidBox);
      split = mid > begin && mid < end;
    }
    if (!split)
    {
      // Median of the centroids along the longest axis.
      mid = begin + count / 2;
      std::nth_element(state.Order.begin() + begin, state.Order.begin() + mid,
        state.Order.begin() + end, [&](int a, int b) {
          return state.Centroids[3 * static_cast<size_t>(a) + longest] <
            state.Centroids[3 * static_cast<size_t>(b) + longest];
        });
    }
  }

  // The node before its subtrees (depth-first order): the left child's node,
  // if any, is the next one.
  const int index = static_cast<int>(nodes.size());
  nodes.emplace_back();
  double childBox[2][6];
  Child left, right;
  if (count >= ParallelGrain && omp_in_parallel())
  {
    // The halves are disjoint ranges of state.Order: build them as tasks
    // into their own vectors, then splice them after this node (left, then
    // right: the serial depth-first order), shifting their interior refs.
    std::vector<Node> sub[2];
    int subDepth[2] = { depth, depth };
    std::exception_ptr error[2];
    Child* out[2] = { &left, &right };
    const int from[2] = { begin, mid }, to[2] = { mid, end };
    for (int h = 0; h < 2; ++h)
    {
#pragma omp task default(none) firstprivate(h, depth) shared(state, sub, subDepth, error, out, from, to, childBox)
      {
        try
        {
          *out[h] = BuildSubtree(state, sub[h], subDepth[h], from[h], to[h], depth + 1, childBox[h]);
        }
        catch (...)
        {
          error[h] = std::current_exception();
        }
      }
    }
#pragma omp taskwait
    for (int h = 0; h < 2; ++h)
    {
      if (error[h])
      {
        std::rethrow_exception(error[h]);
      }
    }
    for (int h = 0; h < 2; ++h)
    {
      const int offset = static_cast<int>(nodes.size());
      for (Node& n : sub[h])
      {
        for (Child& c : n.Children)
        {
          c.Ref += c.Count == 0 ? offset : 0;
        }
      }
      out[h]->Ref += out[h]->Count == 0 ? offset : 0;
      nodes.insert(nodes.end(), sub[h].begin(), sub[h].end());
      maxDepth = std::max(maxDepth, subDepth[h]);
    }
  }
  else
  {
    left = BuildSubtree(state, nodes, maxDepth, begin, mid, depth + 1, childBox[0]);
    right = BuildSubtree(state, nodes, maxDepth, mid, end, depth + 1, childBox[1]);
  }
  Node& node = nodes[index];
  node.Children[0] = left;
  node.Children[1] = right;
  for (int c = 0; c < 2; ++c)
  {
    for (int k = 0; k < 3; ++k)
    {
      node.Bounds[c][k] = FloatDown(childBox[c][k] - state.Pad);
      node.Bounds[c][k + 3] = FloatUp(childBox[c][k + 3] + state.Pad);
    }
  }
  Child interior;
  interior.Ref = index;
  interior.Count = 0;
  return interior;
}

//------------------------------------------------------------------------------
void RayCaster::SetEpsilon(double epsilon)
{
  if (!(epsilon >= 0.0) || !std::isfinite(epsilon))
  {
    std::ostringstream msg;
    msg << "RayCaster: epsilon is " << epsilon << ": must be finite and >= 0 (mm)";
    throw Error(msg.str());
  }
  Epsilon_ = epsilon;
}

//------------------------------------------------------------------------------
bool RayCaster::IntersectTriangle(const double origin[3], const double direction[3],
  const double a[3], const double b[3], const double c[3], double tMin, double tMax, double& t)
{
  const double e1[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
  const double e2[3] = { c[0] - a[0], c[1] - a[1], c[2] - a[2] };
  return IntersectEdges(origin, direction, a, e1, e2, tMin, tMax, t);
}

//------------------------------------------------------------------------------
bool RayCaster::UnitDirection(const double origin[3], const double direction[3], double unit[3])
{
  const double len2 = direction[0] * direction[0] + direction[1] * direction[1] +
    direction[2] * direction[2];
  if (!(len2 > 0.0) || !std::isfinite(len2) || !std::isfinite(origin[0]) ||
    !std::isfinite(origin[1]) || !std::isfinite(origin[2]))
  {
    return false;
  }
  const double len = std::sqrt(len2);
  for (int k = 0; k < 3; ++k)
  {
    unit[k] = direction[k] / len;
  }
  return true;
}

//------------------------------------------------------------------------------
template <bool AnyHit>
bool RayCaster::Traverse(const double origin[3], const double direction[3], double tMax,
  double& tOut, int& triangleOut) const
{
  if (Root_.Count < 0 || !(tMax > Epsilon_))
  {
    return false;
  }
  double d[3];
  if (!UnitDirection(origin, direction, d))
  {
    return false;
  }
  // Inverse direction; a (near) zero component becomes a tiny one of the same
  // sign, which gives the limit of the slab test without 0 * inf = NaN.
  double inv[3];
  int nearPlane[3], farPlane[3];
  for (int k = 0; k < 3; ++k)
  {
    const double dk = std::abs(d[k]) > 1e-300 ? d[k] : std::copysign(1e-300, d[k]);
    inv[k] = 1.0 / dk;
    nearPlane[k] = inv[k] >= 0.0 ? k : k + 3;
    farPlane[k] = inv[k] >= 0.0 ? k + 3 : k;
  }
  // Robust slab test (Ize 2013): the exit distance grows by 2 gamma_3 to
  // cover the rounding of (plane - o) * inv.
  constexpr double u = std::numeric_limits<double>::epsilon() * 0.5;
  constexpr double exitScale = 1.0 + 2.0 * (3.0 * u) / (1.0 - 3.0 * u);
  const double tMin = Epsilon_;
  double tBest = tMax;
  // Entry distance into a box given as min x, y, z, max x, y, z (float or
  // double); false if the ray misses it within (tMin, tBest].
  auto boxEntry = [&](const auto* b, double& entry) {
    const double t0x = (static_cast<double>(b[nearPlane[0]]) - origin[0]) * inv[0];
    const double t0y = (static_cast<double>(b[nearPlane[1]]) - origin[1]) * inv[1];
    const double t0z = (static_cast<double>(b[nearPlane[2]]) - origin[2]) * inv[2];
    const double t1x = (static_cast<double>(b[farPlane[0]]) - origin[0]) * inv[0];
    const double t1y = (static_cast<double>(b[farPlane[1]]) - origin[1]) * inv[1];
    const double t1z = (static_cast<double>(b[farPlane[2]]) - origin[2]) * inv[2];
    const double tNear = std::max(std::max(t0x, t0y), std::max(t0z, tMin));
    const double tFar = std::min(std::min(t1x, t1y), t1z) * exitScale;
    entry = tNear;
    return tNear <= std::min(tFar, tBest);
  };

  struct Entry
  {
    Child Item;
    double TNear;
  };
  Entry stack[MaxDepth];
  int top = 0;
  double entry;
  if (!boxEntry(RootBounds_, entry))
  {
    return false;
  }
  int hit = -1;
  Child current = Root_;
  while (true)
  {
    if (current.Count > 0)
    {
      const double* tri = &Triangles_[9 * static_cast<size_t>(current.Ref)];
      for (int k = 0; k < current.Count; ++k, tri += 9)
      {
        double t;
        if (IntersectEdges(origin, d, tri, tri + 3, tri + 6, tMin, tBest, t))
        {
          if (AnyHit)
          {
            return true;
          }
          tBest = t;
          hit = current.Ref + k;
        }
      }
    }
    else
    {
      // Both children's boxes are in this node's cache line; go to the
      // nearer child hit first and keep the other for later.
      const Node& node = Nodes_[current.Ref];
      double tLeft, tRight;
      const bool hitLeft = boxEntry(node.Bounds[0], tLeft);
      const bool hitRight = boxEntry(node.Bounds[1], tRight);
      if (hitLeft && hitRight)
      {
        const int nearChild = tRight < tLeft ? 1 : 0;
        stack[top++] = { node.Children[1 - nearChild], nearChild ? tLeft : tRight };
        current = node.Children[nearChild];
        continue;
      }
      if (hitLeft || hitRight)
      {
        current = node.Children[hitLeft ? 0 : 1];
        continue;
      }
    }
    // Pop the next subtree that may still hold a closer hit.
    bool found = false;
    while (top > 0)
    {
      const Entry& e = stack[--top];
      if (e.TNear <= tBest)
      {
        current = e.Item;
        found = true;
        break;
      }
    }
    if (!found)
    {
      break;
    }
  }
  if (hit < 0)
  {
    return false;
  }
  tOut = tBest;
  triangleOut = TriangleIds_[hit];
  return true;
}

//------------------------------------------------------------------------------
bool RayCaster::Occluded(const double origin[3], const double direction[3], double tMax) const
{
  double t;
  int triangle;
  return Traverse<true>(origin, direction, tMax, t, triangle);
}

//------------------------------------------------------------------------------
bool RayCaster::FirstHit(const double origin[3], const double direction[3], double tMax,
  double& t, int& triangle) const
{
  return Traverse<false>(origin, direction, tMax, t, triangle);
}

} // namespace translucency
