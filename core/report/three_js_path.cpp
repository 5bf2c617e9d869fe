// Where the viewer library comes from: three.js is not part of the repository; Debian's
// libjs-three installs it, and the page embeds it so that it opens without a network.
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "vdbwrap/html_report.h"

#ifndef VDBWRAP_THREE_JS_PATH
#define VDBWRAP_THREE_JS_PATH ""
#endif

namespace vdbwrap {
namespace {

bool readable(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return in.good() && in.peek() != std::ifstream::traits_type::eof();
}

}  // namespace

std::string find_three_js() {
  // An explicit choice is not second-guessed: a wrong VDBWRAP_THREE_JS is an error, not a fallback.
  if (const char* env = std::getenv("VDBWRAP_THREE_JS"); env && *env) {
    if (readable(env)) return env;
    throw Error(ErrorKind::InvalidArgument,
                std::string("--html: VDBWRAP_THREE_JS names ") + env + ", which is missing, empty or unreadable");
  }
  std::vector<std::string> tried;
  const std::string configured = VDBWRAP_THREE_JS_PATH;
  if (!configured.empty()) tried.push_back(configured);
  for (const char* p : {"/usr/share/javascript/three/three.min.js", "/usr/share/nodejs/three/build/three.min.js",
                        "/usr/lib/nodejs/three/build/three.min.js", "/usr/local/share/javascript/three/three.min.js"})
    tried.push_back(p);
  for (const std::string& p : tried)
    if (readable(p)) return p;
  std::string msg =
      "--html needs three.js (Debian package libjs-three; or set VDBWRAP_THREE_JS to a three.min.js); not found at";
  for (size_t i = 0; i < tried.size(); ++i) msg += (i ? ", " : " ") + tried[i];
  throw Error(ErrorKind::InvalidArgument, msg);
}

std::string read_three_js(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(ErrorKind::InvalidArgument, "--html: cannot read " + path);
  std::ostringstream text;
  text << in.rdbuf();
  if (text.str().empty()) throw Error(ErrorKind::InvalidArgument, "--html: " + path + " is empty");
  return text.str();
}

}  // namespace vdbwrap
