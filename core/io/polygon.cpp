// Triangulation of the polygon faces of OBJ, OFF and PLY files.
#include <algorithm>
#include <cmath>

#include "common/vec.h"
#include "io/readers.h"

namespace vdbwrap::io::detail {
namespace {

// Newell's normal: twice the vector area, robust for non-planar and non-convex polygons.
// Coordinates are taken relative to the first vertex to keep precision far from the origin.
Vec3 newell_normal(const std::vector<Vec3>& points, const uint32_t* poly, size_t n) {
  const Vec3& origin = points[poly[0]];
  Vec3 normal{0, 0, 0};
  for (size_t i = 0; i < n; ++i) {
    Vec3 a = points[poly[i]] - origin;
    Vec3 b = points[poly[(i + 1) % n]] - origin;
    normal[0] += (a[1] - b[1]) * (a[2] + b[2]);
    normal[1] += (a[2] - b[2]) * (a[0] + b[0]);
    normal[2] += (a[0] - b[0]) * (a[1] + b[1]);
  }
  return normal;
}

// Orientation of 2D triangle (a, b, c): > 0 counter-clockwise.
double orient(double ax, double ay, double bx, double by, double cx, double cy) {
  return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
}

void fan(const uint32_t* poly, size_t n, std::vector<Tri>& out) {
  for (size_t i = 1; i + 1 < n; ++i) out.push_back({poly[0], poly[i], poly[i + 1]});
}

}  // namespace

void PolygonTriangulator::run(const std::vector<Vec3>& points, const uint32_t* poly, size_t n, std::vector<Tri>& out) {
  if (n == 3) {
    out.push_back({poly[0], poly[1], poly[2]});
    return;
  }
  if (!project(points, poly, n)) {
    fan(poly, n, out);  // zero area: no plane to clip ears in
    return;
  }
  ear_clip(poly, n, out);
}

// Projects the polygon into a 2D frame (e1, e2) of its Newell plane with e1 x e2 = normal,
// so the polygon is counter-clockwise in 2D. False when the polygon has no area.
bool PolygonTriangulator::project(const std::vector<Vec3>& points, const uint32_t* poly, size_t n) {
  Vec3 normal = newell_normal(points, poly, n);
  double len = std::sqrt(dot(normal, normal));
  if (!(len > 0) || !std::isfinite(len)) return false;
  for (double& c : normal) c /= len;
  // e1: perpendicular to the normal, built from the axis least aligned with it.
  int axis = 0;
  for (int k = 1; k < 3; ++k)
    if (std::abs(normal[k]) < std::abs(normal[axis])) axis = k;
  Vec3 helper{0, 0, 0};
  helper[axis] = 1;
  Vec3 e1 = cross(normal, helper);
  double e1_len = std::sqrt(dot(e1, e1));
  for (double& c : e1) c /= e1_len;
  Vec3 e2 = cross(normal, e1);

  u_.resize(n);
  v_.resize(n);
  const Vec3& origin = points[poly[0]];
  for (size_t i = 0; i < n; ++i) {
    Vec3 d = points[poly[i]] - origin;
    u_[i] = dot(d, e1);
    v_[i] = dot(d, e2);
  }
  return true;
}

// Classic O(n^2) ear clipping. Starting at vertex 1 makes convex polygons come out as the
// same fan around vertex 0 that simple readers produce.
void PolygonTriangulator::ear_clip(const uint32_t* poly, size_t n, std::vector<Tri>& out) {
  prev_.resize(n);
  next_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    prev_[i] = (i + n - 1) % n;
    next_[i] = (i + 1) % n;
  }
  size_t remaining = n;
  size_t i = 1;
  size_t misses = 0;  // consecutive vertices that were not ears
  while (remaining > 3) {
    size_t a = prev_[i], c = next_[i];
    if (is_ear(a, i, c)) {
      out.push_back({poly[a], poly[i], poly[c]});
      next_[a] = c;
      prev_[c] = a;
      --remaining;
      misses = 0;
      i = c;
    } else if (++misses >= remaining) {
      break;  // no ear left: self-intersecting or degenerate remainder
    } else {
      i = next_[i];
    }
  }
  if (remaining == 3) {
    out.push_back({poly[prev_[i]], poly[i], poly[next_[i]]});
    return;
  }
  // No ear found: fan over what remains.
  for (size_t k = next_[i]; next_[k] != i; k = next_[k]) out.push_back({poly[i], poly[k], poly[next_[k]]});
}

// b is an ear when it is a strictly convex corner and no other remaining vertex lies in or on
// triangle (a, b, c). Vertices at the same position as a corner (seams that join a hole to its
// outline) do not block the ear.
bool PolygonTriangulator::is_ear(size_t a, size_t b, size_t c) const {
  const double ax = u_[a], ay = v_[a], bx = u_[b], by = v_[b], cx = u_[c], cy = v_[c];
  if (!(orient(ax, ay, bx, by, cx, cy) > 0)) return false;
  for (size_t p = next_[c]; p != a; p = next_[p]) {
    const double px = u_[p], py = v_[p];
    if ((px == ax && py == ay) || (px == bx && py == by) || (px == cx && py == cy)) continue;
    if (orient(ax, ay, bx, by, px, py) >= 0 && orient(bx, by, cx, cy, px, py) >= 0 &&
        orient(cx, cy, ax, ay, px, py) >= 0)
      return false;
  }
  return true;
}

}  // namespace vdbwrap::io::detail
