// What every entry point asks of a mesh before any stage reads it: indices in range,
// coordinates finite and within the range where the geometry's products stay finite.
#pragma once
#include "vdbwrap/mesh.h"

namespace vdbwrap::prep {

// Coordinates beyond this magnitude are refused: squared distances and the exact predicates'
// filters need products of three coordinate differences to stay far from overflow.
constexpr double kMaxCoordinate = 1e15;

// Throws Error(InvalidInput) naming the first bad vertex or triangle; `what` starts the
// message ("input", "repair input").
void check_input_mesh(const Mesh& mesh, const char* what = "input");

}  // namespace vdbwrap::prep
