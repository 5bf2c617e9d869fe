// Stage 4, quality analysis (spec: "Analyse quality"): flags the triangles of a surface that
// intersect others or are degenerate, have a small area or a sliver shape, have edges of
// uncharacteristic length for the local cell size, or approximate the input poorly (normal
// off the input's, sharp edges of the input lost), and counts each kind.
#pragma once
#include <array>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "common/bitwise_key.h"
#include "mesh/surface_index.h"
#include "post/nearest_memo.h"
#include "prep/prepare.h"
#include "vdbwrap/params.h"
#include "vdbwrap/report.h"

namespace vdbwrap::post {

// Per-triangle defect flags.
enum DefectFlag : uint8_t {
  kSelfIntersecting = 1 << 0,
  kSmallArea = 1 << 1,
  kSliver = 1 << 2,
  kShortEdge = 1 << 3,
  kLongEdge = 1 << 4,
  kNormalDeviation = 1 << 5,
  kLostFeature = 1 << 6,
};

// What a surface is measured against. Surfaces are in output coordinates; the input, its
// index and the feature samples in the local frame (local = output - origin).
struct QualityReference {
  const mesh::SurfaceIndex* input = nullptr;
  const NearestMemo* nearest = nullptr;  // optional: answers input's nearest-point queries from a memo
  // The input's nearest point (local frame), from the memo when there is one.
  mesh::SurfaceIndex::Hit closest(const Vec3& q) const { return nearest ? nearest->closest(q) : input->closest(q); }
  bool closest_within(const Vec3& q, double radius, mesh::SurfaceIndex::Hit& hit) const {
    return nearest ? nearest->closest_within(q, radius, hit) : input->closest_within(q, radius, hit);
  }
  Vec3 origin{0, 0, 0};
  std::vector<Vec3> feature_samples;  // along the input's sharp edges
  double finest_size = 0;             // finest cell of the voxel stage
  QualityThresholds thresholds;
};

// Samples every `spacing` along the sharp feature edges of the prepared input (local frame),
// the spacing widened so that there are at most max_samples.
std::vector<Vec3> sample_sharp_edges(const prep::PreparedInput& input, double spacing, size_t max_samples = 200000);

// Smallest angle of a triangle, in degrees (0 for a degenerate one).
double min_angle_deg(const Vec3& a, const Vec3& b, const Vec3& c);

// The shape flags of one triangle (kSmallArea, kSliver) for a local cell size.
uint8_t shape_flags(const Vec3& a, const Vec3& b, const Vec3& c, double cell, const QualityThresholds& t);

// Angle in degrees between a triangle's normal and the input's normal near it (orientation
// ignored: open inputs have none; at an edge or corner of the input, the normal of its cone
// that points at the triangle), the least of its centroid and three inner points; negative
// when the input is farther than near_input x cell (the triangle bridges a gap: nothing to
// compare with).
double normal_deviation_deg(const Vec3& a, const Vec3& b, const Vec3& c, double cell, const QualityReference& ref);

// Normal deviations measured before, by triangle: its corners in order and its cell size,
// compared bit for bit (the value is a function of these alone). The final analysis of a wrap
// meets mostly triangles the first one measured, and asks the input only about the others
// (its nearest-point queries were most of that analysis).
class NormalDeviationMemo {
 public:
  bool find(const Vec3& a, const Vec3& b, const Vec3& c, double cell, double& deviation) const;
  void add(const Vec3& a, const Vec3& b, const Vec3& c, double cell, double deviation);

 private:
  using Key = BitwiseKey<10>;
  static Key key(const Vec3& a, const Vec3& b, const Vec3& c, double cell);
  std::unordered_map<Key, double, BitwiseKeyHash> known_;
};

// Flags every triangle (flags: one byte per triangle, DefectFlag bits; an edge defect flags
// both its triangles) and counts the defects. cell_size: per point. Intersections are found
// with exact predicates unless `intersecting` gives them (sorted triangle ids). A memo, when
// given, answers the normal deviations it knows and learns the others.
QualityCounts analyse_quality(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                              const std::vector<double>& cell_size, const QualityReference& ref,
                              std::vector<uint8_t>* flags = nullptr,
                              const std::vector<uint32_t>* intersecting = nullptr, NormalDeviationMemo* memo = nullptr);

}  // namespace vdbwrap::post
