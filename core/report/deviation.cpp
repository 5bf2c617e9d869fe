// Deviation fields: the signed distance of every vertex of a surface to a reference, and the
// defect flags of its triangles.
#include "vdbwrap/deviation.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>

#include "common/edge_key.h"
#include "common/exact_weld.h"
#include "common/vec.h"
#include "mesh/surface_index.h"
#include "post/quality.h"

namespace vdbwrap {

// The public bits are the quality analysis' own (one byte per triangle crosses unchanged).
constexpr bool same_bit(DefectFlag a, post::DefectFlag b) { return int(a) == int(b); }
static_assert(same_bit(kDefectSelfIntersecting, post::kSelfIntersecting) &&
                  same_bit(kDefectSmallArea, post::kSmallArea) && same_bit(kDefectSliver, post::kSliver) &&
                  same_bit(kDefectShortEdge, post::kShortEdge) && same_bit(kDefectLongEdge, post::kLongEdge) &&
                  same_bit(kDefectNormalDeviation, post::kNormalDeviation) &&
                  same_bit(kDefectLostFeature, post::kLostFeature),
              "DefectFlag must match post::DefectFlag");

namespace {

// The reference welded exactly, without its zero-area triangles, with the angle-weighted
// pseudo-normals of its vertices and edges (Baerentzen and Aanaes): at the nearest point p of a
// closed, consistently oriented surface, the sign of dot(q - p, n) tells the side of q, whether
// p is inside a face, on an edge or at a vertex.
class OrientedReference {
 public:
  explicit OrientedReference(const Mesh& mesh) {
    ExactWeld weld = exact_weld(mesh.points);
    points_ = std::move(weld.unique);
    for (const Tri& t : mesh.triangles) {
      const Tri w{weld.remap[t[0]], weld.remap[t[1]], weld.remap[t[2]]};
      const Vec3 n = area_vector(points_[w[0]], points_[w[1]], points_[w[2]]);
      if (norm2(n) > 0) triangles_.push_back(w), face_normal_.push_back(normalized(n));
    }
    vertex_normal_.assign(points_.size(), Vec3{0, 0, 0});
    for (size_t f = 0; f < triangles_.size(); ++f) {
      const Tri& t = triangles_[f];
      for (int k = 0; k < 3; ++k) {
        const Vec3 &p = points_[t[k]], &u = points_[t[(k + 1) % 3]], &v = points_[t[(k + 2) % 3]];
        const double angle = std::atan2(norm(cross(u - p, v - p)), dot(u - p, v - p));
        vertex_normal_[t[k]] = vertex_normal_[t[k]] + face_normal_[f] * angle;
      }
    }
    build_edges();
  }

  bool empty() const { return triangles_.empty(); }
  const std::vector<Vec3>& points() const { return points_; }
  const std::vector<Tri>& triangles() const { return triangles_; }
  DistanceSign sign() const { return sign_; }

  // +1 or -1: the side of q at its nearest point `hit` (+ where the normals point); 0 on it.
  double side(const Vec3& q, const mesh::SurfaceIndex::Hit& hit) const {
    const Vec3 d = q - hit.point;
    if (norm2(d) == 0) return 0;
    return dot(d, pseudo_normal(hit.point, hit.triangle)) < 0 ? -1.0 : 1.0;
  }

  // -1 when a closed, consistently oriented reference faces inward: its "outside" is then the
  // side its normals do not point to.
  double orientation() const { return orientation_; }

 private:
  // The pseudo-normal at p on triangle f: the face's inside it, the edge's or the vertex's on
  // its border (barycentric weights within a tolerance of zero: the nearest point computed on an
  // edge or at a corner lands within rounding of it).
  Vec3 pseudo_normal(const Vec3& p, uint32_t f) const {
    const Tri& t = triangles_[f];
    const Vec3 &a = points_[t[0]], &b = points_[t[1]], &c = points_[t[2]];
    const Vec3 n = area_vector(a, b, c);
    const double n2 = norm2(n);
    const double w[3] = {dot(area_vector(p, b, c), n) / n2, dot(area_vector(a, p, c), n) / n2,
                         dot(area_vector(a, b, p), n) / n2};
    constexpr double kZero = 1e-7;
    int zeros = 0, last_zero = -1, nonzero = -1;
    for (int k = 0; k < 3; ++k) {
      if (w[k] < kZero)
        ++zeros, last_zero = k;
      else
        nonzero = k;
    }
    if (zeros == 0) return face_normal_[f];
    if (zeros == 1) return edge_normal(t[(last_zero + 1) % 3], t[(last_zero + 2) % 3]);
    return vertex_normal_[t[nonzero >= 0 ? nonzero : 0]];
  }

  Vec3 edge_normal(uint32_t a, uint32_t b) const {
    const uint64_t key = edge_key(a, b);
    auto it = std::lower_bound(edges_.begin(), edges_.end(), key,
                               [](const std::pair<uint64_t, Vec3>& e, uint64_t k) { return e.first < k; });
    return it != edges_.end() && it->first == key ? it->second : Vec3{0, 0, 0};
  }

  // Edge pseudo-normals (the sum of the faces' normals at each edge), and what the edges say
  // of the reference: closed (no edge with one face) and consistently oriented (every edge used
  // as often in one direction as in the other).
  void build_edges() {
    struct Use {
      uint64_t key;
      uint32_t face;
      bool forward;  // from the smaller index to the larger
      bool operator<(const Use& o) const { return key != o.key ? key < o.key : face < o.face; }
    };
    std::vector<Use> uses(3 * triangles_.size());
    for (size_t f = 0; f < triangles_.size(); ++f)
      for (int k = 0; k < 3; ++k) {
        const uint32_t u = triangles_[f][k], v = triangles_[f][(k + 1) % 3];
        uses[3 * f + size_t(k)] = {edge_key(u, v), uint32_t(f), u < v};
      }
    tbb::parallel_sort(uses.begin(), uses.end());
    bool closed = true, oriented = true;
    for (size_t i = 0; i < uses.size();) {
      size_t j = i;
      Vec3 sum{0, 0, 0};
      int balance = 0;
      for (; j < uses.size() && uses[j].key == uses[i].key; ++j)
        sum = sum + face_normal_[uses[j].face], balance += uses[j].forward ? 1 : -1;
      if (j - i == 1) closed = false;
      if (j - i > 1 && balance != 0) oriented = false;
      edges_.emplace_back(uses[i].key, sum);
      i = j;
    }
    if (triangles_.empty() || !oriented) {
      sign_ = DistanceSign::Unsigned;
    } else if (closed) {
      sign_ = DistanceSign::Outside;
      // The enclosed volume's sign (about the centroid of the points, for less rounding).
      Vec3 centre{0, 0, 0};
      for (const Vec3& p : points_) centre = centre + p;
      centre = centre * (1.0 / double(points_.size()));
      double volume = 0;
      for (const Tri& t : triangles_)
        volume += dot(points_[t[0]] - centre, cross(points_[t[1]] - centre, points_[t[2]] - centre));
      if (volume < 0) orientation_ = -1;
    } else {
      sign_ = DistanceSign::FrontSide;
    }
  }

  std::vector<Vec3> points_;
  std::vector<Tri> triangles_;
  std::vector<Vec3> face_normal_, vertex_normal_;
  std::vector<std::pair<uint64_t, Vec3>> edges_;  // sorted by key
  DistanceSign sign_ = DistanceSign::Unsigned;
  double orientation_ = 1;
};

}  // namespace

std::vector<std::string> defect_flag_names(uint8_t flags) {
  static const char* const kNames[8] = {"self_intersecting", "small_area",       "sliver",       "short_edge",
                                        "long_edge",         "normal_deviation", "lost_feature", "held_back"};
  std::vector<std::string> names;
  for (int bit = 0; bit < 8; ++bit)
    if (flags & (1u << bit)) names.emplace_back(kNames[bit]);
  return names;
}

std::vector<uint8_t> geometric_defect_flags(const Mesh& surface, double cell_size) {
  const auto& p = surface.points;
  std::vector<uint8_t> flags(surface.triangles.size(), 0);
  for (const Tri& t : surface.triangles)
    for (uint32_t v : t)
      if (v >= p.size()) throw Error(ErrorKind::InvalidArgument, "defect flags: a triangle refers to a missing vertex");
  if (!(cell_size > 0)) {
    // Without a voxel stage, the surface's typical edge stands for the local cell size.
    std::vector<double> edges;
    edges.reserve(3 * surface.triangles.size());
    for (const Tri& t : surface.triangles)
      for (int k = 0; k < 3; ++k) edges.push_back(norm(p[t[(k + 1) % 3]] - p[t[k]]));
    if (edges.empty()) return flags;
    std::nth_element(edges.begin(), edges.begin() + edges.size() / 2, edges.end());
    cell_size = edges[edges.size() / 2];
  }
  const QualityThresholds thresholds;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, surface.triangles.size(), 4096),
                    [&](const tbb::blocked_range<size_t>& r) {
                      for (size_t f = r.begin(); f != r.end(); ++f) {
                        const Tri& t = surface.triangles[f];
                        const Vec3 &a = p[t[0]], &b = p[t[1]], &c = p[t[2]];
                        flags[f] = post::shape_flags(a, b, c, cell_size, thresholds);
                        if (norm2(area_vector(a, b, c)) == 0) flags[f] |= kDefectSelfIntersecting;  // degenerate
                      }
                    });
  return flags;
}

DeviationField measure_deviation(const Mesh& surface, const Mesh& reference, const std::vector<uint8_t>* defect_flags) {
  for (const Mesh* m : {&surface, &reference})
    for (const Tri& t : m->triangles)
      for (uint32_t v : t)
        if (v >= m->points.size())
          throw Error(ErrorKind::InvalidArgument, std::string("deviation: a triangle of the ") +
                                                      (m == &surface ? "surface" : "reference") +
                                                      " refers to a missing vertex");
  if (defect_flags && defect_flags->size() != surface.triangles.size())
    throw Error(ErrorKind::InvalidArgument, "deviation: " + std::to_string(defect_flags->size()) +
                                                " defect flags for " + std::to_string(surface.triangles.size()) +
                                                " triangles");
  DeviationField field;
  field.triangle_flags = defect_flags ? *defect_flags : geometric_defect_flags(surface);
  Box3 box;
  for (const Vec3& q : reference.points) box.add(q);
  field.diagonal = reference.points.empty() ? 0 : box.diagonal();
  field.distance.assign(surface.points.size(), 0.0);

  const OrientedReference ref(reference);
  field.sign = ref.sign();
  if (ref.empty() || surface.points.empty()) return field;
  const mesh::SurfaceIndex index(ref.points(), ref.triangles());
  const double outward = ref.orientation();
  const bool signed_field = field.sign != DistanceSign::Unsigned;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, surface.points.size(), 512),
                    [&](const tbb::blocked_range<size_t>& r) {
                      uint32_t hint = UINT32_MAX;  // neighbouring vertices tend to share a nearest triangle
                      for (size_t i = r.begin(); i != r.end(); ++i) {
                        const Vec3& q = surface.points[i];
                        const mesh::SurfaceIndex::Hit hit = index.closest(q, hint);
                        hint = hit.triangle;
                        const double d = std::sqrt(hit.squared_distance);
                        field.distance[i] = signed_field ? outward * ref.side(q, hit) * d : d;
                      }
                    });

  std::vector<double> magnitude(field.distance.size());
  double sum = 0;
  for (size_t i = 0; i < field.distance.size(); ++i) {
    magnitude[i] = std::fabs(field.distance[i]);
    sum += magnitude[i];
    if (magnitude[i] > field.max_abs || i == 0) field.max_abs = magnitude[i], field.max_vertex = uint32_t(i);
  }
  field.max_at = surface.points[field.max_vertex];
  field.mean_abs = sum / double(magnitude.size());
  const size_t k95 = std::min(magnitude.size() - 1, size_t(0.95 * double(magnitude.size())));
  std::nth_element(magnitude.begin(), magnitude.begin() + k95, magnitude.end());
  field.p95_abs = magnitude[k95];
  return field;
}

}  // namespace vdbwrap
