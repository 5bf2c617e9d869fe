// What the lattice extraction hands to the manifold fix: the finest lattice's numbering, the
// volume test of a leaf, and a surface's faces and nodes before its polygons are made.
#pragma once
#include <cstdint>
#include <vector>

#include "common/dense_numbers.h"
#include "extract/extract_surface.h"
#include "grid/adaptive_grid.h"
#include "vdbwrap/params.h"

namespace vdbwrap::extract {

// The finest lattice's points, from 0 to the box's far side, numbered densely.
inline DenseNumbers lattice_numbers(const grid::AdaptiveGrid& g) {
  const uint64_t fu = uint64_t(g.fine_units(0));
  const Coord& d = g.dims0();
  return DenseNumbers({0, 0, 0}, {uint64_t(d.x()) * fu + 1, uint64_t(d.y()) * fu + 1, uint64_t(d.z()) * fu + 1});
}

// Is a leaf in the chosen volume (outside the box counts as chosen for VolumeChoice::Outside)?
inline bool in_volume(const grid::LeafRef& r, int32_t label, VolumeChoice choice) {
  if (r.outside_box) return choice == VolumeChoice::Outside;
  return r.value == label;
}

// A cell face: its corners on the finest lattice, its side in fine units.
struct Quad {
  Coord corner[4];
  int32_t size;
};

// A surface's faces and nodes, and what its polygons are made from: extraction's rounds
// before the last need the nodes alone, so the polygons are made only for the last.
struct FacesAndNodes {
  LatticeSurface surf;  // nodes only
  std::vector<Quad> quads;
  std::vector<uint64_t> group_point;  // lattice point of each group of corners, ascending
  std::vector<uint32_t> group_of_corner, node_of_group;
  DenseNumbers lattice;
};

// The faces between the volume `label` and the rest, and their corners numbered as nodes.
FacesAndNodes faces_and_nodes(const grid::AdaptiveGrid& g, int32_t label, VolumeChoice choice);

// The surface with its polygons.
LatticeSurface with_polygons(FacesAndNodes&& fn);

}  // namespace vdbwrap::extract
