// Stage 2c, the lattice extraction: the cell faces between the chosen volume and the rest,
// their corners numbered as nodes, and the polygons with the nodes on their edges inserted.
#include "extract/extract_surface.h"

#include <algorithm>
#include <limits>
#include <utility>

#include <tbb/parallel_for.h>

#include "common/dense_numbers.h"
#include "common/fill_vector.h"
#include "common/radix_sort.h"
#include "extract/lattice_faces.h"

namespace vdbwrap::extract {
namespace {

using grid::AdaptiveGrid;
using grid::LeafRef;

// Quad on the plane `axis` = plane, spanning [u0,u0+s] x [v0,v0+s] in the two other axes,
// ordered so its normal points along `normal_dir` * axis.
Quad make_quad(int axis, int32_t plane, int32_t u0, int32_t v0, int32_t s, int normal_dir) {
  const int b = (axis + 1) % 3, c = (axis + 2) % 3;
  auto at = [&](int32_t u, int32_t v) {
    Coord p;
    p[axis] = plane;
    p[b] = u;
    p[c] = v;
    return p;
  };
  Quad q;
  q.size = s;
  q.corner[0] = at(u0, v0);
  q.corner[1] = at(u0 + s, v0);
  q.corner[2] = at(u0 + s, v0 + s);
  q.corner[3] = at(u0, v0 + s);
  if (normal_dir < 0) std::swap(q.corner[1], q.corner[3]);
  return q;
}

// The level-0 cells of plane z = `plane` that may have a face, in the order of for_each_leaf.
void level0_cells_with_faces(const AdaptiveGrid& g, int32_t label, int plane,
                             std::vector<std::pair<int, Coord>>& cells) {
  AdaptiveGrid::Reader reader(g);
  auto closed = [&](const AdaptiveGrid::Block& b, int axis, int dir) {
    const int across = dir < 0 ? b.lo[axis] - 1 : b.hi[axis];
    if (across < 0 || across >= g.dims0()[axis]) return false;
    Coord next = b.lo;
    next[axis] = across & ~(AdaptiveGrid::kBlock - 1);
    int32_t v;
    return reader.uniform_block(next, v) && v == label;
  };
  g.for_each_level0_run(
      [&](const Coord& first, int length, int32_t v, const AdaptiveGrid::Block& b) {
        if (v != label) return;
        const int y = first.y(), z = first.z();
        const bool side_row = (y == b.lo.y() && !closed(b, 1, -1)) || (y == b.hi.y() - 1 && !closed(b, 1, 1)) ||
                              (z == b.lo.z() && !closed(b, 2, -1)) || (z == b.hi.z() - 1 && !closed(b, 2, 1));
        if (side_row) {
          for (int x = first.x(); x < first.x() + length; ++x) cells.emplace_back(0, Coord(x, y, z));
          return;
        }
        const bool low = !closed(b, 0, -1), high = !closed(b, 0, 1);
        if (length == 1) {
          if (low || high) cells.emplace_back(0, first);
          return;
        }
        if (low) cells.emplace_back(0, first);
        if (high) cells.emplace_back(0, Coord(first.x() + length - 1, y, z));
      },
      [&](const Coord& c, int32_t v) {
        if (v == label) cells.emplace_back(0, c);
      },
      plane, plane + 1);
}

// The volume's leaves that may have a face, in the order of for_each_leaf. In a uniform
// level-0 block of the volume only cells on its sides can, and only on sides where the next
// block is not all volume too: the cells deep inside an outside volume (most of a fine box)
// are never listed. Level 0 is listed in parallel, a plane of cells to a part, joined in
// order: on a fine grid the listing is a large share of each extraction round.
std::vector<std::pair<int, Coord>> cells_with_faces(const AdaptiveGrid& g, int32_t label) {
  std::vector<std::vector<std::pair<int, Coord>>> planes(size_t(std::max(0, g.dims0().z())));
  tbb::parallel_for(size_t(0), planes.size(), [&](size_t z) { level0_cells_with_faces(g, label, int(z), planes[z]); });
  std::vector<std::pair<int, Coord>> cells;
  size_t total = 0;
  for (const auto& p : planes) total += p.size();
  cells.reserve(total);
  for (auto& p : planes) cells.insert(cells.end(), p.begin(), p.end()), std::vector<std::pair<int, Coord>>().swap(p);
  g.for_each_fine_leaf([&](int level, const Coord& c, int32_t v) {
    if (v == label) cells.emplace_back(level, c);
  });
  return cells;
}

}  // namespace

FacesAndNodes faces_and_nodes(const AdaptiveGrid& g, int32_t label, VolumeChoice choice) {
  // The wrap's outward normal points into the outside volume, or out of an inside volume.
  const int orient = choice == VolumeChoice::Outside ? -1 : 1;
  // The volume's cells first, then their faces in parallel (the grid is only read), in
  // chunks joined in cell order: the same quads in the same order as one pass would give.
  const std::vector<std::pair<int, Coord>> cells = cells_with_faces(g, label);
  constexpr size_t chunk = 2048;
  std::vector<std::vector<Quad>> chunks((cells.size() + chunk - 1) / chunk);
  tbb::parallel_for(size_t(0), chunks.size(), [&](size_t k) {
    std::vector<Quad>& out = chunks[k];
    AdaptiveGrid::Reader reader(g);  // neighbouring cells: cached reads
    for (size_t i = k * chunk; i < std::min(cells.size(), (k + 1) * chunk); ++i) {
      const auto& [level, c] = cells[i];
      const int32_t s = g.fine_units(level);
      const Coord C(c.x() * s, c.y() * s, c.z() * s);
      for (int axis = 0; axis < 3; ++axis)
        for (int dir = -1; dir <= 1; dir += 2) {
          const int32_t plane = C[axis] + (dir > 0 ? s : 0);
          const int b = (axis + 1) % 3, cc = (axis + 2) % 3;
          reader.for_each_face_neighbour(level, c, axis, dir, [&, level = level](const LeafRef& n) {
            if (in_volume(n, label, choice)) return;
            if (n.outside_box || n.level <= level) {
              out.push_back(make_quad(axis, plane, C[b], C[cc], s, orient * dir));
            } else {
              const int32_t sn = g.fine_units(n.level);
              out.push_back(make_quad(axis, plane, n.ijk[b] * sn, n.ijk[cc] * sn, sn, orient * dir));
            }
          });
        }
    }
  });
  FacesAndNodes out;
  std::vector<Quad>& quads = out.quads;
  for (auto& part : chunks) quads.insert(quads.end(), part.begin(), part.end()), std::vector<Quad>().swap(part);

  // Nodes: the quads' corners, numbered in order of first appearance (quad by quad, corner
  // by corner), each with the smallest quad at it. Not a serial hash map filled corner by
  // corner, which would cost a large share of each round: here a stable radix sort of
  // (lattice point, corner) groups the corners of each point, in parallel, the first of each
  // group is its first appearance, and one pass over the corners in order numbers them.
  LatticeSurface& surf = out.surf;
  const DenseNumbers lattice = out.lattice = lattice_numbers(g);
  auto number = [&](const Coord& p) { return lattice.number(p.x(), p.y(), p.z()); };
  struct CornerRef {
    uint64_t point;   // the lattice point's number
    uint32_t corner;  // quad * 4 + corner
  };
  constexpr size_t kQuadChunk = 8192;
  std::vector<std::vector<CornerRef>> parts((quads.size() + kQuadChunk - 1) / kQuadChunk);
  tbb::parallel_for(size_t(0), parts.size(), [&](size_t k) {
    const size_t end = std::min(quads.size(), (k + 1) * kQuadChunk);
    parts[k].reserve(4 * (end - k * kQuadChunk));
    for (size_t i = k * kQuadChunk; i < end; ++i)
      for (int c = 0; c < 4; ++c) parts[k].push_back({number(quads[i].corner[c]), uint32_t(4 * i + size_t(c))});
  });
  const FillVector<CornerRef> sorted = radix_sort_joined(
      parts, [](const CornerRef& r) { return r.point; }, bits_for(lattice.count));
  std::vector<uint64_t>& group_point = out.group_point;
  std::vector<size_t> group_start;
  for (size_t i = 0; i < sorted.size(); ++i)
    if (i == 0 || sorted[i].point != sorted[i - 1].point)
      group_point.push_back(sorted[i].point), group_start.push_back(i);
  const size_t groups = group_point.size();
  group_start.push_back(sorted.size());
  std::vector<uint32_t>& group_of_corner = out.group_of_corner;
  group_of_corner.resize(4 * quads.size());
  std::vector<uint32_t> group_first_at(4 * quads.size(), UINT32_MAX);
  std::vector<int32_t> group_size(groups);
  tbb::parallel_for(size_t(0), groups, [&](size_t k) {
    int32_t size = std::numeric_limits<int32_t>::max();
    for (size_t i = group_start[k]; i < group_start[k + 1]; ++i) {
      group_of_corner[sorted[i].corner] = uint32_t(k);
      size = std::min(size, quads[sorted[i].corner / 4].size);
    }
    group_size[k] = size;
    group_first_at[sorted[group_start[k]].corner] = uint32_t(k);  // the sort is stable: the lowest corner
  });
  std::vector<uint32_t>& node_of_group = out.node_of_group;
  node_of_group.resize(groups);
  surf.nodes.reserve(groups);
  surf.node_size.reserve(groups);
  for (size_t c = 0; c < group_first_at.size(); ++c) {
    const uint32_t k = group_first_at[c];
    if (k == UINT32_MAX) continue;
    node_of_group[k] = uint32_t(surf.nodes.size());
    surf.nodes.push_back(quads[c / 4].corner[c % 4]);
    surf.node_size.push_back(group_size[k]);
  }
  return out;
}

LatticeSurface with_polygons(FacesAndNodes&& fn) {
  LatticeSurface surf = std::move(fn.surf);
  const std::vector<Quad>& quads = fn.quads;
  const std::vector<uint64_t>& group_point = fn.group_point;
  const std::vector<uint32_t>& group_of_corner = fn.group_of_corner;
  const std::vector<uint32_t>& node_of_group = fn.node_of_group;
  auto number = [&](const Coord& p) { return fn.lattice.number(p.x(), p.y(), p.z()); };
  // Conforming polygons: every surface node on a quad's edge becomes a polygon vertex. The
  // nodes are only read here, so the quads go in parallel.
  surf.polygons.resize(quads.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, quads.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const Quad& q = quads[i];
      std::vector<uint32_t>& poly = surf.polygons[i];
      for (int e = 0; e < 4; ++e) {
        const Coord& a = q.corner[e];
        const Coord& b = q.corner[(e + 1) % 4];
        poly.push_back(node_of_group[group_of_corner[4 * i + size_t(e)]]);
        if (q.size > 1) {
          Coord step((b.x() - a.x()) / q.size, (b.y() - a.y()) / q.size, (b.z() - a.z()) / q.size);
          for (int32_t k = 1; k < q.size; ++k) {
            const uint64_t point = number(Coord(a.x() + step.x() * k, a.y() + step.y() * k, a.z() + step.z() * k));
            const auto it = std::lower_bound(group_point.begin(), group_point.end(), point);
            if (it != group_point.end() && *it == point)
              poly.push_back(node_of_group[size_t(it - group_point.begin())]);
          }
        }
      }
    }
  });
  return surf;
}

LatticeSurface extract_faces(const AdaptiveGrid& g, int32_t label, VolumeChoice choice) {
  return with_polygons(faces_and_nodes(g, label, choice));
}

}  // namespace vdbwrap::extract
