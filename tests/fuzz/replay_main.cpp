// Replays inputs through a harness without libFuzzer (the normal build's regression test):
// every file of the directories given, in name order. A crash or a violated property ends the
// process with the file named just before it.
//
// A directory may hold open-bugs.txt: one "FILE reason" per line for reproducers of bugs not
// fixed yet. They are skipped (and listed) unless VDBWRAP_REPLAY_OPEN=1; delete the line with
// the fix.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

namespace fs = std::filesystem;

namespace {

std::set<std::string> open_bugs(const fs::path& dir) {
  std::set<std::string> names;
  std::ifstream in(dir / "open-bugs.txt");
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string name;
    if (words >> name && name[0] != '#') names.insert(name);
  }
  return names;
}

bool replay(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    std::fprintf(stderr, "cannot read %s\n", file.c_str());
    return false;
  }
  const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::fprintf(stderr, "replay %s (%zu bytes)\n", file.c_str(), bytes.size());
  LLVMFuzzerTestOneInput(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  const char* env = std::getenv("VDBWRAP_REPLAY_OPEN");
  const bool run_open = env && std::string(env) == "1";
  size_t done = 0, skipped = 0;
  bool ok = true;
  for (int i = 1; i < argc; ++i) {
    const fs::path arg = argv[i];
    if (!fs::is_directory(arg)) {
      ok = replay(arg) && ok, ++done;
      continue;
    }
    const std::set<std::string> open = open_bugs(arg);
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(arg)) {
      const std::string name = entry.path().filename().string();
      if (entry.is_regular_file() && name != "open-bugs.txt" && name != "README.md" && name[0] != '.')
        files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
    for (const fs::path& f : files) {
      if (!run_open && open.count(f.filename().string())) {
        std::fprintf(stderr, "skip %s (open bug, see open-bugs.txt)\n", f.c_str());
        ++skipped;
        continue;
      }
      ok = replay(f) && ok, ++done;
    }
  }
  std::fprintf(stderr, "replayed %zu input(s), skipped %zu open bug reproducer(s)\n", done, skipped);
  return ok ? 0 : 1;
}
