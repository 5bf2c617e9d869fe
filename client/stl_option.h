// `--stl ascii|binary` of `wrap` and `repair`: how an STL output is encoded. Not an option of
// `submit`: the server writes its results itself (binary, ASCII with several parts).
#pragma once
#include <CLI/CLI.hpp>

#include <string>

#include "vdbwrap/io.h"

namespace vdbwrap::cli {

class StlOption {
 public:
  void add_to(CLI::App* cmd);
  // The writer's options for `output`. Without --stl: binary, ASCII when the mesh has several
  // parts (binary STL has no solids). Throws Error(InvalidArgument) when --stl is given for an
  // output that is not .stl. The coordinates are the same either way: STL output is validated
  // in single precision (WrapParams::float_coordinates), so ASCII and binary hold one mesh.
  io::WriteOptions write_options(const std::string& output) const;

 private:
  std::string encoding_;  // "", "ascii" or "binary"
};

}  // namespace vdbwrap::cli
