// One wrap in progress: what each stage of the pipeline (stages.h) hands to the next, and the
// few services several stages share (the nearest-point index built in the background,
// cancellation, the intersection repair, the part labels).
#pragma once
#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "common/exact_weld.h"
#include "common/in_background.h"
#include "extract/extract_surface.h"
#include "fit/features.h"
#include "fit/fit_surface.h"
#include "mesh/surface_index.h"
#include "grid/refine.h"
#include "grid/size_controls.h"
#include "post/nearest_memo.h"
#include "post/quality.h"
#include "post/remesh.h"
#include "prep/prepare.h"
#include "vdbwrap/wrap.h"

namespace vdbwrap::pipeline {

struct WrapRun {
  WrapRun(const Mesh& input, const WrapParams& params, ProgressSink* progress);
  WrapRun(const WrapRun&) = delete;
  WrapRun& operator=(const WrapRun&) = delete;

  const Mesh& input;
  const WrapParams& params;
  ProgressSink* progress;
  const std::chrono::steady_clock::time_point started;
  WrapResult result;
  WrapReport& report;  // result.report

  // Diagnosis -> prepare: the input's exact weld, made once for both.
  ExactWeld input_weld;
  // Prepare.
  prep::PreparedInput prepared;
  double base = 0;  // the base size in model units
  // The volume: size controls, the refined grid, the chosen volume's label, its surface.
  grid::SizeControls controls;
  grid::RefineResult refined;
  int32_t label = 0;
  std::vector<grid::Coord> anchors;
  extract::LatticeSurface lattice;
  // Points (local frame) around which the grid is refined to the finest level: where a first
  // fit was far from the input (see refine_where_far).
  std::vector<Vec3> refine_near;
  // Started in the background when their inputs exist, waited for when first needed.
  std::unique_ptr<InBackground<std::unique_ptr<mesh::SurfaceIndex>>> index_builder;
  std::unique_ptr<InBackground<std::vector<fit::FeatureCurve>>> curves_builder;
  // The fit (stage 3), then the surface stage 4 works on.
  fit::FittedSurface fitted;
  post::PostSurface surface;
  post::QualityReference quality_ref;
  post::NormalDeviationMemo deviation_memo;  // the final analysis re-measures only what changed
  std::unique_ptr<post::NearestMemo> nearest_memo;

  // The nearest-point index of the prepared input; waits for its build the first time (timed
  // as the stage "index": what is left of the build when first needed).
  const mesh::SurfaceIndex& index();
  // Throws Error(Cancelled) when the caller asked to stop.
  void check_cancel() const;
  // Seconds since the run started.
  double seconds() const;
  // The intersection repair on `surface`, counted in the report; true when it ran.
  bool repair_if_intersecting();
  // `surface` as the output mesh, each triangle with the part of the input nearest to it.
  Mesh labelled_surface() const;

 private:
  const mesh::SurfaceIndex* index_ready_ = nullptr;
};

}  // namespace vdbwrap::pipeline
