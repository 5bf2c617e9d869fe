// Text forms of the voxel-stage controls, shared by the CLI (local and remote) and the
// parameter file: "box:0,0,0,1,1,1:0.5%", "hot,cold", "a,b:c,d", "NAME=SIZE", "X,Y,Z".
#include <charconv>
#include <cmath>
#include <sstream>

#include "vdbwrap/params.h"

namespace vdbwrap {
namespace {

[[noreturn]] void bad(const std::string& what) { throw Error(ErrorKind::InvalidArgument, what); }

std::string trim(const std::string& s) {
  size_t b = s.find_first_not_of(" \t"), e = s.find_last_not_of(" \t");
  return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string cur;
  std::istringstream in(s);
  while (std::getline(in, cur, sep)) out.push_back(trim(cur));
  if (!s.empty() && s.back() == sep) out.push_back("");
  return out;
}

double number(const std::string& text, const std::string& context) {
  double v = 0;
  auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || ec != std::errc() || end != text.data() + text.size() || !std::isfinite(v))
    bad(context + ": '" + text + "' is not a number");
  return v;
}

std::vector<double> numbers(const std::string& text, const std::string& context) {
  std::vector<double> out;
  for (const std::string& t : split(text, ',')) out.push_back(number(t, context));
  return out;
}

// Shortest text that reads back to the same double ("0.2", not "0.20000000000000001").
std::string join(const std::vector<double>& v) {
  std::string s;
  char buf[64];
  for (size_t i = 0; i < v.size(); ++i) {
    auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v[i]);
    if (i) s += ',';
    s.append(buf, ec == std::errc() ? end : buf);
  }
  return s;
}

}  // namespace

ControlVolume ControlVolume::parse(const std::string& text) {
  const std::string usage =
      "control volume '" + text +
      "': expected box:X0,Y0,Z0,X1,Y1,Z1:SIZE, sphere:X,Y,Z,R:SIZE, cylinder:X0,Y0,Z0,X1,Y1,Z1,R:SIZE or "
      "cone:X0,Y0,Z0,X1,Y1,Z1,R0,R1:SIZE";
  auto fields = split(text, ':');
  if (fields.size() != 3) bad(usage);
  ControlVolume cv;
  const std::string& kind = fields[0];
  std::vector<double> v = numbers(fields[1], "control volume '" + text + "'");
  auto point = [&](size_t i) { return Vec3{v[i], v[i + 1], v[i + 2]}; };
  if (kind == "box" && v.size() == 6) {
    cv.shape = Shape::Box;
    cv.a = point(0), cv.b = point(3);
    for (int k = 0; k < 3; ++k)
      if (cv.a[k] > cv.b[k]) std::swap(cv.a[k], cv.b[k]);
  } else if (kind == "sphere" && v.size() == 4) {
    cv.shape = Shape::Sphere;
    cv.a = cv.b = point(0);
    cv.radius = v[3];
  } else if (kind == "cylinder" && v.size() == 7) {
    cv.shape = Shape::Cylinder;
    cv.a = point(0), cv.b = point(3);
    cv.radius = cv.radius_b = v[6];
  } else if (kind == "cone" && v.size() == 8) {
    cv.shape = Shape::Cone;
    cv.a = point(0), cv.b = point(3);
    cv.radius = v[6], cv.radius_b = v[7];
  } else {
    bad(usage);
  }
  if (cv.radius < 0 || cv.radius_b < 0) bad("control volume '" + text + "': radii must not be negative");
  if (cv.shape != Shape::Box && cv.shape != Shape::Sphere && cv.a == cv.b)
    bad("control volume '" + text + "': the axis has zero length");
  cv.size = Length::parse(fields[2]);
  cv.name = text;
  return cv;
}

std::string ControlVolume::to_string() const {
  switch (shape) {
    case Shape::Box:
      return "box:" + join({a[0], a[1], a[2], b[0], b[1], b[2]}) + ":" + size.to_string();
    case Shape::Sphere:
      return "sphere:" + join({a[0], a[1], a[2], radius}) + ":" + size.to_string();
    case Shape::Cylinder:
      return "cylinder:" + join({a[0], a[1], a[2], b[0], b[1], b[2], radius}) + ":" + size.to_string();
    case Shape::Cone:
      return "cone:" + join({a[0], a[1], a[2], b[0], b[1], b[2], radius, radius_b}) + ":" + size.to_string();
  }
  return "";
}

PartSize PartSize::parse(const std::string& text) {
  size_t eq = text.rfind('=');
  if (eq == std::string::npos) bad("part size '" + text + "': expected NAME=SIZE");
  std::string name = trim(text.substr(0, eq));
  // A blank name (" =1") would match no part, as the API's empty one does: refused alike.
  if (name.empty()) bad("part size '" + text + "': the part name is empty (expected NAME=SIZE)");
  return PartSize{std::move(name), Length::parse(text.substr(eq + 1))};
}

ContactRule ContactRule::parse(const std::string& text) {
  ContactRule rule;
  for (const std::string& group : split(text, ':')) {
    std::vector<std::string> names;
    for (const std::string& n : split(group, ','))
      if (!n.empty()) names.push_back(n);
    if (names.empty()) bad("contact prevention '" + text + "': an empty group of part names");
    rule.groups.push_back(std::move(names));
  }
  if (rule.groups.size() > 2) bad("contact prevention '" + text + "': at most two groups (A:B)");
  if (rule.groups.size() == 1 && rule.groups[0].size() < 2)
    bad("contact prevention '" + text + "': name at least two parts (a,b) or two groups (a:b)");
  return rule;
}

std::string ContactRule::to_string() const {
  std::string s;
  for (size_t g = 0; g < groups.size(); ++g) {
    if (g) s += ':';
    for (size_t i = 0; i < groups[g].size(); ++i) s += (i ? "," : "") + groups[g][i];
  }
  return s;
}

void parse_volume_choice(const std::string& text, VolumeChoice& choice, std::vector<Vec3>& seeds) {
  const std::string t = trim(text);
  seeds.clear();
  if (t == "outside") {
    choice = VolumeChoice::Outside;
    return;
  }
  if (t == "inside") {
    choice = VolumeChoice::Inside;
    return;
  }
  for (const std::string& point : split(t, ';')) {
    if (point.empty()) continue;
    std::vector<double> v;
    try {
      v = numbers(point, "volume");
    } catch (const Error&) {
      bad("volume '" + text + "': expected outside, inside, or seed points X,Y,Z (several separated by ';')");
    }
    if (v.size() != 3) bad("volume '" + text + "': a seed point needs three coordinates X,Y,Z");
    seeds.push_back({v[0], v[1], v[2]});
  }
  if (seeds.empty()) bad("volume '" + text + "': expected outside, inside, or seed points X,Y,Z");
  choice = VolumeChoice::SeedPoints;
}

std::string volume_choice_to_string(VolumeChoice choice, const std::vector<Vec3>& seeds) {
  if (choice == VolumeChoice::Outside) return "outside";
  if (choice == VolumeChoice::Inside) return "inside";
  std::string s;
  for (size_t i = 0; i < seeds.size(); ++i) s += (i ? ";" : "") + join({seeds[i][0], seeds[i][1], seeds[i][2]});
  return s;
}

}  // namespace vdbwrap
