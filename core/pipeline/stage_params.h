// The one place where the user's WrapParams become the stages' own parameter structs: a stage
// sees only what it uses, with its defaults beside it in its header.
#pragma once
#include "grid/refine.h"
#include "grid/size_controls.h"
#include "prep/prepare.h"
#include "vdbwrap/params.h"

namespace vdbwrap::pipeline {

prep::PrepareParams prepare_params(const WrapParams& params);
grid::SizeRequests size_requests(const WrapParams& params);
grid::RefineCriteria refine_criteria(const WrapParams& params);

}  // namespace vdbwrap::pipeline
