// The one public API of the vdbwrap core: wrap a dirty triangle mesh into a closed,
// 2-manifold, outward-oriented, self-intersection-free surface, and diagnose meshes.
// The CLI and the gRPC server are thin layers over these functions. The parts by concern:
// params.h (what to do), progress.h (progress, cancellation), report.h (what was done),
// check.h (measures of any mesh).
#pragma once
#include <memory>
#include <string>

#include "vdbwrap/check.h"
#include "vdbwrap/errors.h"
#include "vdbwrap/mesh.h"
#include "vdbwrap/params.h"
#include "vdbwrap/progress.h"
#include "vdbwrap/report.h"

namespace vdbwrap {

struct WrapResult {
  Mesh surface;
  WrapReport report;
  // Per surface triangle: DefectFlag bits (vdbwrap/deviation.h) of the final quality analysis,
  // and held-back nodes at its corners.
  std::vector<uint8_t> triangle_flags;
  // The input's feature curves the surface was snapped to (sharp, boundary and non-manifold
  // edges, intersection lines), as polylines in model coordinates; a closed curve ends on its
  // first point. Empty when params.snap_features is false.
  std::vector<std::vector<Vec3>> feature_curves;
};

// A wrap that stopped with a report worth keeping (a leak, a surface that failed
// validation): the report so far comes with the error.
class WrapFailure : public Error {
 public:
  WrapFailure(const std::string& message, WrapReport report)
      : Error(ErrorKind::WrapFailed, message), report_(std::make_shared<WrapReport>(std::move(report))) {}
  const WrapReport& report() const { return *report_; }

 private:
  std::shared_ptr<WrapReport> report_;
};

// Runs the whole pipeline. Throws Error: InvalidArgument (parameters), InvalidInput
// (mesh unusable, e.g. no triangles left), WrapFailed (no valid surface; a WrapFailure
// with the report so far when there is one, e.g. for a leak), Cancelled.
WrapResult wrap(const Mesh& input, const WrapParams& params, ProgressSink* progress = nullptr);

}  // namespace vdbwrap
