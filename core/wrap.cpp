// The wrap: the parameters checked, then the pipeline's stages (core/pipeline/) in order.
#include <tbb/task_arena.h>

#include "pipeline/stages.h"
#include "prep/check_input.h"
#include "vdbwrap/wrap.h"

namespace vdbwrap {
namespace {

// The pipeline of docs/pipeline.md: a call per stage, on one run that carries what each
// stage hands to the next.
WrapResult run_pipeline(const Mesh& input, const WrapParams& params, ProgressSink* progress) {
  pipeline::WrapRun run(input, params, progress);
  pipeline::diagnose_input(run);
  pipeline::prepare_input(run);
  pipeline::build_volume(run);
  pipeline::project_lattice(run);
  pipeline::refine_where_far(run);
  pipeline::fit_surface(run);
  pipeline::post_process(run);
  pipeline::validate_surface(run);
  pipeline::measure_distances(run);
  return std::move(run.result);
}

}  // namespace

WrapResult wrap(const Mesh& input, const WrapParams& params, ProgressSink* progress) {
  validate(params);
  prep::check_input_mesh(input);
  // A task arena per job: its thread limit holds for this job only, so a server running
  // several jobs at once does not let one job's limit throttle the others.
  if (params.threads <= 0) return run_pipeline(input, params, progress);
  tbb::task_arena arena(params.threads);
  return arena.execute([&] { return run_pipeline(input, params, progress); });
}

}  // namespace vdbwrap
