// Jittered fine anisotropic tessellations for the repair benchmark (issue 35), written as OBJ
// (double coordinates: the jitter is not rounded away).
//
//   make_jittered OUT_DIR [--kind K] [--seeds N] [--scale S] [--amount A]
//     Writes KIND_sSCALE_SEED.obj for seeds 1..N (default 3) of each kind (default: all of
//     tests/support/jittered_meshes.h: anisotropic_sphere, cad_cylinder, trefoil_tube), every
//     vertex moved by up to A x the mesh's shortest edge (default: the kind's, 1.25 for the
//     sphere, 1.1 for the others).
//
// Deterministic for a given (kind, seed, scale, amount).
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "jittered_meshes.h"
#include "vdbwrap/io.h"

using namespace vdbwrap;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: make_jittered OUT_DIR [--kind K] [--seeds N] [--scale S] [--amount A]\n");
    return 2;
  }
  const std::string dir = argv[1];
  std::vector<std::string> kinds = testing::jittered_kinds();
  int seeds = 3, scale = 1;
  double amount = 0;
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string flag = argv[i], value = argv[i + 1];
    if (flag == "--kind")
      kinds = {value};
    else if (flag == "--seeds")
      seeds = std::atoi(value.c_str());
    else if (flag == "--scale")
      scale = std::atoi(value.c_str());
    else if (flag == "--amount")
      amount = std::atof(value.c_str());
    else {
      std::fprintf(stderr, "make_jittered: unknown option %s\n", flag.c_str());
      return 2;
    }
  }
  for (const std::string& kind : kinds)
    for (int seed = 1; seed <= seeds; ++seed) {
      const Mesh m = testing::jittered_mesh(kind, uint32_t(seed), scale, amount);
      const std::string path = dir + "/" + kind + "_s" + std::to_string(scale) + "_" + std::to_string(seed) + ".obj";
      io::write_mesh(m, path);
      std::printf("%s: %zu triangles\n", path.c_str(), m.triangles.size());
    }
  return 0;
}
