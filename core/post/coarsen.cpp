#include "post/coarsen.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <memory>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>
#include <unordered_map>

#include "check/intersections.h"
#include "common/cell_lists.h"
#include "common/compressed_lists.h"
#include "common/dense_numbers.h"
#include "common/edge_key.h"
#include "common/grid_key.h"
#include "common/radix_sort.h"
#include "common/triangle_buckets.h"
#include "common/vec.h"
#include "vdbwrap/errors.h"

namespace vdbwrap::post {
namespace {

double min_angle_cos_max(const Vec3& a, const Vec3& b, const Vec3& c) {
  // The largest cosine among the three angles (the smallest angle's cosine).
  auto cosine = [](const Vec3& o, const Vec3& p, const Vec3& q) {
    Vec3 u = p - o, w = q - o;
    double d = std::sqrt(norm2(u) * norm2(w));
    return d > 0 ? dot(u, w) / d : 1.0;
  };
  return std::max({cosine(a, b, c), cosine(b, c, a), cosine(c, a, b)});
}

class Coarsener {
 public:
  Coarsener(std::vector<Vec3>& p, std::vector<Tri>& t, const std::vector<uint8_t>& locked,
            const mesh::SurfaceIndex& input, const Vec3& origin, const CoarsenParams& params)
      : p_(p),
        t_(t),
        locked_(locked),
        input_(input),
        origin_(origin),
        prm_(params),
        buckets_(p, t, std::max(params.max_edge, 1e-300)),
        batch_made_(std::max(params.max_edge, 1e-300)) {
    alive_.assign(t.size(), 1);
    vertex_alive_.assign(p.size(), 1);
    vf_ = to_vectors(vertex_triangle_lists(p.size(), t));
    ring_claim_.assign(p.size(), 0);
    changed_in_.assign(p.size(), 0);
    made_in_.assign(t.size(), 0);
    witness_ = std::make_unique<std::atomic<uint32_t>[]>(p.size());
    for (size_t i = 0; i < p.size(); ++i) witness_[i].store(UINT32_MAX, std::memory_order_relaxed);
    cos_turn_ = std::cos(prm_.max_normal_turn_deg * M_PI / 180.0);
    cos_min_angle_ = std::cos(prm_.min_angle_deg * M_PI / 180.0);
    // No edge is ever longer than this: the longest one now, or the longest a collapse may make.
    const double longest2 = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, t_.size(), 16384), 0.0,
        [&](const tbb::blocked_range<size_t>& r, double m) {
          for (size_t f = r.begin(); f != r.end(); ++f)
            for (int i = 0; i < 3; ++i) m = std::max(m, norm2(p_[t_[f][i]] - p_[t_[f][(i + 1) % 3]]));
          return m;
        },
        [](double a, double b) { return std::max(a, b); });
    edge_bound_ = std::max(std::sqrt(longest2), prm_.max_edge);
    live_edges([](uint32_t, uint32_t) { return true; }, start_edges_);
  }

  // Passes over the edges, shortest first, until one pass changes little (at most four). A
  // later pass retries only edges whose checks read something that changed since they were
  // last refused: elsewhere they would be refused again. Most edges next to a collapse were
  // checked again after it in the same pass, and a second pass that retried all of them
  // made a fifth of coarsening's checks for one collapse in a hundred.
  //
  // A pass first runs in blocks (see in_blocks), then takes the edges the blocks left in
  // batches over the whole surface.
  size_t run(ProgressSink* progress) {
    size_t total = 0;
    std::vector<Entry> edges = std::move(start_edges_), left;
    for (uint32_t pass = 0; pass < 4; ++pass) {
      if (pass > 0) {
        tbb::parallel_sort(refusals_.begin(), refusals_.end());  // by edge, then in refusal order
        live_edges([&](uint32_t a, uint32_t b) { return needs_retry(a, b); }, edges);
        refusals_.clear();
      }
      pass_start_ = (phase_ + 1) << 32;
      left.clear();
      size_t n = in_blocks(edges, left, progress);
      edges.clear();
      for (const Entry& e : left) queue_.add(e);
      queue_.start();
      n += one_pass(progress);
      total += n;
      if (n < 16) break;
    }
    return total;
  }

  // One pass in batches: collapses whose closed 1-rings are disjoint do not read what the
  // others write, so a batch is checked in parallel against the frozen mesh and then applied
  // in queue order. The batches depend on the queue alone, so the result is the same for any
  // number of threads.
  size_t one_pass(ProgressSink* progress) {
    size_t collapses = 0;
    std::vector<Entry> batch, deferred;
    std::vector<uint32_t> ring;
    while (!queue_.empty()) {
      if (progress && progress->cancelled()) throw Error(ErrorKind::Cancelled, "cancelled");
      ++batch_id_;
      const uint64_t stamp = ++phase_ << 32;
      batch.clear();
      deferred.clear();
      while (!queue_.empty() && batch.size() < kBatch && deferred.size() < 4 * kBatch) {
        const Entry e = queue_.pop();
        // Points never move, so an edge whose ends are both alive is still there and as long.
        if (!vertex_alive_[e.a] || !vertex_alive_[e.b]) continue;
        // Compatible with the batch when neither end is in a claimed ring. (Then no claimed
        // end is in this ring either: a ring is its ends and their neighbours, and being
        // neighbours is mutual.)
        if (ring_claim_[e.a] == batch_id_ || ring_claim_[e.b] == batch_id_) {
          deferred.push_back(e);
          continue;
        }
        closed_ring(e.a, e.b, ring);
        for (uint32_t w : ring) ring_claim_[w] = batch_id_;
        batch.push_back(e);
      }
      // Plans keep their buffers from batch to batch (plan() clears them): allocations were a
      // tenth of coarsening.
      if (plans_.size() < batch.size()) plans_.resize(batch.size());
      std::vector<Plan>& plans = plans_;
      batch_made_.clear();
      // One plan per task at the finest: plans differ in cost by far (most refusals come
      // early), and coarser chunks left one thread waiting at the end of a batch.
      tbb::parallel_for(tbb::blocked_range<size_t>(0, batch.size(), 1), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) {
          const Entry& e = batch[i];
          plan_either_way(e, plans[i]);
        }
      });
      for (size_t i = 0; i < batch.size(); ++i) {
        const bool made = plans[i].ok && clear_of_batch(plans[i]);
        if (made) apply(plans[i], stamp, queue_, true), ++collapses;
        // A refusal by its own neighbourhood holds until that changes; one by other
        // triangles in the way (checked here or against the batch) may not.
        else
          refusals_.push_back({edge_key(batch[i].a, batch[i].b), stamp, !plans[i].ok && !plans[i].hit_other});
      }
      queue_.put_back(deferred);
    }
    return collapses;
  }

 private:
  // Large enough to keep two threads busy between the serial steps, small enough that the
  // order stays close to shortest first.
  static constexpr size_t kBatch = 512;
  struct Entry {
    double length2;
    uint32_t a, b;
    // Shortest first; ties in a fixed order, so that the order does not depend on the queue.
    bool operator<(const Entry& o) const {
      return length2 != o.length2 ? length2 < o.length2 : a != o.a ? a < o.a : b < o.b;
    }
  };
  struct Refusal {
    uint64_t edge;
    uint64_t stamp;     // the event (see phase_)
    bool by_own_rings;  // else by triangles in the way
    bool operator<(const Refusal& o) const { return edge != o.edge ? edge < o.edge : stamp < o.stamp; }
  };
  // Shortest edge first. Most entries are known when a pass starts (its edges) or are put back
  // unchanged by a batch that could not take them: those stay in sorted runs, and only the
  // edges a collapse shortened or lengthened go through a heap. A heap of every edge had cost
  // a third of coarsening: hundreds of thousands of entries, each pop a walk through memory.
  class EdgeQueue {
   public:
    void add(const Entry& e) { start_.push_back(e); }  // before start()
    void start() {
      std::sort(start_.begin(), start_.end());
      next_ = 0;
    }
    void push(const Entry& e) {
      heap_.push_back(e);
      std::push_heap(heap_.begin(), heap_.end(), later);
    }
    bool empty() const { return next_ == start_.size() && held_next_ == held_.size() && heap_.empty(); }
    Entry pop() {  // not empty
      const Entry* best = nullptr;
      int from = 0;
      if (next_ < start_.size()) best = &start_[next_], from = 0;
      if (held_next_ < held_.size() && (!best || held_[held_next_] < *best)) best = &held_[held_next_], from = 1;
      if (!heap_.empty() && (!best || heap_.front() < *best)) best = &heap_.front(), from = 2;
      const Entry e = *best;
      if (from == 0) {
        if (++next_ == start_.size()) start_.clear(), next_ = 0;
      } else if (from == 1) {
        ++held_next_;
      } else {
        std::pop_heap(heap_.begin(), heap_.end(), later);
        heap_.pop_back();
      }
      return e;
    }
    // Entries popped since the last put_back, in the order popped: every one of them comes
    // before every entry still held, so together they are one sorted run.
    void put_back(const std::vector<Entry>& popped) {
      std::vector<Entry> run(popped);
      run.insert(run.end(), held_.begin() + held_next_, held_.end());
      held_.swap(run);
      held_next_ = 0;
    }

   private:
    static bool later(const Entry& x, const Entry& y) { return y < x; }
    std::vector<Entry> start_, held_, heap_;
    size_t next_ = 0, held_next_ = 0;
  };
  // A checked collapse of u into v: the two faces on the edge go, the others of u are rewritten.
  struct Plan {
    bool ok = false;
    bool hit_other = false;  // refused because it would cross a triangle outside its 1-rings
    uint32_t u = 0, v = 0;
    std::vector<uint32_t> shared, moved;
    std::vector<Tri> fresh;
  };
  // Blocks of bucket cells coarsened at once (see in_blocks): kReach cells around a block are
  // its own while it runs, and the next block of its colour is kBlock cells away.
  static constexpr int64_t kBlock = 4, kReach = 2;
  static_assert(2 * kReach <= kBlock, "the reaches of blocks of one colour must not meet");
  struct Block {
    GridKey key;
    std::vector<Entry> edges;  // its edges when the pass starts, longest first
    std::vector<Entry> left;   // the edges it leaves to the batches
    std::vector<Refusal> refusals;
    size_t collapses = 0;
  };
  static int64_t floor_div(int64_t a, int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }
  GridKey cell_of(const Vec3& q) const { return grid_key(q, 1.0 / std::max(prm_.max_edge, 1e-300)); }
  GridKey block_of(uint32_t node) const {
    const GridKey c = cell_of(p_[node]);
    return {floor_div(c.x, kBlock), floor_div(c.y, kBlock), floor_div(c.z, kBlock)};
  }
  // Is box b within the reach of block k?
  bool in_reach(const Box3& b, const GridKey& k) const {
    const GridKey lo = cell_of(b.lo), hi = cell_of(b.hi);
    return lo.x >= k.x * kBlock - kReach && lo.y >= k.y * kBlock - kReach && lo.z >= k.z * kBlock - kReach &&
           hi.x < (k.x + 1) * kBlock + kReach && hi.y < (k.y + 1) * kBlock + kReach &&
           hi.z < (k.z + 1) * kBlock + kReach;
  }

  // One block's edges, shortest first, each collapse checked and applied before the next
  // edge is taken. The block's edges sit in a sorted run (popped from the back) beside a heap
  // of the edges its collapses make.
  void coarsen_block(Block& blk, uint64_t stamp) {
    Plan pl;
    std::vector<Entry> made;
    auto later = [](const Entry& x, const Entry& y) { return y < x; };
    uint64_t step = stamp;
    while (!blk.edges.empty() || !made.empty()) {
      Entry e;
      if (made.empty() || (!blk.edges.empty() && blk.edges.back() < made.front())) {
        e = blk.edges.back(), blk.edges.pop_back();
      } else {
        e = made.front();
        std::pop_heap(made.begin(), made.end(), later), made.pop_back();
      }
      // Only this block writes the nodes in its reach and their faces, so they are read
      // safely once both ends are in it (points never move).
      Box3 ring;
      ring.add(p_[e.a]), ring.add(p_[e.b]);
      if (!in_reach(ring, blk.key)) {
        blk.left.push_back(e);
        continue;
      }
      if (!vertex_alive_[e.a] || !vertex_alive_[e.b]) continue;
      // The 1-rings lie within an edge of the ends: when that is in the reach, so are they
      // (the same answer, without reading them here).
      const Vec3 grow{edge_bound_, edge_bound_, edge_bound_};
      Box3 around;
      around.add(ring.lo - grow), around.add(ring.hi + grow);
      if (!in_reach(around, blk.key)) {
        for (uint32_t x : {e.a, e.b})
          for (uint32_t f : vf_[x]) ring.add(box_of(t_[f]));
        if (!in_reach(ring, blk.key)) {
          blk.left.push_back(e);
          continue;
        }
      }
      ++step;
      plan_either_way(e, pl);
      if (pl.ok) {
        bool covered = true;
        for (const Tri& n : pl.fresh) covered = covered && buckets_.covers(box_of(n));
        if (!covered) {
          blk.left.push_back(e);
          continue;
        }
        apply(pl, step, made, false);
        ++blk.collapses;
      } else {
        blk.refusals.push_back({edge_key(e.a, e.b), step, !pl.hit_other});
      }
    }
  }

  // The surface cut into blocks of kBlock x kBlock x kBlock bucket cells: a collapse whose
  // 1-rings lie within kReach cells of its block reads and writes nothing outside that reach.
  // Blocks of one colour (the parities of their three coordinates) are two reaches apart, so
  // they coarsen at once, each on its own, shortest edge first, checking and applying one
  // collapse at a time; the eight colours take turns. An edge belongs to the block holding
  // its first end; an edge whose 1-rings leave the reach, or whose new triangles would need a
  // bucket cell that does not exist yet, is left to the batches. Each block's work depends on
  // its own edges alone, so the result is the same for any number of threads. (The batches'
  // forming and applying is serial, and their order over the whole surface reads cold memory:
  // blocks keep most edges out of them.)
  size_t in_blocks(const std::vector<Entry>& edges, std::vector<Entry>& left, ProgressSink* progress) {
    // Each edge's block, numbered densely (in the order of the blocks' keys); a stable radix
    // sort by it, then each block's run sorted longest first on its own, in parallel (a
    // comparison sort of all the edges is serial and was slower).
    struct Range {
      GridKey lo{INT64_MAX, INT64_MAX, INT64_MAX}, hi{INT64_MIN, INT64_MIN, INT64_MIN};
      void add(const GridKey& k) {
        lo = {std::min(lo.x, k.x), std::min(lo.y, k.y), std::min(lo.z, k.z)};
        hi = {std::max(hi.x, k.x), std::max(hi.y, k.y), std::max(hi.z, k.z)};
      }
    };
    const Range range = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, edges.size(), 4096), Range{},
        [&](const tbb::blocked_range<size_t>& r, Range acc) {
          for (size_t i = r.begin(); i != r.end(); ++i) acc.add(block_of(edges[i].a));
          return acc;
        },
        [](Range a, const Range& b) {
          if (b.lo.x <= b.hi.x) a.add(b.lo), a.add(b.hi);
          return a;
        });
    if (edges.empty()) return 0;
    const DenseNumbers numbers({range.lo.x, range.lo.y, range.lo.z},
                               {uint64_t(range.hi.x - range.lo.x + 1), uint64_t(range.hi.y - range.lo.y + 1),
                                uint64_t(range.hi.z - range.lo.z + 1)});
    struct Owned {
      uint64_t block;
      Entry e;
    };
    constexpr size_t kChunk = 65536;
    std::vector<std::vector<Owned>> parts((edges.size() + kChunk - 1) / kChunk);
    tbb::parallel_for(size_t(0), parts.size(), [&](size_t k) {
      const size_t end = std::min(edges.size(), (k + 1) * kChunk);
      parts[k].reserve(end - k * kChunk);
      for (size_t i = k * kChunk; i < end; ++i) {
        const GridKey b = block_of(edges[i].a);
        parts[k].push_back({numbers.number(b.x, b.y, b.z), edges[i]});
      }
    });
    FillVector<Owned> owned = radix_sort_joined(
        parts, [](const Owned& o) { return o.block; }, bits_for(numbers.count));
    const std::vector<size_t> starts = run_starts(owned, [](const Owned& o) { return o.block; });
    std::vector<Block> blocks(starts.size() - 1);
    for (size_t b = 0; b + 1 < starts.size(); ++b) {
      const auto k = numbers.point(owned[starts[b]].block);
      blocks[b].key = {k[0], k[1], k[2]};
    }
    tbb::parallel_for(size_t(0), blocks.size(), [&](size_t b) {
      std::vector<Entry>& run = blocks[b].edges;
      run.reserve(starts[b + 1] - starts[b]);
      for (size_t i = starts[b]; i < starts[b + 1]; ++i) run.push_back(owned[i].e);
      std::sort(run.begin(), run.end(), [](const Entry& x, const Entry& y) { return y < x; });  // longest first
    });
    FillVector<Owned>().swap(owned);  // freed before the blocks run
    size_t collapses = 0;
    for (int colour = 0; colour < 8; ++colour) {
      if (progress && progress->cancelled()) throw Error(ErrorKind::Cancelled, "cancelled");
      const uint64_t stamp = ++phase_ << 32;
      std::vector<Block*> turn;
      for (Block& b : blocks)
        if (((b.key.x & 1) | ((b.key.y & 1) << 1) | ((b.key.z & 1) << 2)) == colour) turn.push_back(&b);
      tbb::parallel_for(tbb::blocked_range<size_t>(0, turn.size(), 1), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) coarsen_block(*turn[i], stamp);
      });
    }
    for (Block& b : blocks) {
      collapses += b.collapses;
      left.insert(left.end(), b.left.begin(), b.left.end());
      refusals_.insert(refusals_.end(), b.refusals.begin(), b.refusals.end());
    }
    return collapses;
  }

  // Checks merging e.a into e.b, else e.b into e.a: pl.ok says whether one may go,
  // pl.hit_other whether a check was refused by triangles outside the 1-rings.
  void plan_either_way(const Entry& e, Plan& pl) const {
    pl.hit_other = false;
    bool ok = removable(e.a, e.b) && plan(e.a, e.b, pl);
    bool hit_other = pl.hit_other;
    if (!ok) ok = removable(e.b, e.a) && plan(e.b, e.a, pl), hit_other = hit_other || pl.hit_other;
    pl.ok = ok;
    pl.hit_other = hit_other;
  }

  // Edge a-b as a queue entry; false when it is already too long to collapse.
  bool entry_of(uint32_t a, uint32_t b, Entry& e) const {
    e = {norm2(p_[a] - p_[b]), a, b};
    return e.length2 <= prm_.max_edge * prm_.max_edge;
  }
  // The edges a < b of the live triangles that `keep` and that are short enough, in triangle
  // order (found in parallel chunks, joined in order): the edges of a pass about to start.
  template <typename Keep>
  void live_edges(Keep&& keep, std::vector<Entry>& out) const {
    constexpr size_t kChunk = 16384;
    std::vector<std::vector<Entry>> parts((t_.size() + kChunk - 1) / kChunk);
    tbb::parallel_for(size_t(0), parts.size(), [&](size_t k) {
      for (size_t f = k * kChunk; f < std::min(t_.size(), (k + 1) * kChunk); ++f) {
        if (!alive_[f]) continue;
        for (int i = 0; i < 3; ++i) {
          const uint32_t a = t_[f][i], b = t_[f][(i + 1) % 3];
          Entry e;
          if (a < b && keep(a, b) && entry_of(a, b, e)) parts[k].push_back(e);
        }
      }
    });
    size_t total = out.size();
    for (const auto& part : parts) total += part.size();
    out.reserve(total);
    for (const auto& part : parts) out.insert(out.end(), part.begin(), part.end());
  }
  // a, b and all their neighbours: everything a collapse of the edge reads or writes.
  void closed_ring(uint32_t a, uint32_t b, std::vector<uint32_t>& out) const {
    out.clear();
    for (uint32_t x : {a, b})
      for (uint32_t f : vf_[x])
        for (uint32_t w : t_[f]) out.push_back(w);
    out.push_back(a);
    out.push_back(b);
  }
  // A free node may always go. A node on a feature curve may go only into a neighbour on the
  // same straight run of the curve: it has exactly two feature neighbours, v and one more, and
  // the chain through it is nearly straight, so the chain keeps following the curve.
  bool removable(uint32_t u, uint32_t v) const {
    if (!locked_[u]) return true;
    if (!locked_[v]) return false;
    std::vector<uint32_t> chain;
    for (uint32_t w : neighbours(u))
      if (locked_[w]) chain.push_back(w);
    if (chain.size() != 2) return false;
    const uint32_t w = chain[0] == v ? chain[1] : chain[0];
    const Vec3 a = normalized(p_[v] - p_[u]), b = normalized(p_[w] - p_[u]);
    return dot(a, b) < -std::cos(prm_.max_chain_turn_deg * M_PI / 180.0);
  }

  // Is q within the deviation bound of the input? Nodes keep the input triangle that last said
  // yes near them (a witness), tried before the tree: probes come around a collapse's nodes,
  // while the batches scatter one thread's successive probes over the whole surface. Any
  // witness is a valid hint (the answer is the tree's), so plans of one batch may share them.
  template <size_t N>
  bool near_input(const Vec3& q, const std::array<uint32_t, N>& nodes) const {
    std::array<uint32_t, N> hints;
    for (size_t k = 0; k < N; ++k) hints[k] = witness_[nodes[k]].load(std::memory_order_relaxed);
    uint32_t found = UINT32_MAX;
    if (!input_.within(q - origin_, prm_.max_deviation, hints.data(), N, &found)) return false;
    if (found != UINT32_MAX) witness_[nodes[0]].store(found, std::memory_order_relaxed);
    return true;
  }

  // Checks merging u into v against the current mesh (read only: safe in parallel).
  bool plan(uint32_t u, uint32_t v, Plan& out) const {
    out.ok = false;
    out.u = out.v = 0;
    out.shared.clear(), out.moved.clear(), out.fresh.clear();
    // The two faces on edge u-v, and the link condition: u and v share exactly their two
    // opposite vertices as neighbours (else the collapse pinches the surface).
    for (uint32_t f : vf_[u]) {
      const Tri& tri = t_[f];
      (tri[0] == v || tri[1] == v || tri[2] == v ? out.shared : out.moved).push_back(f);
    }
    if (out.shared.size() != 2) return false;
    if (vf_[v].size() + out.moved.size() > 24) return false;  // a star vertex makes slivers

    for (uint32_t f : out.moved) {
      Tri n = t_[f];
      for (uint32_t& w : n)
        if (w == u) w = v;
      const Vec3 &a = p_[n[0]], &b = p_[n[1]], &c = p_[n[2]];
      const Vec3 area_new = area_vector(a, b, c);
      const double an = norm(area_new);
      if (an < prm_.min_area2) return false;
      const Tri& o = t_[f];
      const Vec3 area_old = area_vector(p_[o[0]], p_[o[1]], p_[o[2]]);
      if (dot(area_new, area_old) < cos_turn_ * an * norm(area_old)) return false;
      for (int k = 0; k < 3; ++k)
        if (norm2(p_[n[k]] - p_[n[(k + 1) % 3]]) > prm_.max_edge * prm_.max_edge) return false;
      const double cos_new = min_angle_cos_max(a, b, c);
      if (cos_new > cos_min_angle_ && cos_new > min_angle_cos_max(p_[o[0]], p_[o[1]], p_[o[2]])) return false;
      out.fresh.push_back(n);
    }
    // The link condition, after the shape tests that refuse most collapses (it sorts two
    // neighbour lists).
    Marks& scratch = marks_.local();  // this thread's buffers for the rest of the check
    neighbours(u, scratch.nu), neighbours(v, scratch.nv);
    size_t common = 0;
    for (size_t i = 0, j = 0; i < scratch.nu.size() && j < scratch.nv.size();) {
      if (scratch.nu[i] < scratch.nv[j])
        ++i;
      else if (scratch.nv[j] < scratch.nu[i])
        ++j;
      else
        ++common, ++i, ++j;
    }
    if (common != 2) return false;
    // Close to the input: the centroid of every new triangle and the midpoint of every new
    // edge, once each (the spokes from v; the edge across from v is an old one, unchanged).
    // Half the queries of probing each triangle's three midpoints, and these queries were
    // most of a successful check.
    std::vector<uint32_t>& spokes = scratch.spokes;
    spokes.clear();
    for (const Tri& n : out.fresh) {
      const Vec3 &a = p_[n[0]], &b = p_[n[1]], &c = p_[n[2]];
      if (!near_input((a + b + c) * (1.0 / 3.0), n)) return false;
      for (uint32_t w : n)
        if (w != v) spokes.push_back(w);
    }
    std::sort(spokes.begin(), spokes.end());
    spokes.erase(std::unique(spokes.begin(), spokes.end()), spokes.end());
    for (uint32_t w : spokes)
      if (!near_input((p_[v] + p_[w]) * 0.5, std::array<uint32_t, 2>{w, v})) return false;
    // No intersection among the new triangles, nor with the rest of the surface: one bucket
    // scan over the box of all new triangles (one scan each read mostly the same cells again).
    // A pair with a corner whose new fan lies unfolded needs no test (see
    // closed_fan_unfolded): most pairs here are a new triangle and a neighbour, or two new
    // ones, and those share a corner. (spokes and v are the new triangles' corners.)
    std::vector<uint32_t>& unfolded = scratch.unfolded;
    unfolded.clear();
    if (fan_unfolded_after(v, v, out, scratch.fan)) unfolded.push_back(v);
    for (uint32_t w : spokes)
      if (fan_unfolded_after(w, v, out, scratch.fan)) unfolded.push_back(w);
    auto settled = [&](const Tri& a, const Tri& b) {
      for (uint32_t x : a)
        if ((b[0] == x || b[1] == x || b[2] == x) && std::find(unfolded.begin(), unfolded.end(), x) != unfolded.end())
          return true;
      return false;
    };
    std::vector<Box3>& boxes = scratch.boxes;
    boxes.clear();
    Box3 all;
    for (size_t i = 0; i < out.fresh.size(); ++i) {
      if (check::triangle_is_degenerate(p_, out.fresh[i])) return false;
      for (size_t j = 0; j < i; ++j)
        if (!settled(out.fresh[i], out.fresh[j]) && check::triangle_pair_intersects(p_, out.fresh[i], out.fresh[j]))
          return false;
      boxes.push_back(box_of(out.fresh[i]));
      all.add(boxes.back().lo), all.add(boxes.back().hi);
    }
    bool hit = false;
    buckets_.for_each_in_box(all, scratch.seen, scratch.stamp, [&](uint32_t g) {
      if (hit || !alive_[g]) return;
      const Tri& other = t_[g];
      if (other[0] == u || other[1] == u || other[2] == u) return;  // replaced or removed
      const Box3& box = buckets_.box(g);
      for (size_t i = 0; i < out.fresh.size() && !hit; ++i)
        hit = boxes[i].overlaps(box) && !settled(out.fresh[i], other) &&
              check::triangle_pair_intersects(p_, out.fresh[i], other);
    });
    if (hit) {
      out.hit_other = true;
      return false;
    }
    out.u = u, out.v = v, out.ok = true;
    return true;
  }

  // Is the fan of x after the planned collapse into v (u's faces rewritten, the two on u-v gone)
  // closed and unfolded? `fan`: scratch for its triangles' corners after x.
  bool fan_unfolded_after(uint32_t x, uint32_t v, const Plan& pl, std::vector<std::array<uint32_t, 2>>& fan) const {
    fan.clear();
    auto add = [&](const Tri& tri) {
      const int k = tri[0] == x ? 0 : tri[1] == x ? 1 : 2;
      fan.push_back({tri[(k + 1) % 3], tri[(k + 2) % 3]});
    };
    for (uint32_t f : vf_[x]) {
      if (f == pl.shared[0] || f == pl.shared[1]) continue;
      const auto moved = std::find(pl.moved.begin(), pl.moved.end(), f);
      add(moved == pl.moved.end() ? t_[f] : pl.fresh[size_t(moved - pl.moved.begin())]);
    }
    if (x == v)  // u's rewritten faces were not v's yet
      for (const Tri& n : pl.fresh) add(n);
    return check::closed_fan_unfolded(p_, x, fan.data(), fan.size());
  }

  // The plans of one batch were checked against the mesh before the batch: each must also
  // clear the triangles the earlier plans of the batch made.
  bool clear_of_batch(const Plan& pl) {
    for (const Tri& n : pl.fresh) {
      const Box3 b = box_of(n);
      const bool hit = batch_made_.for_lists(b, [&](const std::vector<uint32_t>& list) {
        for (uint32_t g : list) {
          if (!alive_[g] || made_in_[g] != batch_id_) continue;
          const Tri& other = t_[g];
          if (other[0] == pl.u || other[1] == pl.u || other[2] == pl.u || !b.overlaps(box_of(other))) continue;
          if (check::triangle_pair_intersects(p_, n, other)) return true;
        }
        return false;
      });
      if (hit) return false;
    }
    return true;
  }

  // Applies a checked collapse; `stamp` marks the nodes whose faces change. The edges it
  // makes go to `queue` (the batches' EdgeQueue, or a block's heap). In a batch, the new
  // triangles are also listed for the batch's later plans, and bucket cells may be added.
  template <typename Queue>
  void apply(const Plan& pl, uint64_t stamp, Queue& queue, bool in_batch) {
    // The edges the collapse makes, v to u's neighbours that were not v's (all but the two
    // across the removed faces), join the queue. v's other edges keep their length: they
    // are checked again in the next pass when their neighbourhood changed after a refusal.
    // (Queueing all of v's edges again made most entries stale before they were popped, and
    // checked the same edges again after every collapse near them.)
    std::array<uint32_t, 2> across{UINT32_MAX, UINT32_MAX};
    for (size_t k = 0; k < 2; ++k)
      for (uint32_t w : t_[pl.shared[k]])
        if (w != pl.u && w != pl.v) across[k] = w;
    for (uint32_t f : pl.shared) {
      alive_[f] = 0;
      for (uint32_t w : t_[f]) {
        auto& list = vf_[w];
        list.erase(std::remove(list.begin(), list.end(), f), list.end());
      }
    }
    for (size_t i = 0; i < pl.moved.size(); ++i) {
      t_[pl.moved[i]] = pl.fresh[i];
      if (in_batch) {
        made_in_[pl.moved[i]] = batch_id_;
        batch_made_.for_cells(box_of(pl.fresh[i]), [&](const GridKey& k) { batch_made_.add(k, pl.moved[i]); });
      }
      vf_[pl.v].push_back(pl.moved[i]);
      buckets_.move(pl.moved[i], in_batch);
    }
    for (uint32_t f : vf_[pl.v])
      for (uint32_t w : t_[f]) changed_in_[w] = stamp;
    vf_[pl.u].clear();
    vertex_alive_[pl.u] = 0;
    std::vector<uint32_t>& made = marks_.local().made_ends;  // blocks apply at once
    made.clear();
    for (const Tri& n : pl.fresh)
      for (uint32_t w : n)
        if (w != pl.v && w != across[0] && w != across[1]) made.push_back(w);
    std::sort(made.begin(), made.end());
    made.erase(std::unique(made.begin(), made.end()), made.end());
    for (uint32_t w : made) {
      Entry e;
      if (entry_of(std::min(pl.v, w), std::max(pl.v, w), e)) push_entry(queue, e);
    }
  }
  static void push_entry(EdgeQueue& q, const Entry& e) { q.push(e); }
  static void push_entry(std::vector<Entry>& heap, const Entry& e) {
    heap.push_back(e);
    std::push_heap(heap.begin(), heap.end(), [](const Entry& x, const Entry& y) { return y < x; });
  }

  // Must edge a-b be checked again in the next pass? Only when a vertex whose faces its checks
  // read (a's and b's) changed in this pass, after the edge's last refusal when that was by
  // its own neighbourhood: a plan reads only those faces and their fixed points, besides the
  // input and the triangles in the way.
  bool needs_retry(uint32_t a, uint32_t b) const {
    const uint64_t changed = std::max(changed_in_[a], changed_in_[b]);
    if (changed < pass_start_) return false;
    const uint64_t key = edge_key(a, b);
    auto it = std::upper_bound(refusals_.begin(), refusals_.end(), Refusal{key, UINT64_MAX, false});
    if (it == refusals_.begin() || (it - 1)->edge != key) return true;  // not refused in this pass
    const Refusal& last = *(it - 1);
    return !last.by_own_rings || changed >= last.stamp;
  }

  Box3 box_of(const Tri& t) const {
    Box3 b;
    for (uint32_t w : t) b.add(p_[w]);
    return b;
  }

  std::vector<uint32_t> neighbours(uint32_t v) const {
    std::vector<uint32_t> out;
    neighbours(v, out);
    return out;
  }
  void neighbours(uint32_t v, std::vector<uint32_t>& out) const {
    out.clear();
    for (uint32_t f : vf_[v])
      for (uint32_t w : t_[f])
        if (w != v) out.push_back(w);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  }

 public:
  std::vector<uint32_t> compact() {
    std::vector<uint32_t> remap(p_.size(), UINT32_MAX);
    std::vector<Vec3> points;
    for (uint32_t i = 0; i < p_.size(); ++i)
      if (vertex_alive_[i] && !vf_[i].empty()) remap[i] = uint32_t(points.size()), points.push_back(p_[i]);
    std::vector<Tri> tris;
    for (uint32_t f = 0; f < t_.size(); ++f)
      if (alive_[f]) tris.push_back({remap[t_[f][0]], remap[t_[f][1]], remap[t_[f][2]]});
    p_.swap(points);
    t_.swap(tris);
    return remap;
  }

 private:
  std::vector<Vec3>& p_;
  std::vector<Tri>& t_;
  const std::vector<uint8_t>& locked_;
  const mesh::SurfaceIndex& input_;
  Vec3 origin_;
  CoarsenParams prm_;
  TriangleBuckets buckets_;
  std::vector<uint8_t> alive_, vertex_alive_;
  // The batch whose rings hold a vertex, the batch that rewrote a triangle.
  std::vector<uint32_t> ring_claim_, made_in_;
  uint32_t batch_id_ = 0;
  // Order of events: a phase (a batch, or the blocks of one colour) in the high half, a
  // block's own steps in the low half. Events of different blocks in one phase are never
  // compared: they concern nodes in different reaches.
  uint64_t phase_ = 0, pass_start_ = 0;  // the first event of the pass
  std::vector<uint64_t> changed_in_;     // per node: the last event that changed its faces
  std::vector<Refusal> refusals_;        // this pass's
  std::vector<Entry> start_edges_;       // the first pass's edges
  CellLists<> batch_made_;               // the batch's new triangles, in cells the longest edge wide
  struct Marks {                         // per thread: bucket marks and plan()'s scratch lists
    std::vector<uint32_t> seen;
    uint32_t stamp = 0;
    std::vector<uint32_t> nu, nv;
    std::vector<Box3> boxes;                   // of a plan's new triangles
    std::vector<uint32_t> spokes;              // the other ends of its new edges
    std::vector<uint32_t> unfolded;            // corners of its new triangles whose new fans lie unfolded
    std::vector<std::array<uint32_t, 2>> fan;  // fan_unfolded_after()'s
    std::vector<uint32_t> made_ends;           // apply()'s: the other ends of the edges a collapse makes
  };
  std::vector<Plan> plans_;
  std::unique_ptr<std::atomic<uint32_t>[]> witness_;  // per node: an input triangle near it, or UINT32_MAX
  mutable tbb::enumerable_thread_specific<Marks> marks_;
  std::vector<std::vector<uint32_t>> vf_;
  EdgeQueue queue_;
  double cos_turn_ = 0, cos_min_angle_ = 0;
  double edge_bound_ = 0;  // no edge is longer
};

}  // namespace

CoarsenStats coarsen(std::vector<Vec3>& points, std::vector<Tri>& triangles, const std::vector<uint8_t>& locked,
                     const mesh::SurfaceIndex& input, const Vec3& origin, const CoarsenParams& params,
                     ProgressSink* progress) {
  CoarsenStats stats;
  stats.triangles_before = triangles.size();
  if (progress)
    progress->progress("coarsen", 0.0,
                       "merging nodes on flat parts of " + std::to_string(triangles.size()) + " triangles");
  Coarsener c(points, triangles, locked, input, origin, params);
  stats.collapses = c.run(progress);
  stats.remap = c.compact();
  stats.triangles_after = triangles.size();
  if (progress)
    progress->progress(
        "coarsen", 1.0,
        std::to_string(stats.triangles_before) + " -> " + std::to_string(stats.triangles_after) + " triangles");
  return stats;
}

}  // namespace vdbwrap::post
