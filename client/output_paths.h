// Output paths are checked before any work starts: a wrap that runs for minutes and then
// cannot write its result because of a typo in a folder name wastes the run.
#pragma once
#include <string>

namespace vdbwrap::cli {

// path (given with `option`, e.g. "-o") must name a file in an existing, writable folder.
// Throws Error(InvalidArgument) naming the path when its folder is missing or not a folder,
// or when the path is a folder itself; Error(OutputFailed) when the folder is not writable.
// An empty path (option not given) passes.
void check_output_path(const std::string& option, const std::string& path);

// A folder for results (--out-dir): created with its parents when missing, like mkdir -p.
// Throws Error(InvalidArgument) when a file of that name is in the way, Error(OutputFailed)
// when it cannot be created or written to.
void ensure_output_folder(const std::string& option, const std::string& dir);

}  // namespace vdbwrap::cli
