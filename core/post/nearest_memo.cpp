#include "post/nearest_memo.h"

#include <limits>

namespace vdbwrap::post {

NearestMemo::Hit NearestMemo::closest(const Vec3& q) const {
  Hit hit;
  if (!closest_within(q, std::numeric_limits<double>::infinity(), hit))
    hit = input_.closest(q);  // no input: its "none"
  return hit;
}

bool NearestMemo::closest_within(const Vec3& q, double radius, Hit& hit) const {
  const BitwiseKey<3> key = bitwise_key<3>({q[0], q[1], q[2]});
  Known k;
  const bool known = known_.find(key, k);
  if (known) {
    if (k.triangle != UINT32_MAX) {
      // The nearest triangle is within the radius exactly when its distance is: then the
      // index would answer with it (see SurfaceIndex::closest_within).
      const Hit found = input_.hit_on(q, k.triangle);
      if (!(found.squared_distance <= radius * radius)) return false;
      hit = found;
      return true;
    }
    if (radius <= k.none_within) return false;
  }
  // Asked for the first time, or farther than a search that found nothing: the index answers.
  // (Entries are never changed: the first answer for a point stays.)
  const bool found = input_.closest_within(q, radius, hit);
  if (!known) known_.insert(key, Known{found ? hit.triangle : UINT32_MAX, radius});
  return found;
}

}  // namespace vdbwrap::post
