// Long triangles cut into slabs (see slab_boxes.h).
#include "check/slab_boxes.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace vdbwrap::check::pair_search {
namespace {

CGAL::Bbox_3 triangle_box(const std::vector<P3>& p, const Tri& t) {
  return p[t[0]].bbox() + p[t[1]].bbox() + p[t[2]].bbox();
}
int longest_axis(const CGAL::Bbox_3& b) {
  int axis = 0;
  for (int k = 1; k < 3; ++k)
    if (b.max(k) - b.min(k) > b.max(axis) - b.min(axis)) axis = k;
  return axis;
}

// The box of the part of triangle v with coordinate `axis` in [s0, s1], widened by `pad` so
// that rounding leaves none of it out: the corners inside the slab and where the sides cross
// its two planes.
CGAL::Bbox_3 slab_part_box(const std::array<const P3*, 3>& v, int axis, double s0, double s1, double pad) {
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  auto add = [&](double x, double y, double z) {
    const double q[3] = {x, y, z};
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], q[k]), hi[k] = std::max(hi[k], q[k]);
  };
  for (int e = 0; e < 3; ++e) {
    const P3 &a = *v[e], &b = *v[(e + 1) % 3];
    if (a[axis] >= s0 && a[axis] <= s1) add(a.x(), a.y(), a.z());
    for (double s : {s0, s1})
      if ((a[axis] - s) * (b[axis] - s) < 0) {
        const double t = (s - a[axis]) / (b[axis] - a[axis]);
        add(a.x() + t * (b.x() - a.x()), a.y() + t * (b.y() - a.y()), a.z() + t * (b.z() - a.z()));
      }
  }
  lo[axis] = std::max(lo[axis], s0), hi[axis] = std::min(hi[axis], s1);
  return CGAL::Bbox_3(lo[0] - pad, lo[1] - pad, lo[2] - pad, hi[0] + pad, hi[1] + pad, hi[2] + pad);
}

// Slab k of a triangle cut into `count` along the longest axis of its box b: [s0, s1].
std::pair<double, double> slab_range(const CGAL::Bbox_3& b, int axis, uint32_t k, uint32_t count) {
  const double width = (b.max(axis) - b.min(axis)) / count;
  return {k == 0 ? b.min(axis) : b.min(axis) + k * width, k + 1 == count ? b.max(axis) : b.min(axis) + (k + 1) * width};
}

}  // namespace

SlabBoxes slab_boxes(const std::vector<P3>& p, const std::vector<Tri>& triangles, const std::vector<uint8_t>& usable) {
  const size_t n = triangles.size();
  SlabBoxes out;
  out.first.assign(n + 1, 0);
  std::vector<double> extents(n, -1);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t t = r.begin(); t != r.end(); ++t)
      if (usable[t]) {
        const CGAL::Bbox_3 b = triangle_box(p, triangles[t]);
        extents[t] = b.max(longest_axis(b)) - b.min(longest_axis(b));
      }
  });
  std::vector<double> sizes;
  for (double e : extents)
    if (e >= 0) sizes.push_back(e);
  if (sizes.empty()) return out;
  std::nth_element(sizes.begin(), sizes.begin() + sizes.size() / 2, sizes.end());
  // About the grid's cell (grid_candidate_pairs); at most 16 slabs (more only add boxes to
  // sort).
  const double slab = 2 * sizes[sizes.size() / 2];
  constexpr double most_slabs = 16;
  for (size_t t = 0; t < n; ++t) {
    const double length = extents[t];
    const uint32_t slabs = length < 0                      ? 0
                           : slab > 0 && length > 4 * slab ? uint32_t(std::min(most_slabs, std::ceil(length / slab)))
                                                           : 1;
    out.first[t + 1] = out.first[t] + slabs;
  }
  out.boxes.resize(out.first[n]);  // filled below, in parallel
  out.owner.resize(out.first[n]);
  const double eps = std::numeric_limits<double>::epsilon();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t t = r.begin(); t != r.end(); ++t) {
      const uint32_t count = out.count(uint32_t(t));
      for (uint32_t k = 0; k < count; ++k) out.owner[out.first[t] + k] = uint32_t(t);
      if (count == 0) continue;
      const CGAL::Bbox_3 b = triangle_box(p, triangles[t]);
      if (count == 1) {
        out.boxes[out.first[t]] = Bounds::of(b);
        continue;
      }
      const Tri& tri = triangles[t];
      const std::array<const P3*, 3> v{&p[tri[0]], &p[tri[1]], &p[tri[2]]};
      const int axis = longest_axis(b);
      const double magnitude = std::max({std::fabs(b.xmin()), std::fabs(b.xmax()), std::fabs(b.ymin()),
                                         std::fabs(b.ymax()), std::fabs(b.zmin()), std::fabs(b.zmax())});
      const double pad = 1e-9 * (b.max(axis) - b.min(axis)) + 64 * eps * magnitude;
      for (uint32_t k = 0; k < count; ++k) {
        const auto [s0, s1] = slab_range(b, axis, k, count);
        out.boxes[out.first[t] + k] = Bounds::of(slab_part_box(v, axis, s0, s1, pad));
      }
    }
  });
  return out;
}

bool met_earlier(const SlabBoxes& s, const std::vector<P3>& p, const std::vector<Tri>& triangles, uint32_t x,
                 uint32_t a, uint32_t y, uint32_t b) {
  if (s.count(x) == 1 && s.count(y) == 1) return false;
  const CGAL::Bbox_3 bx = triangle_box(p, triangles[x]), by = triangle_box(p, triangles[y]);
  auto reaching = [&](uint32_t t, const CGAL::Bbox_3& own, const CGAL::Bbox_3& other) -> std::pair<uint32_t, uint32_t> {
    const uint32_t count = s.count(t);
    if (count == 1) return {s.first[t], s.first[t] + 1};
    const int axis = longest_axis(own);
    const double width = (own.max(axis) - own.min(axis)) / count;
    const double lo = std::floor((other.min(axis) - own.min(axis)) / width) - 1,
                 hi = std::floor((other.max(axis) - own.min(axis)) / width) + 2;
    return {s.first[t] + uint32_t(std::clamp(lo, 0.0, double(count))),
            s.first[t] + uint32_t(std::clamp(hi, 0.0, double(count)))};
  };
  const auto [x0, x1] = reaching(x, bx, by);
  const auto [y0, y1] = reaching(y, by, bx);
  for (uint32_t i = x0; i <= a && i < x1; ++i)
    for (uint32_t j = y0; j < y1 && (i < a || j < b); ++j)
      if (s.boxes[i].overlaps(s.boxes[j])) return true;
  return false;
}

}  // namespace vdbwrap::check::pair_search
