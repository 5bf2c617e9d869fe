#include "stl_option.h"

#include "vdbwrap/errors.h"

namespace vdbwrap::cli {

void StlOption::add_to(CLI::App* cmd) {
  cmd->add_option("--stl", encoding_,
                  "Encoding of an .stl output: ascii (text, one solid per part) or binary (no part names); "
                  "default binary, ascii when the result has several parts")
      ->check(CLI::IsMember({"ascii", "binary"}))
      ->group("Output");
}

io::WriteOptions StlOption::write_options(const std::string& output) const {
  io::WriteOptions options;
  if (encoding_.empty()) return options;
  if (io::format_from_extension(output) != io::Format::Stl)
    throw Error(ErrorKind::InvalidArgument, "--stl " + encoding_ + ": the output " + output + " is not an .stl file");
  options.stl = encoding_ == "ascii" ? io::StlEncoding::Ascii : io::StlEncoding::Binary;
  return options;
}

}  // namespace vdbwrap::cli
