#include "grid/thin_parts.h"

#include "mesh/rough_edges.h"

#include <algorithm>
#include <cmath>

namespace vdbwrap::grid {

namespace {
// Faces meeting at a corner are a fold (a spike of a rough surface, a fin's ridge), not two
// sides of a part across its solid: a rod's sides are apart all round.
bool share_corner(const Tri& a, const Tri& b) {
  for (uint32_t u : a)
    for (uint32_t v : b)
      if (u == v) return true;
  return false;
}
}  // namespace

double thinnest_part(const prep::PreparedInput& in, const std::vector<uint32_t>& cell_tris, const Vec3& centre,
                     double within) {
  if (in.closed_piece.size() != in.mesh.triangles.size()) return within;
  // A closed piece smaller than the cell all round (a pin, a particle, a scan's stray blob) is
  // as thin as it is long, whatever its faces: a tetrahedron has no two sides facing away.
  double best = within;
  for (uint32_t t : cell_tris)
    if (in.closed_piece[t] != mesh::kOpenPiece) best = std::min(best, double(in.closed_piece_size[in.closed_piece[t]]));
  if (cell_tris.size() < 4) return best;
  // Noise as coarse as the faces folds them every way, faces facing away from each other a
  // fraction of a cell apart all over: a rough surface, no part.
  if (in.sharp_all_round.size() == in.mesh.triangles.size() && mesh::cut_up_by_noise(in.sharp_all_round, cell_tris))
    return best;
  constexpr double kOpposite = -0.8;  // cos 143 degrees: a wedge's faces are not a part's two sides
  constexpr double kTurned = 0.7071;  // cos 45 degrees
  constexpr size_t kMostPairs = 64;   // the thinnest pairs weighed against each other
  // Coplanar faces of two closed pieces that touch (an assembly's shared face) are no part.
  const double least = 1e-3 * within;
  struct Face {
    double offset;  // the plane's distance from the centre along the normal
    uint32_t t;
  };
  struct Pair {
    double thickness;
    Vec3 normal;
  };
  std::vector<Face> front, back;
  std::vector<Pair> pairs;
  for (int axis = 0; axis < 3; ++axis) {
    front.clear(), back.clear();
    for (uint32_t t : cell_tris) {
      if (in.closed_piece[t] == mesh::kOpenPiece) continue;
      const Vec3& n = in.normals[t];
      const Face f{dot(n, in.mesh.points[in.mesh.triangles[t][0]] - centre), t};
      if (n[axis] > 0.5) front.push_back(f);
      if (n[axis] < -0.5) back.push_back(f);
    }
    if (front.empty() || back.empty()) continue;
    std::sort(back.begin(), back.end(), [](const Face& a, const Face& b) { return a.offset < b.offset; });
    for (const Face& f : front) {
      // Faces pointing away from each other with solid between: the offsets add up to the
      // thickness (facing each other, across a gap, they add up to minus the gap). The
      // thinnest such pair for this face.
      auto it = std::lower_bound(back.begin(), back.end(), least - f.offset,
                                 [](const Face& a, double v) { return a.offset < v; });
      // Sides of one piece: between faces of two (solids welded along an edge, fanned round
      // it) the offsets measure no solid, only where the centre lies.
      for (; it != back.end() && f.offset + it->offset < within; ++it)
        if (in.closed_piece[it->t] == in.closed_piece[f.t] && dot(in.normals[f.t], in.normals[it->t]) <= kOpposite &&
            !share_corner(in.mesh.triangles[f.t], in.mesh.triangles[it->t])) {
          pairs.push_back({f.offset + it->offset, in.normals[f.t]});
          break;
        }
    }
  }
  // Thin across two directions at least 45 degrees apart: a rod, not a wall (whose rim, where a
  // wall is wrapped in a strip of needles, the sliver removal's rail splits mend at less cost).
  std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) { return a.thickness < b.thickness; });
  if (pairs.size() > kMostPairs) pairs.resize(kMostPairs);
  for (size_t i = 0; i < pairs.size() && pairs[i].thickness < best; ++i)
    for (size_t j = 0; j < i; ++j)
      if (std::abs(dot(pairs[i].normal, pairs[j].normal)) < kTurned) {
        best = pairs[i].thickness;  // the thicker of the two (pairs are sorted)
        break;
      }
  return best;
}

}  // namespace vdbwrap::grid
