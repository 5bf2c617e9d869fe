#include "grid/refine.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <unordered_map>
#include <unordered_set>

#include "common/cell_lists.h"
#include "common/closest_point.h"
#include "common/dense_numbers.h"
#include "common/fill_vector.h"
#include "common/grid_key.h"
#include "common/radix_sort.h"
#include "common/vec.h"
#include "grid/thin_parts.h"
#include "vdbwrap/errors.h"

namespace vdbwrap::grid {

namespace {

struct CellTris {
  Coord c;
  std::vector<uint32_t> tris;
};

// Level-0 blocks: kBlock^3 cells, cut from the cells' box (coordinates from -1 to the
// grid's size) starting at cell -1.
constexpr int kBlock = 16;
DenseNumbers block_numbers(const Coord& dims) {
  auto blocks = [](int cells) { return uint64_t((cells + 2 + kBlock - 1) / kBlock); };
  return DenseNumbers({0, 0, 0}, {blocks(dims.x()), blocks(dims.y()), blocks(dims.z())});
}

struct FeatureSegments {
  // per triangle: indices into segments (feature edges and intersection segments it carries)
  std::vector<std::vector<uint32_t>> of_triangle;
  std::vector<std::array<Vec3, 2>> segments;
};

FeatureSegments collect_features(const prep::PreparedInput& in) {
  FeatureSegments fs;
  fs.of_triangle.resize(in.mesh.triangles.size());
  // Feature edges belong to the triangles that carry them.
  std::unordered_map<uint64_t, uint32_t> edge_index;
  for (const auto& fe : in.feature_edges) {
    uint32_t id = uint32_t(fs.segments.size());
    fs.segments.push_back({in.mesh.points[fe.a], in.mesh.points[fe.b]});
    uint32_t a = std::min(fe.a, fe.b), b = std::max(fe.a, fe.b);
    edge_index[(uint64_t(a) << 32) | b] = id;
  }
  for (uint32_t t = 0; t < in.mesh.triangles.size(); ++t) {
    const Tri& tri = in.mesh.triangles[t];
    for (int e = 0; e < 3; ++e) {
      uint32_t a = std::min(tri[e], tri[(e + 1) % 3]), b = std::max(tri[e], tri[(e + 1) % 3]);
      auto it = edge_index.find((uint64_t(a) << 32) | b);
      if (it != edge_index.end()) fs.of_triangle[t].push_back(it->second);
    }
  }
  for (const auto& s : in.intersections) {
    uint32_t id = uint32_t(fs.segments.size());
    fs.segments.push_back({s.a, s.b});
    fs.of_triangle[s.tri_a].push_back(id);
    fs.of_triangle[s.tri_b].push_back(id);
  }
  return fs;
}

}  // namespace

namespace {

// Triangles of the parts under contact prevention, bucketed by level-0 cell, to find the
// parts near a cell quickly.
class ContactBuckets {
 public:
  ContactBuckets(const std::vector<CellTris>& level0, const prep::PreparedInput& in, const SizeControls& sc) {
    for (const CellTris& ct : level0)
      for (uint32_t t : ct.tris)
        if (sc.part_in_contact_rule[size_t(in.mesh.part_of(t))]) cells_[key(ct.c)].push_back(t);
  }

  // True when the cell [lo, lo+h]^3, grown by h on every side, meets a triangle of a part
  // that must stay apart from one of `present` (the parts in the cell).
  bool conflict(const prep::PreparedInput& in, const SizeControls& sc, const std::vector<int32_t>& present,
                const Vec3& origin, double base, const Vec3& lo, double h) const {
    const Vec3 centre = lo + Vec3{0.5 * h, 0.5 * h, 0.5 * h};
    const Vec3 half{1.5 * h, 1.5 * h, 1.5 * h};
    Coord c0, c1;
    for (int k = 0; k < 3; ++k) {
      c0[k] = int(std::floor((centre[k] - half[k] - origin[k]) / base));
      c1[k] = int(std::floor((centre[k] + half[k] - origin[k]) / base));
    }
    const auto& pts = in.mesh.points;
    for (int z = c0.z(); z <= c1.z(); ++z)
      for (int y = c0.y(); y <= c1.y(); ++y)
        for (int x = c0.x(); x <= c1.x(); ++x) {
          auto it = cells_.find(key(Coord(x, y, z)));
          if (it == cells_.end()) continue;
          for (uint32_t t : it->second) {
            const int32_t q = in.mesh.part_of(t);
            bool against = false;
            for (int32_t p : present) against |= sc.conflicting(p, q);
            if (!against) continue;
            const Tri& tri = in.mesh.triangles[t];
            if (triangle_overlaps_box(pts[tri[0]], pts[tri[1]], pts[tri[2]], centre, half)) return true;
          }
        }
    return false;
  }

 private:
  static GridKey key(const Coord& c) { return {c.x(), c.y(), c.z()}; }
  std::unordered_map<GridKey, std::vector<uint32_t>, GridKeyHash> cells_;
};

}  // namespace

// Level 0's cells on the input in (x, y, z) order, each with its triangles in order; cell
// size h0, each cell grown by the margin. Every triangle goes to the blocks it meets (in
// parallel chunks of triangles, then a stable radix sort by block keeps each block's
// triangles in order); then each block, in parallel, tests its triangles against its own
// cells and sorts its hits by cell with a counting sort in cache; a sort of the cells by
// their numbers joins the blocks. (A global list of (cell, triangle) hits has tens of
// millions of entries on big assemblies: slow to sort, and twice its memory.)
std::vector<CellTris> level0_cells(const prep::PreparedInput& in, const Vec3& origin, double h0, const Coord& dims0,
                                   double margin_fraction) {
  const auto& pts = in.mesh.points;
  const auto& tris = in.mesh.triangles;
  const DenseNumbers blocks = block_numbers(dims0);
  const double half_cell = h0 * (0.5 + margin_fraction);
  auto cell_range = [&](uint32_t t, int lo[3], int hi[3]) {
    Box3 tb;
    for (uint32_t v : tris[t]) tb.add(pts[v]);
    for (int k = 0; k < 3; ++k) {
      lo[k] = int(std::floor((tb.lo[k] - origin[k]) / h0 - margin_fraction));
      hi[k] = int(std::floor((tb.hi[k] - origin[k]) / h0 + margin_fraction));
    }
  };
  struct Entry {
    uint64_t block;
    uint32_t triangle;
  };
  constexpr size_t kChunk = 4096;
  std::vector<std::vector<Entry>> chunk_entries((tris.size() + kChunk - 1) / kChunk);
  // A block is grown by the cells' margin and a little more, so that it keeps every triangle
  // that one of its cells' own tests would keep.
  const Vec3 block_origin = origin - Vec3{h0, h0, h0};
  const double block_half = h0 * (0.5 * kBlock + margin_fraction + 1e-6);
  tbb::parallel_for(size_t(0), chunk_entries.size(), [&](size_t chunk) {
    std::vector<Entry>& entries = chunk_entries[chunk];
    for (size_t t = chunk * kChunk; t < std::min(tris.size(), (chunk + 1) * kChunk); ++t) {
      int lo[3], hi[3], blo[3], bhi[3];
      cell_range(uint32_t(t), lo, hi);
      for (int k = 0; k < 3; ++k) blo[k] = (lo[k] + 1) / kBlock, bhi[k] = (hi[k] + 1) / kBlock;
      auto add = [&](int x, int y, int z) { entries.push_back({blocks.number(x, y, z), uint32_t(t)}); };
      if (blo[0] == bhi[0] && blo[1] == bhi[1] && blo[2] == bhi[2]) {
        add(blo[0], blo[1], blo[2]);
        continue;
      }
      const Vec3 &a = pts[tris[t][0]], &b = pts[tris[t][1]], &c = pts[tris[t][2]];
      for_cells_overlapping(a, b, c, block_origin, kBlock * h0, block_half, blo, bhi, add);
    }
  });
  const FillVector<Entry> entries = radix_sort_joined(
      chunk_entries, [](const Entry& e) { return e.block; }, bits_for(blocks.count));
  const std::vector<size_t> runs = run_starts(entries, [](const Entry& e) { return e.block; });

  constexpr int kCells = kBlock * kBlock * kBlock;
  struct Hit {
    uint16_t cell;  // in the block, x first, then y, then z
    uint32_t triangle;
  };
  struct Scratch {
    std::vector<Hit> hits;
    std::vector<uint32_t> count, cell_index;
  };
  tbb::enumerable_thread_specific<Scratch> scratch;
  std::vector<std::vector<CellTris>> block_cells(runs.size() - 1);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, block_cells.size(), 1), [&](const tbb::blocked_range<size_t>& r) {
    Scratch& s = scratch.local();
    for (size_t k = r.begin(); k != r.end(); ++k) {
      const auto b = blocks.point(entries[runs[k]].block);
      const int first[3] = {int(b[0]) * kBlock - 1, int(b[1]) * kBlock - 1, int(b[2]) * kBlock - 1};
      s.hits.clear();
      for (size_t i = runs[k]; i < runs[k + 1]; ++i) {
        const uint32_t t = entries[i].triangle;
        int lo[3], hi[3];
        cell_range(t, lo, hi);
        for (int j = 0; j < 3; ++j) lo[j] = std::max(lo[j], first[j]), hi[j] = std::min(hi[j], first[j] + kBlock - 1);
        const Vec3 &a = pts[tris[t][0]], &b = pts[tris[t][1]], &c = pts[tris[t][2]];
        for_cells_overlapping(a, b, c, origin, h0, half_cell, lo, hi, [&](int x, int y, int z) {
          s.hits.push_back({uint16_t(((x - first[0]) * kBlock + (y - first[1])) * kBlock + (z - first[2])), t});
        });
      }
      // Each cell's triangles in order, cells in (x, y, z) order: a counting sort by cell.
      s.count.assign(kCells, 0);
      for (const Hit& h : s.hits) ++s.count[h.cell];
      std::vector<CellTris>& cells = block_cells[k];
      for (int c = 0; c < kCells; ++c) {
        if (s.count[c] == 0) continue;
        cells.push_back(
            {Coord(first[0] + c / (kBlock * kBlock), first[1] + c / kBlock % kBlock, first[2] + c % kBlock), {}});
        cells.back().tris.reserve(s.count[c]);
      }
      s.cell_index.resize(kCells);
      for (int c = 0, at = 0; c < kCells; ++c)
        if (s.count[c] != 0) s.cell_index[c] = at++;
      for (const Hit& h : s.hits) cells[s.cell_index[h.cell]].tris.push_back(h.triangle);
    }
  });
  // The blocks' cells joined, in (x, y, z) order.
  size_t total = 0;
  for (const auto& cells : block_cells) total += cells.size();
  std::vector<std::pair<Coord, uint32_t>> order;
  order.reserve(total);
  std::vector<CellTris*> at;
  at.reserve(total);
  for (auto& cells : block_cells)
    for (CellTris& ct : cells) order.push_back({ct.c, uint32_t(at.size())}), at.push_back(&ct);
  tbb::parallel_sort(order.begin(), order.end(), [](const auto& u, const auto& v) { return u.first < v.first; });
  std::vector<CellTris> level_cells(total);
  tbb::parallel_for(size_t(0), total, [&](size_t i) { level_cells[i] = std::move(*at[order[i].second]); });
  return level_cells;
}

// near_thin[i] = 1 where cell i, or one of its 26 neighbours, holds a part thinner than `thin`.
void mark_near_thin(const prep::PreparedInput& in, const std::vector<CellTris>& cells, const Vec3& origin, double h,
                    double thin, std::vector<uint8_t>& near_thin) {
  std::vector<uint8_t> holds(cells.size(), 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, cells.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const Coord& c = cells[i].c;
      const Vec3 centre{origin[0] + (c.x() + 0.5) * h, origin[1] + (c.y() + 0.5) * h, origin[2] + (c.z() + 0.5) * h};
      holds[i] = thinnest_part(in, cells[i].tris, centre, thin) < thin;
    }
  });
  std::unordered_set<GridKey, GridKeyHash> at;
  for (size_t i = 0; i < cells.size(); ++i)
    if (holds[i]) at.insert(GridKey{cells[i].c.x(), cells[i].c.y(), cells[i].c.z()});
  if (at.empty()) return;
  for (size_t i = 0; i < cells.size(); ++i) {
    near_thin[i] = holds[i];
    const Coord& c = cells[i].c;
    for (int dx = -1; dx <= 1 && !near_thin[i]; ++dx)
      for (int dy = -1; dy <= 1 && !near_thin[i]; ++dy)
        for (int dz = -1; dz <= 1 && !near_thin[i]; ++dz)
          near_thin[i] = at.count(GridKey{c.x() + dx, c.y() + dy, c.z() + dz}) > 0;
  }
}

RefineResult build_refined_grid(const prep::PreparedInput& in, const RefineCriteria& params, double base,
                                const SizeControls& sc, ProgressSink* progress, int padding) {
  const auto& pts = in.mesh.points;
  const auto& tris = in.mesh.triangles;
  Box3 box;
  for (const Tri& t : tris)  // the surface's extent: stray points no triangle uses do not count
    for (uint32_t v : t) box.add(pts[v]);
  // Thin parts may ask for levels below everything else; the grid keeps only those used.
  const int thin_from = sc.criteria_levels, thin_to = sc.criteria_levels + std::max(params.thin_levels, 0);
  const int levels = std::max(sc.max_level, thin_to);
  Vec3 origin = box.lo - Vec3{padding * base, padding * base, padding * base};
  Coord dims0;
  for (int k = 0; k < 3; ++k) {
    double cells = std::ceil((box.hi[k] - box.lo[k]) / base) + 2 * padding;
    if (cells > 1 << 20)
      throw Error(ErrorKind::InvalidArgument, "base size too small for the model: over a million cells per axis");
    dims0[k] = int(cells);
  }
  RefineResult result;
  result.grid = std::make_unique<AdaptiveGrid>(origin, base, levels, dims0);
  AdaptiveGrid& g = *result.grid;

  // A cell counts as touched when the input meets it grown by a small margin, so that the
  // faces of free cells stay strictly off the input.
  const double margin_fraction = 1e-3;

  std::vector<CellTris> level_cells = level0_cells(in, origin, base, dims0, margin_fraction);
  std::unique_ptr<ContactBuckets> contact;
  if (sc.contact()) contact = std::make_unique<ContactBuckets>(level_cells, in, sc);

  const FeatureSegments features = collect_features(in);
  const double cos_spread = std::cos(params.normal_spread_deg * M_PI / 180.0);
  // Proximity: the 26 points of the cell's boundary on its 3x3x3 lattice, each within the bound
  // of one of the cell's triangles (the nearest input may be nearer: this refines more, never less).
  const double far2 =
      params.far_point_cells > 0 ? (params.far_point_cells * base) * (params.far_point_cells * base) : 0.0;
  auto has_far_point = [&](const std::vector<uint32_t>& cell_tris, const Vec3& lo, double h) {
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        for (int c = 0; c < 3; ++c) {
          if (a == 1 && b == 1 && c == 1) continue;
          const Vec3 q = lo + Vec3{0.5 * a * h, 0.5 * b * h, 0.5 * c * h};
          bool near = false;
          for (uint32_t t : cell_tris) {
            const Tri& tri = tris[t];
            if (norm2(closest_on_triangle(q, pts[tri[0]], pts[tri[1]], pts[tri[2]]) - q) <= far2) {
              near = true;
              break;
            }
          }
          if (!near) return true;
        }
    return false;
  };

  CellLists<> near_points(std::max({params.near_reach, params.far_point_reach, base}));
  for (uint32_t i = 0; i < params.refine_near.size(); ++i) near_points.add(params.refine_near[i], i);
  auto near_a_point = [&](const Vec3& lo, double h, double reach) {
    Box3 cell;
    cell.add(lo), cell.add(lo + Vec3{h, h, h});
    const double r2 = reach * reach;
    return near_points.for_lists(
        cell,
        [&](const std::vector<uint32_t>& list) {
          for (uint32_t i : list)
            if (cell.squared_distance(params.refine_near[i]) <= r2) return true;
          return false;
        },
        1);
  };

  int deepest = 0;
  for (int level = 0; level <= levels; ++level) {
    if (progress) {
      if (progress->cancelled()) throw Error(ErrorKind::Cancelled, "cancelled");
      progress->progress(
          "refine", double(level) / (levels + 1),
          "level " + std::to_string(level) + ": " + std::to_string(level_cells.size()) + " cells on the input");
    }
    result.touched_per_level.push_back(level_cells.size());
    const double h = g.cell_size(level);
    // Decide refinement per cell, in parallel; a refined cell's children are tested against
    // the parent's triangles only.
    std::vector<uint8_t> refine(level_cells.size(), 0), unresolved(level_cells.size(), 0),
        thin_split(level_cells.size(), 0);
    // The children's triangles are needed when they may be split in turn or checked for
    // contacts; else only which children the input meets, and a child is settled by its first
    // triangle (split cells can hold tens of millions of triangles in all: listing them for
    // each child is costly).
    const bool child_lists = level + 1 < sc.max_level || contact;
    // Cells at or past the criteria's depth may be split for a thin part; below it, their
    // children too, and those need their triangles listed.
    const bool thin_here = level >= thin_from - 1 && level < thin_to;
    // Thin parts: the cells holding one and their neighbours, so that no cell the part merely
    // grazes stays coarse beside them (the wrap would go around it, far from the part).
    std::vector<uint8_t> near_thin(thin_here ? level_cells.size() : 0, 0);
    if (thin_here) mark_near_thin(in, level_cells, origin, h, params.thin_fraction * h, near_thin);
    std::vector<std::array<std::vector<uint32_t>, 8>> children(
        level < levels && (child_lists || thin_here) ? level_cells.size() : 0);
    std::vector<uint8_t> children_met(level < levels ? level_cells.size() : 0, 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, level_cells.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i != r.end(); ++i) {
        const CellTris& ct = level_cells[i];
        Vec3 lo{origin[0] + ct.c.x() * h, origin[1] + ct.c.y() * h, origin[2] + ct.c.z() * h};
        auto in_contact = [&] {
          std::vector<int32_t> present;
          for (uint32_t t : ct.tris) {
            int32_t p = in.mesh.part_of(t);
            if (sc.part_in_contact_rule[size_t(p)] && std::find(present.begin(), present.end(), p) == present.end())
              present.push_back(p);
          }
          return !present.empty() && contact->conflict(in, sc, present, origin, base, lo, h);
        };
        if (level >= levels) {
          if (contact && in_contact()) unresolved[i] = 1;
          continue;
        }
        // The user's sizes first (control volumes, parts), then the criteria (down to
        // --levels), then contact prevention (down to its floor).
        bool split = level < region_level(sc, lo, h);
        for (size_t k = 0; !split && k < ct.tris.size(); ++k)
          split = level < sc.part_level[size_t(in.mesh.part_of(ct.tris[k]))];
        const bool criteria = level < sc.criteria_levels;
        if (!split && criteria) split = int(ct.tris.size()) > params.max_triangles;
        if (!split && criteria) {
          const Vec3& n0 = in.normals[ct.tris[0]];
          for (uint32_t t : ct.tris)
            if (dot(in.normals[t], n0) < cos_spread) {
              split = true;
              break;
            }
        }
        if (!split && criteria && params.at_features) {
          Vec3 glo = lo - Vec3{h * margin_fraction, h * margin_fraction, h * margin_fraction};
          Vec3 ghi = lo + Vec3{h * (1 + margin_fraction), h * (1 + margin_fraction), h * (1 + margin_fraction)};
          for (uint32_t t : ct.tris) {
            for (uint32_t s : features.of_triangle[t])
              if (segment_overlaps_box(features.segments[s][0], features.segments[s][1], glo, ghi)) {
                split = true;
                break;
              }
            if (split) break;
          }
        }
        if (!split && criteria && far2 > 0 &&
            (params.far_point_reach <= 0 || near_a_point(lo, h, params.far_point_reach)))
          split = has_far_point(ct.tris, lo, h);
        if (!split && criteria && !near_points.empty()) split = near_a_point(lo, h, params.near_reach);
        bool lists = child_lists;
        // A cell whose parent listed no triangles for it (no thin part near the parent) is not
        // split for one: without its triangles its children would all count as free, and the
        // volume outside would leak through them into a closed surface.
        if (thin_here && near_thin[i]) {
          if (!split && level >= thin_from && !ct.tris.empty()) split = true, thin_split[i] = 1;
          lists = lists || level + 1 < thin_to;
        }
        if (!split && contact && in_contact()) {
          if (level < sc.contact_level)
            split = true;
          else
            unresolved[i] = 1;
        }
        if (!split) continue;
        refine[i] = 1;
        const double hc = h * 0.5;
        const Vec3 centre = lo + Vec3{hc, hc, hc};
        uint8_t met = 0;
        for (uint32_t t : ct.tris) {
          const uint8_t in = octants_overlapped(pts[tris[t][0]], pts[tris[t][1]], pts[tris[t][2]], centre, 0.5 * hc,
                                                hc * (0.5 + margin_fraction), lists ? 0xff : uint8_t(~met));
          met |= in;
          if (lists) {
            for (int k = 0; k < 8; ++k)
              if (in & (1 << k)) children[i][k].push_back(t);
          } else if (met == 0xff) {
            break;
          }
        }
        children_met[i] = met;
      }
    });
    std::vector<CellTris> next;
    size_t refined = 0;
    for (size_t i = 0; i < level_cells.size(); ++i) {
      const Coord& c = level_cells[i].c;
      if (unresolved[i])
        result.unresolved_contacts.push_back(
            {origin[0] + (c.x() + 0.5) * h, origin[1] + (c.y() + 0.5) * h, origin[2] + (c.z() + 0.5) * h});
      if (!refine[i]) {
        g.set(level, c, kTouched);
        continue;
      }
      ++refined;
      result.thin_cells += thin_split[i];
      g.set(level, c, kRefined);
      for (int k = 0; k < 8; ++k) {
        Coord child(2 * c.x() + (k & 1), 2 * c.y() + ((k >> 1) & 1), 2 * c.z() + ((k >> 2) & 1));
        if (!(children_met[i] & (1 << k))) {
          g.set(level + 1, child, kFree);
        } else {
          next.push_back({child, children.empty() ? std::vector<uint32_t>() : std::move(children[i][k])});
        }
      }
    }
    result.refined_per_level.push_back(refined);
    std::sort(next.begin(), next.end(), [](const CellTris& u, const CellTris& v) { return u.c < v.c; });
    level_cells = std::move(next);
    if (level_cells.empty()) break;
    deepest = level + 1;
  }
  g.trim_levels(std::max(sc.max_level, deepest));
  if (progress) progress->progress("refine", 1.0, "done");
  return result;
}

}  // namespace vdbwrap::grid
