#include "grid/refine.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "common/dense_numbers.h"
#include "common/fill_vector.h"
#include "common/grid_key.h"
#include "common/radix_sort.h"
#include "common/vec.h"
#include "vdbwrap/errors.h"

namespace vdbwrap::grid {

namespace {

struct CellTris {
  Coord c;
  std::vector<uint32_t> tris;
};

// A level-0 cell the input meets and the triangle that meets it: in one word when the cell
// numbers fit in 32 bits (the 2.37M assembly at 0.25 % has 29.7M of them to sort: half the
// memory moved), else in two.
struct PackedHit {
  uint64_t word;
  PackedHit() = default;
  PackedHit(uint64_t cell, uint32_t triangle) : word(cell << 32 | triangle) {}
  uint64_t cell() const { return word >> 32; }
  uint32_t triangle() const { return uint32_t(word); }
};
struct WideHit {
  uint64_t cell_number;
  uint32_t triangle_number;
  WideHit() = default;
  WideHit(uint64_t cell, uint32_t triangle) : cell_number(cell), triangle_number(triangle) {}
  uint64_t cell() const { return cell_number; }
  uint32_t triangle() const { return triangle_number; }
};
// Level-0 cells, coordinates from -1 to the grid's size, numbered densely (x, y, z order).
DenseNumbers level0_numbers(const Coord& dims) {
  return DenseNumbers({-1, -1, -1}, {uint64_t(dims.x()) + 2, uint64_t(dims.y()) + 2, uint64_t(dims.z()) + 2});
}
Coord cell_of(const DenseNumbers& numbers, uint64_t n) {
  const auto p = numbers.point(n);
  return Coord(int(p[0]), int(p[1]), int(p[2]));
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
  template <typename Hits>
  ContactBuckets(const Hits& hits, const DenseNumbers& numbers, const prep::PreparedInput& in, const SizeControls& sc) {
    for (const auto& hit : hits)
      if (sc.part_in_contact_rule[size_t(in.mesh.part_of(hit.triangle()))])
        cells_[key(cell_of(numbers, hit.cell()))].push_back(hit.triangle());
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

// Level 0's cells on the input, each with its triangles in order; `contact` gets the
// contact prevention's buckets when there are rules. Cell size h0, each cell grown by the margin.
template <typename Hit>
std::vector<CellTris> level0_cells(const prep::PreparedInput& in, const SizeControls& sc, const Vec3& origin, double h0,
                                   const DenseNumbers& numbers, double margin_fraction, std::unique_ptr<ContactBuckets>& contact) {
  // Every triangle against the cells of its bounding box, in parallel, in chunks of
  // triangles joined in order; then a stable sort by cell puts each cell's triangles in
  // order. (Tens of millions of hits on a 2M-triangle assembly: a comparison sort of them
  // took 4 s.)
  const auto& pts = in.mesh.points;
  const auto& tris = in.mesh.triangles;
  constexpr size_t kChunk = 4096;
  std::vector<std::vector<Hit>> chunk_hits((tris.size() + kChunk - 1) / kChunk);
  tbb::parallel_for(size_t(0), chunk_hits.size(), [&](size_t chunk) {
    std::vector<Hit>& hits = chunk_hits[chunk];
    for (size_t t = chunk * kChunk; t < std::min(tris.size(), (chunk + 1) * kChunk); ++t) {
      const Vec3 &a = pts[tris[t][0]], &b = pts[tris[t][1]], &c = pts[tris[t][2]];
      Box3 tb;
      tb.add(a), tb.add(b), tb.add(c);
      int lo[3], hi[3];
      for (int k = 0; k < 3; ++k) {
        lo[k] = int(std::floor((tb.lo[k] - origin[k]) / h0 - margin_fraction));
        hi[k] = int(std::floor((tb.hi[k] - origin[k]) / h0 + margin_fraction));
      }
      for_cells_overlapping(a, b, c, origin, h0, h0 * (0.5 + margin_fraction), lo, hi,
                            [&](int x, int y, int z) { hits.emplace_back(numbers.number(x, y, z), uint32_t(t)); });
    }
  });
  FillVector<Hit> hits = radix_sort_joined(chunk_hits, [](const Hit& h) { return h.cell(); }, bits_for(numbers.count));
  if (sc.contact()) contact = std::make_unique<ContactBuckets>(hits, numbers, in, sc);
  std::vector<CellTris> level_cells;
  for (size_t i = 0; i < hits.size();) {
    CellTris ct{cell_of(numbers, hits[i].cell()), {}};
    size_t j = i;
    for (; j < hits.size() && hits[j].cell() == hits[i].cell(); ++j) ct.tris.push_back(hits[j].triangle());
    level_cells.push_back(std::move(ct));
    i = j;
  }
  return level_cells;
}

RefineResult build_refined_grid(const prep::PreparedInput& in, const WrapParams& params, double base,
                                const SizeControls& sc, ProgressSink* progress, int padding) {
  const auto& pts = in.mesh.points;
  const auto& tris = in.mesh.triangles;
  Box3 box;
  for (const auto& p : pts) box.add(p);
  const int levels = sc.max_level;
  Vec3 origin = box.lo - Vec3{padding * base, padding * base, padding * base};
  Coord dims0;
  for (int k = 0; k < 3; ++k) {
    double cells = std::ceil((box.hi[k] - box.lo[k]) / base) + 2 * padding;
    if (cells > 1 << 20) throw Error(ErrorKind::InvalidArgument, "base size too small for the model: over a million cells per axis");
    dims0[k] = int(cells);
  }
  RefineResult result;
  result.grid = std::make_unique<AdaptiveGrid>(origin, base, levels, dims0);
  AdaptiveGrid& g = *result.grid;

  // A cell counts as touched when the input meets it grown by a small margin, so that the
  // faces of free cells stay strictly off the input.
  const double margin_fraction = 1e-3;

  const DenseNumbers numbers = level0_numbers(dims0);
  std::unique_ptr<ContactBuckets> contact;
  std::vector<CellTris> level_cells =
      bits_for(numbers.count) <= 32 ? level0_cells<PackedHit>(in, sc, origin, base, numbers, margin_fraction, contact)
                                    : level0_cells<WideHit>(in, sc, origin, base, numbers, margin_fraction, contact);

  const FeatureSegments features = collect_features(in);
  const double cos_spread = std::cos(params.refine_normal_spread_deg * M_PI / 180.0);

  for (int level = 0; level <= levels; ++level) {
    if (progress) {
      if (progress->cancelled()) throw Error(ErrorKind::Cancelled, "cancelled");
      progress->progress("refine", double(level) / (levels + 1),
                         "level " + std::to_string(level) + ": " + std::to_string(level_cells.size()) + " cells on the input");
    }
    result.touched_per_level.push_back(level_cells.size());
    const double h = g.cell_size(level);
    // Decide refinement per cell, in parallel; a refined cell's children are tested against
    // the parent's triangles only.
    std::vector<uint8_t> refine(level_cells.size(), 0), unresolved(level_cells.size(), 0);
    // The children's triangles are needed when they may be split in turn or checked for
    // contacts; else only which children the input meets, and a child is settled by its first
    // triangle (the 2.37M assembly at 0.25 % has 23M triangles in split cells: listing them
    // for each child was 2.6 s).
    const bool child_lists = level + 1 < levels || contact;
    std::vector<std::array<std::vector<uint32_t>, 8>> children(level < levels && child_lists ? level_cells.size() : 0);
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
        for (size_t k = 0; !split && k < ct.tris.size(); ++k) split = level < sc.part_level[size_t(in.mesh.part_of(ct.tris[k]))];
        const bool criteria = level < sc.criteria_levels;
        if (!split && criteria) split = int(ct.tris.size()) > params.refine_max_triangles;
        if (!split && criteria) {
          const Vec3& n0 = in.normals[ct.tris[0]];
          for (uint32_t t : ct.tris)
            if (dot(in.normals[t], n0) < cos_spread) {
              split = true;
              break;
            }
        }
        if (!split && criteria && params.refine_at_features) {
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
                                                hc * (0.5 + margin_fraction), child_lists ? 0xff : uint8_t(~met));
          met |= in;
          if (child_lists) {
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
      g.set(level, c, kRefined);
      for (int k = 0; k < 8; ++k) {
        Coord child(2 * c.x() + (k & 1), 2 * c.y() + ((k >> 1) & 1), 2 * c.z() + ((k >> 2) & 1));
        if (!(children_met[i] & (1 << k))) {
          g.set(level + 1, child, kFree);
        } else {
          next.push_back({child, child_lists ? std::move(children[i][k]) : std::vector<uint32_t>()});
        }
      }
    }
    result.refined_per_level.push_back(refined);
    std::sort(next.begin(), next.end(), [](const CellTris& u, const CellTris& v) { return u.c < v.c; });
    level_cells = std::move(next);
    if (level_cells.empty()) break;
  }
  if (progress) progress->progress("refine", 1.0, "done");
  return result;
}

}  // namespace vdbwrap::grid
