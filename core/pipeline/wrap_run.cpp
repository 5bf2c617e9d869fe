#include "pipeline/wrap_run.h"

#include <tbb/parallel_for.h>

#include <algorithm>

#include "common/stage_timer.h"
#include "common/vec.h"
#include "pipeline/stage_params.h"
#include "post/repair_wrap.h"

namespace vdbwrap::pipeline {

WrapRun::WrapRun(const Mesh& input_mesh, const WrapParams& wrap_params, ProgressSink* sink)
    : input(input_mesh),
      params(wrap_params),
      progress(sink),
      started(std::chrono::steady_clock::now()),
      report(result.report) {
  report.params = params;
}

const mesh::SurfaceIndex& WrapRun::index() {
  if (!index_ready_) {
    StageTimer timer("index", report.stages);
    index_ready_ = index_builder->get().get();
  }
  return *index_ready_;
}

void WrapRun::check_cancel() const {
  if (progress && progress->cancelled()) throw Error(ErrorKind::Cancelled, "cancelled");
}

double WrapRun::seconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
}

bool WrapRun::repair_if_intersecting() {
  const post::WrapRepairOutcome r =
      post::repair_intersections(surface, repair_bound(base), params.float_coordinates, progress);
  report.quality.repair_runs += r.ran ? 1 : 0;
  report.quality.intersecting_before_repair += r.intersecting_before;
  report.quality.intersecting_after_repair = r.intersecting_after;
  if (r.ran) report.quality.repair_summary = r.summary;
  return r.ran;
}

Mesh WrapRun::labelled_surface() const {
  // Every output triangle carries the part of the input triangle nearest its centroid. An
  // input of one part (an STL file) gives it to every triangle without asking.
  const std::vector<int32_t>& input_parts = prepared.mesh.triangle_part;
  const bool one_part =
      std::all_of(input_parts.begin(), input_parts.end(), [&](int32_t p) { return p == input_parts.front(); });
  Mesh out;
  out.points = surface.points;
  out.triangles = surface.triangles;
  out.part_names = prepared.mesh.part_names;
  if (one_part) {
    out.triangle_part.assign(out.triangles.size(), prepared.mesh.triangles.empty() ? 0 : prepared.mesh.part_of(0));
    return out;
  }
  out.triangle_part.resize(out.triangles.size());
  tbb::parallel_for(
      tbb::blocked_range<size_t>(0, out.triangles.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t t = r.begin(); t != r.end(); ++t) {
          const Tri& tri = out.triangles[t];
          const Vec3 c = (out.points[tri[0]] + out.points[tri[1]] + out.points[tri[2]]) * (1.0 / 3.0) - prepared.origin;
          out.triangle_part[t] = prepared.mesh.part_of(quality_ref.closest(c).triangle);
        }
      });
  return out;
}

}  // namespace vdbwrap::pipeline
