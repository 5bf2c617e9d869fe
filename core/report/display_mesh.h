// A mesh as the HTML report's viewer gets it: single-precision coordinates relative to a common
// origin (CAD far from the origin keeps its detail in floats), and meshes too big for a browser
// clustered to a display size. Display only: every number on the page is from the full mesh.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/exact_weld.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::report {

struct DisplayMesh {
  std::vector<float> positions;           // x, y, z per display vertex, minus the origin
  std::vector<uint32_t> triangles;        // three display vertices per triangle
  std::vector<uint32_t> source_triangle;  // the mesh triangle each display triangle stands for
  std::vector<uint32_t> vertex_of;        // per mesh point: its display vertex
  size_t mesh_triangles = 0;
  bool clustered = false;   // vertex clustering reduced it
  double cluster_size = 0;  // the clustering cell, model units
};

// The mesh as is when it has at most max_triangles triangles; else its points merged by cells
// of a uniform grid (vertex clustering: the shape survives, small detail goes), the cell grown
// until at most max_triangles are left. weld: the exact weld of mesh.points when the caller has
// it (clustering works on the distinct points), else it is made here.
DisplayMesh display_mesh(const Mesh& mesh, const Vec3& origin, size_t max_triangles, const ExactWeld* weld = nullptr);

// Per-point values on the display vertices; a cluster shows its value of largest magnitude
// (the worst deviation stays visible).
std::vector<float> display_values(const DisplayMesh& display, const std::vector<double>& per_point);

// Per-triangle values on the display triangles.
template <typename T>
std::vector<T> display_per_triangle(const DisplayMesh& display, const std::vector<T>& per_triangle) {
  std::vector<T> out(display.source_triangle.size());
  for (size_t i = 0; i < out.size(); ++i) out[i] = per_triangle[display.source_triangle[i]];
  return out;
}

}  // namespace vdbwrap::report
