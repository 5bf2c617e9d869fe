// Stage 4 asks the input for the nearest point of the same points again and again: a vertex
// for each of its triangles when a region's substrate is gathered, the samples of a region in
// each round that rebuilds it, the quality analysis's probes. The memo keeps each point's
// nearest input triangle, keyed by the point bit for bit, and rebuilds the hit from it, so an
// answer from the memo is exactly the index's.
#pragma once
#include <cstdint>

#include "common/bitwise_key.h"
#include "common/concurrent_memo.h"
#include "mesh/surface_index.h"

namespace vdbwrap::post {

class NearestMemo {
 public:
  using Hit = mesh::SurfaceIndex::Hit;
  explicit NearestMemo(const mesh::SurfaceIndex& input) : input_(input) {}
  // As mesh::SurfaceIndex's calls of the same names (query points in the index's frame); safe
  // to call from several threads at once.
  Hit closest(const Vec3& query) const;
  bool closest_within(const Vec3& query, double radius, Hit& hit) const;

 private:
  struct Known {
    uint32_t triangle;  // the nearest, or UINT32_MAX: none within `none_within`
    double none_within;
  };
  const mesh::SurfaceIndex& input_;
  mutable ConcurrentMemo<BitwiseKey<3>, Known, BitwiseKeyHash> known_;
};

}  // namespace vdbwrap::post
