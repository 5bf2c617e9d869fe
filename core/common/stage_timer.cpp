#include "common/stage_timer.h"

#include <fstream>
#include <sstream>

namespace vdbwrap {

double current_peak_memory_mb() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmHWM:", 0) == 0) {
      std::istringstream in(line.substr(6));
      double kb = 0;
      in >> kb;
      return kb / 1024.0;
    }
  return 0;
}

void reset_peak_memory() {
  // Writing 5 to clear_refs resets the peak resident set size (Linux 4.0+).
  std::ofstream clear("/proc/self/clear_refs");
  if (clear) clear << "5";
}

}  // namespace vdbwrap
