// The stages of a wrap, in the order of docs/pipeline.md; run_pipeline (core/wrap.cpp) calls
// them one after the other on one WrapRun. Each reads what the stages before it left in the
// run and fills its own part of it and of the report.
#pragma once
#include "pipeline/wrap_run.h"

namespace vdbwrap::pipeline {

// Stage 0: the input's defects, for the report (its intersections come from prepare).
void diagnose_input(WrapRun& run);
// Stage 1: weld, clean, find features and intersection lines; the base size.
void prepare_input(WrapRun& run);
// Stage 2: size controls, the refined grid, the flood fill (the chosen volume, gap closure,
// leaks), and the volume's manifold lattice surface.
void build_volume(WrapRun& run);
// Stage 3: the lattice surface projected onto the input, with feature snapping.
void project_lattice(WrapRun& run);
// Where that left the wrap over a base cell from the input (nodes held back at corners of
// coarse cells, faces bridging a concave crease), stage 2 again with the cells around the far
// parts refined to the finest level, and the projection again (refine_where_far; the outside
// volume only).
void refine_where_far(WrapRun& run);
// Stage 3, end: nodes inserted on missed feature curves, coarsening of flat parts.
void fit_surface(WrapRun& run);
// Stage 4: quality analysis, remeshing of bad regions, intersection repair where anything
// still intersects, sliver removal; then the part labels of the output.
void post_process(WrapRun& run);
// The final checks: closed, manifold, outward, free of self-intersections (one more
// intersection repair when needed), the final quality analysis and the defect flags.
// Throws WrapFailure with the report when the surface is not valid.
void validate_surface(WrapRun& run);
// Sampled distances between the wrap and the input, for the report.
void measure_distances(WrapRun& run);

}  // namespace vdbwrap::pipeline
