// Fuzzes the whole pipeline (vdbwrap::wrap) on small dirty meshes built from the bytes.
// vdbwrap::Error is a fine outcome (wrap.h documents it); any other exception, a signal or a
// sanitizer report is a finding, and so is a returned surface that is not a valid closed one.
//
// Input layout (missing bytes read as 0):
//   0  flags: bits 0-1 volume (outside, inside, seed points, outside), 2 gap closure,
//      3 contact prevention, 4 group against group (three parts), 5 no feature snapping, 6 no remeshing, 7 far from
//      origin
//   1  levels (b % 3), thin-part levels (2 - b / 3 % 3)    2  base size, % of the diagonal (finest cell >= 1.5 %)
//   3  scale 10^(b % 19 - 9)     4  gap closure 0.5..20 %     5  translation 10^(b % 8) x scale
//   6  seed count (1 + b % 2), then 3 bytes per seed point
//   then operations, one byte each plus their operands, until the bytes or 48 triangles run out:
//   op % 10: 0 triangle, 1 duplicate, 2 flipped duplicate, 3 coincident corners, 4 collinear,
//   5 near-degenerate, 6 fan on an existing edge (non-manifold), 7 box, 8 coplanar overlap,
//   9 tetrahedron; op >> 6 is the part (a, b, c).
// Points lie on a quarter grid of 8 x 8 x 8 units so that coincidences are frequent.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

#include "fuzz_check.h"
#include "vdbwrap/wrap.h"

using namespace vdbwrap;

namespace {

class Bytes {
 public:
  Bytes(const uint8_t* p, size_t n) : p_(p), n_(n) {}
  uint8_t next() { return n_ ? (--n_, *p_++) : 0; }
  bool empty() const { return n_ == 0; }

 private:
  const uint8_t* p_;
  size_t n_;
};

constexpr size_t kMaxTriangles = 48;

class MeshBuilder {
 public:
  explicit MeshBuilder(Bytes& in) : in_(in) {}

  Vec3 grid_point() {
    Vec3 p;
    for (double& c : p) {
      const uint8_t b = in_.next();
      c = double(b & 7) + 0.25 * double((b >> 3) & 3);
    }
    return p;
  }
  uint32_t add(const Vec3& p) {
    mesh.points.push_back(p);
    return uint32_t(mesh.points.size() - 1);
  }
  void tri(uint32_t a, uint32_t b, uint32_t c) {
    if (mesh.triangles.size() >= kMaxTriangles) return;
    mesh.triangles.push_back({a, b, c});
    parts_.push_back(part_);
  }
  void tri(const Vec3& a, const Vec3& b, const Vec3& c) { tri(add(a), add(b), add(c)); }
  const Tri& existing() { return mesh.triangles[in_.next() % mesh.triangles.size()]; }

  void operation() {
    const uint8_t op = in_.next();
    part_ = int32_t(std::min(op >> 6, 2));
    const bool have = !mesh.triangles.empty();
    switch (op % 10) {
      case 0: {
        const Vec3 a = grid_point(), b = grid_point(), c = grid_point();
        tri(a, b, c);
        break;
      }
      case 1:  // the same vertices again, or copies of them
        if (have) {
          const Tri t = existing();
          if (op & 16)
            tri(add(mesh.points[t[0]]), add(mesh.points[t[1]]), add(mesh.points[t[2]]));
          else
            tri(t[0], t[1], t[2]);
        }
        break;
      case 2:
        if (have) {
          const Tri t = existing();
          tri(t[0], t[2], t[1]);
        }
        break;
      case 3: {
        const uint32_t a = add(grid_point()), b = add(grid_point());
        tri(a, a, b);
        break;
      }
      case 4: {
        const Vec3 a = grid_point(), b = grid_point();
        const double s = (op & 16) ? 2.0 : 0.5;
        tri(a, b, Vec3{a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1]), a[2] + s * (b[2] - a[2])});
        break;
      }
      case 5: {  // the third corner a tiny distance off the edge's midpoint
        const Vec3 a = grid_point(), b = grid_point();
        const uint8_t e = in_.next();
        const double eps = std::pow(10.0, -double(3 + e % 12));
        Vec3 c{0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])};
        c[(e >> 4) % 3] += (e & 128) ? -eps : eps;
        tri(a, b, c);
        break;
      }
      case 6:  // another triangle on an existing edge: a fan of several is non-manifold
        if (have) {
          const Tri t = existing();
          const int k = in_.next() % 3;
          tri(t[k], t[(k + 1) % 3], add(grid_point()));
        }
        break;
      case 7: {  // a closed box, outward or inside out
        const Vec3 o = grid_point();
        const uint8_t s = in_.next();
        const double size[3] = {1.0 + (s & 3), 1.0 + ((s >> 2) & 3), 1.0 + ((s >> 4) & 3)};
        uint32_t v[8];
        for (int i = 0; i < 8; ++i)
          v[i] = add({o[0] + ((i & 1) ? size[0] : 0), o[1] + ((i & 2) ? size[1] : 0), o[2] + ((i & 4) ? size[2] : 0)});
        static const int kFaces[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                                          {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
        for (const auto& f : kFaces) {
          if (s & 64)
            tri(v[f[0]], v[f[2]], v[f[1]]);
          else
            tri(v[f[0]], v[f[1]], v[f[2]]);
        }
        break;
      }
      case 8:  // a copy slid along one of its own edges: overlapping and coplanar
        if (have) {
          const Tri t = existing();
          const uint8_t m = in_.next();
          const Vec3 &a = mesh.points[t[m % 3]], &b = mesh.points[t[(m + 1) % 3]];
          const double s = 0.125 * double(1 + ((m >> 2) & 7));
          const Vec3 d{s * (b[0] - a[0]), s * (b[1] - a[1]), s * (b[2] - a[2])};
          Vec3 q[3];
          for (int k = 0; k < 3; ++k) {
            const Vec3& p = mesh.points[t[k]];
            q[k] = {p[0] + d[0], p[1] + d[1], p[2] + d[2]};
          }
          tri(q[0], q[1], q[2]);
        }
        break;
      case 9: {
        const uint32_t a = add(grid_point()), b = add(grid_point()), c = add(grid_point()), d = add(grid_point());
        tri(a, b, c), tri(a, d, b), tri(b, d, c), tri(c, d, a);
        break;
      }
    }
  }

  // Parts in order of first use, as the readers make them; none for a single part.
  void finish_parts() {
    static const char* const kNames[3] = {"a", "b", "c"};
    int32_t index[3] = {-1, -1, -1};
    for (int32_t p : parts_)
      if (index[p] < 0) {
        index[p] = int32_t(mesh.part_names.size());
        mesh.part_names.push_back(kNames[p]);
      }
    if (mesh.part_names.size() <= 1) {
      mesh.part_names.clear();
      return;
    }
    for (int32_t p : parts_) mesh.triangle_part.push_back(index[p]);
  }

  Mesh mesh;

 private:
  Bytes& in_;
  int32_t part_ = 0;
  std::vector<int32_t> parts_;
};

bool finite(const Vec3& p) { return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]); }

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  Bytes in(data, size);
  const uint8_t flags = in.next();
  WrapParams params;
  params.threads = 1;  // one core per fuzzer; results do not depend on it
  const uint8_t depth = in.next();
  params.levels = depth % 3;
  params.thin_part_levels = 2 - depth / 3 % 3;  // the default first (the seeds' bytes are small)
  // Small grids keep one run well under a second: finest cell at least 1.5 % of the diagonal.
  const double min_base = 1.5 * double(1 << params.levels);
  params.base_size = Length{std::max(min_base, 3.0 + double(in.next() % 23)), true};
  const double scale = std::pow(10.0, double(in.next() % 19) - 9);
  const double gap = 0.5 + 19.5 * double(in.next()) / 255.0;
  const double offset = (flags & 128) ? std::pow(10.0, double(in.next() % 8)) * scale : 0.0;
  auto place = [&](const Vec3& g) { return Vec3{g[0] * scale + offset, g[1] * scale + offset, g[2] * scale + offset}; };

  switch (flags & 3) {
    case 1:
      params.volume = VolumeChoice::Inside;
      break;
    case 2: {
      params.volume = VolumeChoice::SeedPoints;
      const int seeds = 1 + in.next() % 2;
      for (int s = 0; s < seeds; ++s) {
        Vec3 g;
        for (double& c : g) c = -1.0 + 10.0 * double(in.next()) / 255.0;  // around and inside the grid
        params.seed_points.push_back(place(g));
      }
      break;
    }
    default:
      break;
  }
  if (flags & 4) params.gap_closure = Length{gap, true};
  // The report's distance sampling is fixed at 1000 samples per diagonal: seconds per input here.
  params.compute_distances = false;
  params.snap_features = (flags & 32) == 0;
  params.remesh = (flags & 64) == 0;

  MeshBuilder builder(in);
  while (!in.empty() && builder.mesh.triangles.size() < kMaxTriangles) builder.operation();
  if (builder.mesh.triangles.empty()) return 0;
  builder.finish_parts();
  Mesh& mesh = builder.mesh;
  for (Vec3& p : mesh.points) p = place(p);
  if ((flags & 8) && mesh.part_names.size() >= 2) {
    ContactRule rule;
    if (mesh.part_names.size() == 3 && (flags & 16))
      rule.groups = {{mesh.part_names[0]}, {mesh.part_names[1], mesh.part_names[2]}};
    else
      rule.groups = {mesh.part_names};
    params.contact_prevention.push_back(rule);
    // Its default floor (finest cell / 8) makes grids 8x finer: seconds per input.
    params.contact_floor = Length{params.base_size.value / double(1 << params.levels) / 2, true};
  }

  // VDBWRAP_FUZZ_VERBOSE=1: what an input does (for triage), on stderr.
  static const bool verbose = std::getenv("VDBWRAP_FUZZ_VERBOSE") != nullptr;
  if (verbose)
    std::fprintf(stderr,
                 "fuzz_wrap: %zu triangles, %zu points, %zu parts, base %g%%, levels %d+%d, volume %d, gap %s\n",
                 mesh.triangles.size(), mesh.points.size(), mesh.part_names.size(), params.base_size.value,
                 params.levels, params.thin_part_levels, int(params.volume),
                 params.gap_closure ? params.gap_closure->to_string().c_str() : "off");
  WrapResult result;
  try {
    result = wrap(mesh, params);
  } catch (const Error& e) {
    if (verbose) std::fprintf(stderr, "fuzz_wrap: error %d: %s\n", int(e.kind()), e.what());
    return 0;  // refused or failed, as documented: not a crash
  }
  if (verbose)
    for (const StageStats& st : result.report.stages)
      std::fprintf(stderr, "fuzz_wrap: %-20s %.3f s\n", st.name.c_str(), st.seconds);
  // wrap() returns only surfaces that passed its validation (wrap.h, README): check it did,
  // and check the surface again independently.
  const Mesh& s = result.surface;
  FUZZ_CHECK(!s.triangles.empty(), "empty surface returned");
  for (const Vec3& p : s.points) FUZZ_CHECK(finite(p), "non-finite output point");
  for (const Tri& t : s.triangles)
    for (uint32_t v : t) FUZZ_CHECK(v < s.points.size(), "output index %u of %zu points", v, s.points.size());
  FUZZ_CHECK(result.report.output.valid_closed_surface(), "returned a surface its report calls invalid");
  const MeshDiagnostics d = diagnose(s);
  FUZZ_CHECK(d.valid_closed_surface(),
             "returned surface is invalid: closed %d manifold %d oriented %d outward %d intersecting %d degenerate %zu",
             d.closed, d.manifold, d.oriented, d.outward, d.self_intersecting, d.degenerate_triangles);
  return 0;
}
