#include "output_paths.h"

#include <unistd.h>

#include <filesystem>

#include "vdbwrap/errors.h"

namespace vdbwrap::cli {

namespace fs = std::filesystem;

void check_output_path(const std::string& option, const std::string& path) {
  if (path.empty()) return;
  std::error_code ec;
  const fs::path p(path);
  if (fs::is_directory(p, ec))
    throw Error(ErrorKind::InvalidArgument, option + " " + path + ": is a folder, not a file name");
  const fs::path folder = p.parent_path().empty() ? fs::path(".") : p.parent_path();
  if (!fs::exists(folder, ec))
    throw Error(ErrorKind::InvalidArgument,
                option + " " + path + ": the folder " + folder.string() + " does not exist");
  if (!fs::is_directory(folder, ec))
    throw Error(ErrorKind::InvalidArgument, option + " " + path + ": " + folder.string() + " is not a folder");
  if (::access(folder.c_str(), W_OK) != 0)
    throw Error(ErrorKind::OutputFailed, option + " " + path + ": the folder " + folder.string() + " is not writable");
}

void ensure_output_folder(const std::string& option, const std::string& dir) {
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
    throw Error(ErrorKind::InvalidArgument, option + " " + dir + ": is a file, not a folder");
  if (!fs::is_directory(dir, ec) && !fs::create_directories(dir, ec))
    throw Error(ErrorKind::OutputFailed,
                option + " " + dir + ": cannot create the folder" + (ec ? ": " + ec.message() : ""));
  if (::access(dir.c_str(), W_OK) != 0)
    throw Error(ErrorKind::OutputFailed, option + " " + dir + ": the folder is not writable");
}

}  // namespace vdbwrap::cli
