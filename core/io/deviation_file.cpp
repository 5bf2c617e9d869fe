// A deviation field on disk: the surface with its distances as point data and its parts and
// defect flags as cell data, through the VTP and PLY writers' extra arrays.
#include <string>

#include "vdbwrap/io.h"
#include "vdbwrap/deviation.h"

namespace vdbwrap {

bool is_deviation_path(const std::string& path) {
  const io::Format f = io::format_from_extension(path);
  return f == io::Format::Vtp || f == io::Format::Ply;
}

void write_deviation(const std::string& path, const Mesh& surface, const DeviationField& field) {
  if (!is_deviation_path(path))
    throw Error(ErrorKind::InvalidArgument, path + ": a deviation field is written as .vtp or .ply");
  if (field.distance.size() != surface.points.size())
    throw Error(ErrorKind::InvalidArgument, path + ": the deviation field has " +
                                                std::to_string(field.distance.size()) + " distances for " +
                                                std::to_string(surface.points.size()) + " vertices");
  if (!field.triangle_flags.empty() && field.triangle_flags.size() != surface.triangles.size())
    throw Error(ErrorKind::InvalidArgument, path + ": the deviation field has " +
                                                std::to_string(field.triangle_flags.size()) + " defect flags for " +
                                                std::to_string(surface.triangles.size()) + " triangles");
  using Type = io::DataArray::Type;
  io::MeshData data;
  data.point_data.push_back({"distance", Type::Float64, field.distance});
  io::DataArray& percent =
      data.point_data.emplace_back(io::DataArray{"distance_percent_of_diagonal", Type::Float64, {}});
  percent.values.reserve(field.distance.size());
  for (double d : field.distance) percent.values.push_back(field.percent_of_diagonal(d));
  // PLY writes the parts itself as the face property "part" when the surface has part names.
  if (io::format_from_extension(path) == io::Format::Vtp || surface.part_names.empty()) {
    io::DataArray& part = data.cell_data.emplace_back(io::DataArray{"part", Type::Int32, {}});
    part.values.resize(surface.triangles.size());
    for (size_t t = 0; t < surface.triangles.size(); ++t) part.values[t] = surface.part_of(t);
  }
  io::DataArray& defects = data.cell_data.emplace_back(io::DataArray{"defects", Type::UInt8, {}});
  defects.values.assign(field.triangle_flags.begin(), field.triangle_flags.end());
  defects.values.resize(surface.triangles.size(), 0.0);
  io::WriteOptions options;
  options.data = &data;
  io::write_mesh(surface, path, options);
}

}  // namespace vdbwrap
