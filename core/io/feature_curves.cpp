#include "vdbwrap/io.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <map>

#include "vdbwrap/errors.h"

namespace vdbwrap::io {
namespace {

struct EdgeGraph {
  std::vector<Vec3> points;
  std::vector<std::vector<size_t>> curves;  // point indices per curve
};

// Identical points get one index: the curves come from one welded input, so a shared corner
// is bit-identical in each curve that meets there.
EdgeGraph index_points(const std::vector<std::vector<Vec3>>& curves) {
  EdgeGraph g;
  std::map<std::array<double, 3>, size_t> index;
  for (const auto& curve : curves) {
    if (curve.size() < 2) continue;  // no edge
    auto& ids = g.curves.emplace_back();
    for (const Vec3& p : curve) {
      auto [it, added] = index.try_emplace({p[0], p[1], p[2]}, g.points.size());
      if (added) g.points.push_back(p);
      if (ids.empty() || ids.back() != it->second) ids.push_back(it->second);
    }
    if (ids.size() < 2) g.curves.pop_back();
  }
  return g;
}

void append(std::string& out, const char* fmt, double x, double y, double z) {
  char line[128];
  std::snprintf(line, sizeof line, fmt, x, y, z);
  out += line;
}

}  // namespace

CurveFormat curve_format_from_extension(const std::string& path) {
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || path.find_first_of("/\\", dot) != std::string::npos) return CurveFormat::Unknown;
  std::string ext = path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (ext == "obj") return CurveFormat::Obj;
  if (ext == "emesh") return CurveFormat::EMesh;
  return CurveFormat::Unknown;
}

std::string feature_curves_to_text(const std::vector<std::vector<Vec3>>& curves, CurveFormat format) {
  const EdgeGraph g = index_points(curves);
  size_t edges = 0;
  for (const auto& c : g.curves) edges += c.size() - 1;
  std::string out;
  if (format == CurveFormat::Obj) {
    out += "# vdbwrap feature curves: " + std::to_string(g.curves.size()) + " curves, " +
           std::to_string(g.points.size()) + " points, " + std::to_string(edges) + " edges\n";
    for (const Vec3& p : g.points) append(out, "v %.17g %.17g %.17g\n", p[0], p[1], p[2]);
    for (const auto& c : g.curves) {
      out += 'l';
      for (size_t id : c) out += ' ' + std::to_string(id + 1);
      out += '\n';
    }
    return out;
  }
  if (format != CurveFormat::EMesh) throw Error(ErrorKind::InvalidArgument, "feature curves: unknown format");
  out +=
      "FoamFile\n{\n    version     2.0;\n    format      ascii;\n    class       featureEdgeMesh;\n"
      "    object      features;\n}\n\n// vdbwrap feature curves: points, then edges (pairs of point indices)\n\n";
  out += std::to_string(g.points.size()) + "\n(\n";
  for (const Vec3& p : g.points) append(out, "(%.17g %.17g %.17g)\n", p[0], p[1], p[2]);
  out += ")\n\n" + std::to_string(edges) + "\n(\n";
  for (const auto& c : g.curves)
    for (size_t i = 0; i + 1 < c.size(); ++i)
      out += '(' + std::to_string(c[i]) + ' ' + std::to_string(c[i + 1]) + ")\n";
  out += ")\n";
  return out;
}

void write_feature_curves(const std::string& path, const std::vector<std::vector<Vec3>>& curves) {
  const CurveFormat format = curve_format_from_extension(path);
  if (format == CurveFormat::Unknown)
    throw Error(ErrorKind::InvalidArgument, path + ": feature curves are written as .obj or .eMesh");
  const std::string text = feature_curves_to_text(curves, format);
  auto failed = [&](const std::string& what) { throw Error(ErrorKind::OutputFailed, path + ": " + what); };
  const std::string tmp = path + ".tmp";
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) failed(std::string("cannot create ") + tmp + " (" + std::strerror(errno) + ")");
  const bool written = std::fwrite(text.data(), 1, text.size(), f) == text.size();
  const int saved = errno;
  if (std::fclose(f) != 0 || !written) {
    std::remove(tmp.c_str());
    failed(std::string("cannot write (") + std::strerror(written ? errno : saved) + ")");
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int e = errno;
    std::remove(tmp.c_str());
    failed(std::string("cannot rename ") + tmp + " (" + std::strerror(e) + ")");
  }
}

}  // namespace vdbwrap::io
