// Writes hostile meshes (hostile_meshes.h) to a directory, to wrap them by hand or attach them
// to a bug report.
//
//   make_hostile OUT_DIR [--scale K] [--seed S] [--kind NAME]...   (default: every kind, K = 1, S = 1)
//   make_hostile --list
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "hostile_meshes.h"

int main(int argc, char** argv) {
  using namespace vdbwrap::stress;
  if (argc == 2 && std::string(argv[1]) == "--list") {
    for (const auto& k : hostile_kinds()) std::printf("%s\n", k.c_str());
    return 0;
  }
  if (argc < 2 || argv[1][0] == '-') {
    std::fprintf(stderr, "usage: make_hostile OUT_DIR [--scale K] [--seed S] [--kind NAME]... | make_hostile --list\n");
    return 2;
  }
  const std::filesystem::path dir = argv[1];
  int scale = 1;
  uint32_t seed = 1;
  std::vector<std::string> kinds;
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string opt = argv[i], value = argv[i + 1];
    if (opt == "--scale")
      scale = std::atoi(value.c_str());
    else if (opt == "--seed")
      seed = uint32_t(std::strtoul(value.c_str(), nullptr, 10));
    else if (opt == "--kind")
      kinds.push_back(value);
    else {
      std::fprintf(stderr, "make_hostile: unknown option %s\n", opt.c_str());
      return 2;
    }
  }
  if (kinds.empty()) kinds = hostile_kinds();
  std::filesystem::create_directories(dir);
  try {
    for (const auto& kind : kinds) {
      HostileMesh h = make_hostile(kind, scale, seed);
      std::ofstream((dir / h.file_name).string(), std::ios::binary) << h.bytes;
      std::printf("%s: %zu triangles, %zu bytes%s\n", h.file_name.c_str(), h.triangles, h.bytes.size(),
                  h.must_be_refused ? " (must be refused)" : "");
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "make_hostile: %s\n", e.what());
    return 2;
  }
  return 0;
}
