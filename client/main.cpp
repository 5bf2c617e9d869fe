// vdbwrap: the command-line client. A thin layer over the core API: parse options, read,
// call wrap(), repair() or diagnose(), write, report. Exit codes: 0 ok, 2 bad arguments, 3 unreadable
// or invalid input, 4 no valid surface produced (repair: intersections left, output written),
// 5 output not written, 1 internal error.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "cli_progress.h"
#include "html_output.h"
#include "output_paths.h"
#include "repair_options.h"
#include "stl_option.h"
#include "suggest.h"
#include "wrap_options.h"
#ifdef VDBWRAP_WITH_REMOTE
#include "remote.h"  // submit, wait, jobs, cancel (gRPC job service)
#endif
#include "vdbwrap/io.h"
#include "vdbwrap/deviation.h"
#include "vdbwrap/repair.h"
#include "vdbwrap/source.h"
#include "vdbwrap/wrap.h"

namespace {

using namespace vdbwrap;

void write_text(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw Error(ErrorKind::OutputFailed, path + ": cannot write the report");
    out << text << '\n';
    if (!out) throw Error(ErrorKind::OutputFailed, path + ": cannot write the report");
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0)
    throw Error(ErrorKind::OutputFailed, path + ": cannot write the report");
}

std::string percent(double v, double diag) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.4f%%", diag > 0 ? 100.0 * v / diag : 0.0);
  return buf;
}

void print_diagnostics(const std::string& name, const MeshDiagnostics& d) {
  std::printf("%s\n", name.c_str());
  std::printf("  triangles %zu, vertices %zu, parts %zu, connected components %zu\n", d.triangles, d.vertices, d.parts,
              d.components);
  std::printf("  border edges %zu, non-manifold edges %zu, non-manifold vertices %zu, misoriented edges %zu\n",
              d.border_edges, d.nonmanifold_edges, d.nonmanifold_vertices, d.misoriented_edges);
  std::printf("  degenerate triangles %zu, intersecting triangles %zu (%zu pairs)\n", d.degenerate_triangles,
              d.intersecting_triangles, d.intersecting_pairs);
  std::printf("  closed %s, manifold %s, oriented %s, outward %s, self-intersecting %s\n", d.closed ? "yes" : "no",
              d.manifold ? "yes" : "no", d.oriented ? "yes" : "no", d.outward ? "yes" : "no",
              d.self_intersecting ? "yes" : "no");
  std::printf("  bounding-box diagonal %.6g, area %.6g, volume %.6g\n", d.diagonal, d.area, d.volume);
  std::printf("  verdict: %s\n",
              d.valid_closed_surface() ? "valid closed surface (watertight)" : "NOT a valid closed surface");
}

void print_repair_report(const std::string& output, const RepairReport& r) {
  std::printf("repair of %zu triangles -> %s\n", r.before.triangles, output.c_str());
  std::printf(
      "  regions of intersecting triangles: %zu found, %zu fixed by local operations, %zu fixed by refill, "
      "%zu fixed by uniting bodies, %zu left unfixed\n",
      r.regions_found, r.fixed_by_local, r.fixed_by_refill, r.fixed_by_union, r.left_unfixed);
  std::printf(
      "  local operations: %zu iterations, %zu vertex shifts, %zu triangle shifts, %zu untangles; refill: %zu "
      "iterations, %zu refills, %zu refused\n",
      r.local_iterations_run, r.vertex_shifts, r.triangle_shifts, r.untangles, r.refill_iterations_run, r.refills,
      r.refill_failures);
  for (const auto& [why, count] : r.refusals) std::printf("  refused %zux: %s\n", count, why.c_str());
  if (r.cracks_stitched > 0)
    std::printf("  cracks stitched (corners welded or inserted into edges): %zu\n", r.cracks_stitched);
  if (r.bodies_united > 0) std::printf("  crossing closed bodies united: %zu\n", r.bodies_united);
  if (r.regions_refined > 0)
    std::printf("  refined before refilling: %zu regions (%zu triangles added)\n", r.regions_refined,
                r.refined_triangles_added);
  if (r.pieces_removed > 0)
    std::printf("  small pieces removed: %zu (%zu triangles)\n", r.pieces_removed, r.piece_triangles_removed);
  std::printf(
      "  intersecting pairs %zu -> %zu, border edges %zu -> %zu, non-manifold edges %zu -> %zu, triangles %zu -> %zu\n",
      r.before.intersecting_pairs, r.after.intersecting_pairs, r.before.border_edges, r.after.border_edges,
      r.before.nonmanifold_edges, r.after.nonmanifold_edges, r.before.triangles, r.after.triangles);
  if (r.output_to_input.samples > 0)
    std::printf("  largest deviation from the input (two-sided, sampled): %s of the diagonal %.6g (bound %s)\n",
                percent(r.deviation * r.diagonal, r.diagonal).c_str(), r.diagonal,
                percent(r.max_deviation, r.diagonal).c_str());
  for (size_t i = 0; i < r.unfixed.size() && i < 20; ++i) {
    const auto& u = r.unfixed[i];
    std::printf(
        "  unfixed region %zu: %zu triangles, %zu pairs, around (%.6g, %.6g, %.6g), box (%.6g, %.6g, %.6g)-(%.6g, "
        "%.6g, %.6g)\n",
        i + 1, u.triangles, u.pairs, u.center[0], u.center[1], u.center[2], u.bbox_min[0], u.bbox_min[1], u.bbox_min[2],
        u.bbox_max[0], u.bbox_max[1], u.bbox_max[2]);
  }
  if (r.unfixed.size() > 20) std::printf("  ... %zu more unfixed regions in the JSON report\n", r.unfixed.size() - 20);
  std::printf("  %.2fs; %s\n", r.total_seconds, r.all_fixed() ? "no intersections left" : "INTERSECTIONS LEFT");
}

// A mesh read, and what reading it had to assume (a binary STL's stale count) said on stderr,
// also with -q: the user should know. `progress`: its redrawn line is ended first.
Mesh read_input(const std::string& path, cli::StderrProgress* progress = nullptr) {
  Mesh mesh = io::read_mesh(path);
  if (!mesh.notes.empty() && progress) progress->finish();
  for (const std::string& note : mesh.notes) std::fprintf(stderr, "vdbwrap: note: %s\n", note.c_str());
  return mesh;
}

// --deviation: a .vtp or .ply in a folder that exists, checked before any work.
void check_deviation_path(const std::string& path) {
  if (path.empty()) return;
  if (!is_deviation_path(path))
    throw Error(ErrorKind::InvalidArgument, "--deviation " + path + ": the deviation field is written as .vtp or .ply");
  cli::check_output_path("--deviation", path);
}

bool looks_like_number(const std::string& t) {
  return t.size() > 1 && t[0] == '-' && (std::isdigit(static_cast<unsigned char>(t[1])) || t[1] == '.');
}

// The first unknown subcommand or option on the command line, as a message naming the
// closest valid one: CLI11 only says "A subcommand is required" or "arguments were not
// expected". Empty when every name is known (the error is about something else).
std::string unknown_argument(CLI::App& app, int argc, char** argv) {
  std::vector<std::string> commands;
  for (const CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) commands.push_back(sub->get_name());
  std::vector<std::string> top;  // --help, --version: the options before the command
  for (const CLI::Option* o : static_cast<const CLI::App&>(app).get_options())
    for (const std::string& l : o->get_lnames()) top.push_back("--" + l);
  int at = 1;
  for (; at < argc && argv[at][0] == '-'; ++at) {
    const std::string t = argv[at];
    if (t.size() < 3 || std::find(top.begin(), top.end(), t) != top.end()) continue;
    if (auto near = cli::closest_match(t, top)) return "unknown option " + t + "; did you mean " + *near + "?";
    return "unknown option " + t + " (vdbwrap --help lists the commands)";
  }
  if (at >= argc) return "";
  const std::string word = argv[at];
  CLI::App* cmd = nullptr;
  try {
    cmd = app.get_subcommand(word);
  } catch (const CLI::OptionNotFound&) {
  }
  if (!cmd) {
    std::string msg = "unknown command " + word;
    if (auto near = cli::closest_match(word, commands)) return msg + "; did you mean " + *near + "?";
    msg += "; the commands are";
    for (size_t i = 0; i < commands.size(); ++i) msg += (i ? ", " : " ") + commands[i];
    return msg;
  }
  std::vector<std::string> names;
  std::vector<std::string> takes_value;  // short names that may carry their value (-oFILE)
  for (const CLI::App* scope : {static_cast<const CLI::App*>(cmd), static_cast<const CLI::App*>(&app)})
    for (const CLI::Option* o : scope->get_options()) {
      for (const std::string& l : o->get_lnames()) names.push_back("--" + l);
      for (const std::string& s : o->get_snames()) {
        names.push_back("-" + s);
        if (o->get_items_expected_max() > 0) takes_value.push_back("-" + s);
      }
    }
  auto known = [](const std::vector<std::string>& list, const std::string& t) {
    return std::find(list.begin(), list.end(), t) != list.end();
  };
  for (int i = at + 1; i < argc; ++i) {
    std::string t = argv[i];
    if (t == "--") break;  // the rest are values
    if (t.size() < 2 || t[0] != '-' || looks_like_number(t)) continue;
    if (t[1] == '-')
      t = t.substr(0, t.find('='));
    else if (t.size() > 2 && known(takes_value, t.substr(0, 2)))
      continue;  // -oFILE
    if (known(names, t)) continue;
    std::string msg = "unknown option " + t;
    if (auto near = cli::closest_match(t, names)) return msg + "; did you mean " + *near + "?";
    return msg + " (vdbwrap " + word + " --help lists the options)";
  }
  return "";
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "vdbwrap: shrink-wraps dirty triangle surfaces into closed, 2-manifold, self-intersection-free ones.\n"
      "Reads and writes STL (binary/ASCII), OBJ, OFF and PLY (ASCII/binary)."};
  app.require_subcommand(1);
  app.set_version_flag("--version", "vdbwrap " VDBWRAP_VERSION);
  app.footer(
      "Examples:\n"
      "  vdbwrap wrap part.stl -o part_wrap.stl --base-size 0.5% --report part_wrap.json\n"
      "  vdbwrap check part_wrap.stl --against part.stl\n"
      "  vdbwrap repair part.stl -o part_fixed.stl\n"
      "Run vdbwrap COMMAND --help for the options of a command.");

  // wrap
  auto* wrap_cmd = app.add_subcommand("wrap", "Wrap INPUT into a closed, valid surface written to OUTPUT");
  std::string input, output, report_path, leak_path, deviation_path;
  cli::WrapOptions wrap_options;
  bool quiet = false;
  wrap_cmd->add_option("input", input, "Input mesh (.stl .obj .off .ply .vtp .nas .bdf)")->required();
  wrap_options.add_to(wrap_cmd, "Worker threads (0: all cores)");
  // After the parameters: the help lists its groups in the order they first appear.
  wrap_cmd->add_option("-o,--output", output, "Output mesh; the format follows the extension")
      ->required()
      ->group("Output");
  wrap_cmd
      ->add_option("--report", report_path,
                   "Write a JSON report (diagnostics, parameters, validity, distances, timings)")
      ->group("Output");
  wrap_cmd
      ->add_option("--leak-path", leak_path,
                   "When a seed point's volume leaks: write the narrowest passage and the path to it here (OBJ)")
      ->group("Output");
  wrap_cmd
      ->add_option("--deviation", deviation_path,
                   "Write the wrap with its signed distance to the input per vertex and its defect flags per triangle "
                   "(.vtp for ParaView, or .ply)")
      ->group("Output");
  cli::HtmlOutput html_output;
  html_output.add_to(wrap_cmd);
  cli::StlOption wrap_stl;
  wrap_stl.add_to(wrap_cmd);
  std::string features_path;
  wrap_cmd
      ->add_option(
          "--features", features_path,
          "Write the input's feature curves (the sharp edges the wrap snaps to) as OBJ lines or OpenFOAM's .eMesh")
      ->group("Output");
  wrap_cmd->add_flag("-q,--quiet", quiet, "No progress on stderr")->group("Output");
  wrap_cmd->footer(
      "Examples:\n"
      "  vdbwrap wrap part.stl -o part_wrap.stl --base-size 0.5% --report part_wrap.json\n"
      "  vdbwrap wrap engine_bay.stl -o cabin.obj --volume 0.2,1.5,0.9 --gap-closure 0.15 --leak-path leak.obj\n"
      "  vdbwrap wrap assembly.obj -o wrap.obj --params params.yaml --levels 2\n"
      "Exit codes: 0 ok; 2 bad arguments (checked before the wrap starts, output folders included); 3 unreadable or\n"
      "invalid input; 4 no valid surface (a leak, a failed validation; the report is still written); 5 output not\n"
      "written; 1 internal error.");

  // check
  auto* check_cmd = app.add_subcommand("check", "Diagnose a mesh: watertight? manifold? self-intersecting?");
  std::string check_input, against, check_report, check_deviation;
  check_cmd->add_option("input", check_input, "Mesh to check")->required();
  check_cmd->add_option("--against", against, "Reference mesh: also report the two-sided (Metro-style) distance");
  check_cmd->add_option("--report", check_report, "Write the diagnostics as JSON");
  check_cmd->add_option("--deviation", check_deviation,
                        "With --against: write the mesh with its signed distance to the reference per vertex and its "
                        "sliver and small-triangle flags per triangle (.vtp or .ply)");
  bool require_valid = false;
  check_cmd->add_flag("--require-valid", require_valid,
                      "Exit with code 4 unless the mesh is a valid closed surface (for scripts)");
  check_cmd->footer(
      "Examples:\n"
      "  vdbwrap check part.stl\n"
      "  vdbwrap check part_wrap.stl --against part.stl --report distances.json\n"
      "  vdbwrap check part_wrap.stl --require-valid && echo watertight");

  // repair
  auto* repair_cmd =
      app.add_subcommand("repair", "Repair the self-intersections of INPUT locally (no re-wrap) and write OUTPUT");
  repair_cmd->footer(
      "Examples:\n"
      "  vdbwrap repair part.stl -o part_fixed.stl --report repair.json\n"
      "  vdbwrap repair scan.ply -o scan_fixed.ply --max-deviation 0.2%\n"
      "Exit codes: 0 no intersections left; 4 intersections left (OUTPUT and the report are still written, the\n"
      "report lists the unfixed regions); 2 bad arguments; 3 unreadable or invalid input; 5 output not written.");
  std::string repair_input, repair_output, repair_report;
  cli::RepairOptions repair_options;
  bool repair_quiet = false;
  repair_cmd->add_option("input", repair_input, "Input mesh (.stl .obj .off .ply .vtp .nas .bdf)")->required();
  repair_options.add_to(repair_cmd, true);
  cli::StlOption repair_stl;
  repair_stl.add_to(repair_cmd);
  repair_cmd->add_option("-o,--output", repair_output, "Output mesh; the format follows the extension")
      ->required()
      ->group("Output");
  repair_cmd
      ->add_option("--report", repair_report, "Write a JSON report (regions, diagnostics before/after, deviation)")
      ->group("Output");
  repair_cmd->add_flag("-q,--quiet", repair_quiet, "No progress on stderr")->group("Output");

#ifdef VDBWRAP_WITH_REMOTE
  vdbwrap::remote::RemoteCommands remote(app);
#endif
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() != 0) {  // not --help or --version
      const std::string unknown = unknown_argument(app, argc, argv);
      if (!unknown.empty()) {
        std::fprintf(stderr, "vdbwrap: error: %s\n", unknown.c_str());
        return exit_code(ErrorKind::InvalidArgument);
      }
    }
    int code = app.exit(e);
    return code == 0 ? 0 : exit_code(ErrorKind::InvalidArgument);
  }

#ifdef VDBWRAP_WITH_REMOTE
  if (auto code = remote.run()) return *code;
#endif
  std::string current_file;
  try {
    if (*wrap_cmd) {
      WrapParams params = wrap_options.resolve();
      // Binary STL stores floats: validate what will be written.
      params.float_coordinates = io::format_from_extension(output) == io::Format::Stl;
      if (io::format_from_extension(output) == io::Format::Unknown)
        throw Error(ErrorKind::InvalidArgument,
                    output + ": unknown output format (use .stl, .obj, .off, .ply, .vtp, .nas or .bdf)");
      cli::check_output_path("-o", output);
      const io::WriteOptions write_options = wrap_stl.write_options(output);
      cli::check_output_path("--report", report_path);
      cli::check_output_path("--leak-path", leak_path);
      if (!features_path.empty()) {
        if (io::curve_format_from_extension(features_path) == io::CurveFormat::Unknown)
          throw Error(ErrorKind::InvalidArgument,
                      "--features " + features_path + ": feature curves are written as .obj or .eMesh");
        if (!params.snap_features)
          throw Error(ErrorKind::InvalidArgument, "--features: --no-features turns the feature curves off");
        cli::check_output_path("--features", features_path);
      }
      html_output.check();  // three.js too: exit 2 before the work
      check_deviation_path(deviation_path);
      cli::StderrProgress progress(quiet, cli::wrap_stage_weights());
      progress.progress("read", 0.0, input);
      Mesh mesh = read_input(input, &progress);
      progress.progress("read", 1.0, std::to_string(mesh.triangles.size()) + " triangles");
      const WrapReport::Source source = source_of(input, mesh);
      WrapResult result;
      try {
        result = wrap(mesh, params, &progress);
      } catch (const WrapFailure& failure) {
        // The report is written even when the run stops (a leak, a failed validation).
        if (!report_path.empty()) {
          WrapReport report = failure.report();
          report.source = source;
          write_text(report_path, to_json(report));
        }
        const LeakReport& leak = failure.report().leak;
        progress.finish();  // the messages below start on a line of their own
        if (leak.detected) {
          if (!leak_path.empty()) write_text(leak_path, leak_to_obj(leak));
          std::fprintf(stderr, "vdbwrap: %s\n", leak.description.c_str());
          std::fprintf(stderr, "vdbwrap: narrowest passage at (%.6g, %.6g, %.6g), about %.4g wide%s%s\n",
                       leak.location[0], leak.location[1], leak.location[2], leak.width,
                       leak_path.empty() ? "" : "; path in ", leak_path.c_str());
        }
        if (html_output.wanted()) {  // the page shows the input and the leak
          WrapReport report = failure.report();
          report.source = source;
          const std::string page = html_output.write(mesh, nullptr, to_json(report), nullptr, source.file_name);
          if (!quiet) std::fprintf(stderr, "vdbwrap: wrote %s\n", page.c_str());
        }
        throw;
      }
      progress.progress("write", 0.0, output);
      io::write_mesh(result.surface, output, write_options);
      if (!features_path.empty()) io::write_feature_curves(features_path, result.feature_curves);
      result.report.source = source;
      if (!report_path.empty()) write_text(report_path, to_json(result.report));
      // The deviation field, measured once for the file and the page.
      DeviationField deviation;
      if (!deviation_path.empty() || html_output.wanted()) {
        progress.progress("deviation", 0.0, deviation_path.empty() ? html_output.path() : deviation_path);
        deviation = measure_deviation(result.surface, mesh, &result.triangle_flags);
      }
      if (!deviation_path.empty()) write_deviation(deviation_path, result.surface, deviation);
      progress.complete(output);
      if (html_output.wanted()) {
        const std::string page =
            html_output.write(mesh, &result.surface, to_json(result.report), &deviation, source.file_name);
        if (!quiet) std::fprintf(stderr, "wrote %s\n", page.c_str());
      }
      const auto& r = result.report;
      // Without samples (--no-distances) there is no distance to print: zeros would read as a
      // perfect fit.
      char distances[256] = "distances not sampled (--no-distances)";
      if (r.output_to_input.samples > 0)
        std::snprintf(distances, sizeof distances,
                      "distance to input mean %s, p95 %s of the diagonal, max %.6g at (%.6g, %.6g, %.6g)",
                      percent(r.output_to_input.mean, r.diagonal).c_str(),
                      percent(r.output_to_input.p95, r.diagonal).c_str(), r.output_to_input.max,
                      r.output_to_input.max_at[0], r.output_to_input.max_at[1], r.output_to_input.max_at[2]);
      if (!quiet)
        std::fprintf(stderr,
                     "wrote %s: %zu triangles, closed, manifold, outward, no self-intersections; %s; %.2fs%s%s%s%s\n",
                     output.c_str(), result.surface.triangles.size(), distances, r.total_seconds,
                     report_path.empty() ? "" : "; report ", report_path.c_str(),
                     deviation_path.empty() ? "" : "; deviation field ", deviation_path.c_str());
      return 0;
    }
    if (*repair_cmd) {
      RepairParams rparams = repair_options.resolve();
      // Binary STL stores floats: repair what will be written.
      rparams.float_coordinates = io::format_from_extension(repair_output) == io::Format::Stl;
      if (io::format_from_extension(repair_output) == io::Format::Unknown)
        throw Error(ErrorKind::InvalidArgument,
                    repair_output + ": unknown output format (use .stl, .obj, .off, .ply, .vtp, .nas or .bdf)");
      cli::check_output_path("-o", repair_output);
      const io::WriteOptions repair_write_options = repair_stl.write_options(repair_output);
      cli::check_output_path("--report", repair_report);
      cli::StderrProgress progress(repair_quiet, cli::repair_stage_weights());
      progress.progress("read", 0.0, repair_input);
      Mesh mesh = read_input(repair_input, &progress);
      RepairResult result = repair(mesh, rparams, &progress);
      progress.progress("write", 0.0, repair_output);
      io::write_mesh(result.mesh, repair_output, repair_write_options);
      if (!repair_report.empty())
        write_text(repair_report, with_source(to_json(result.report), source_of(repair_input, mesh)));
      progress.complete(repair_output);
      print_repair_report(repair_output, result.report);
      return result.report.all_fixed() ? 0 : exit_code(ErrorKind::WrapFailed);
    }
    if (*check_cmd) {
      cli::check_output_path("--report", check_report);
      if (!check_deviation.empty() && against.empty())
        throw Error(ErrorKind::InvalidArgument,
                    "--deviation needs --against REFERENCE (the distances are to the reference)");
      check_deviation_path(check_deviation);
      Mesh mesh = read_input(check_input);
      MeshDiagnostics d = diagnose(mesh, true);
      print_diagnostics(check_input, d);
      std::string json = "{\"diagnostics\": " + to_json(d);
      if (!against.empty()) {
        Mesh ref = read_input(against);
        DistanceStats ab = sampled_distance(mesh, ref), ba = sampled_distance(ref, mesh);
        double diag = ab.diagonal;
        std::printf("distance to %s (percent of its diagonal %.6g):\n", against.c_str(), diag);
        std::printf("  mesh -> reference: mean %s, p95 %s, max %s at (%.6g, %.6g, %.6g)\n",
                    percent(ab.mean, diag).c_str(), percent(ab.p95, diag).c_str(), percent(ab.max, diag).c_str(),
                    ab.max_at[0], ab.max_at[1], ab.max_at[2]);
        std::printf("  reference -> mesh: mean %s, p95 %s, max %s at (%.6g, %.6g, %.6g)\n",
                    percent(ba.mean, diag).c_str(), percent(ba.p95, diag).c_str(), percent(ba.max, diag).c_str(),
                    ba.max_at[0], ba.max_at[1], ba.max_at[2]);
        std::printf("  two-sided (Hausdorff) max %s\n", percent(std::max(ab.max, ba.max), diag).c_str());
        // How well the mesh keeps the reference's sharp edges (samples every 0.1 % of the diagonal).
        DistanceStats edges = sharp_edge_distance(ref, mesh);
        if (edges.samples > 0)
          std::printf("  reference's sharp edges -> mesh: mean %s, p95 %s, max %s (%zu samples)\n",
                      percent(edges.mean, diag).c_str(), percent(edges.p95, diag).c_str(),
                      percent(edges.max, diag).c_str(), edges.samples);
        json += ", \"to_reference\": " + to_json(ab) + ", \"from_reference\": " + to_json(ba) +
                ", \"sharp_edges_from_reference\": " + to_json(edges);
        if (!check_deviation.empty()) {
          const DeviationField field = measure_deviation(mesh, ref);
          write_deviation(check_deviation, mesh, field);
          const Vec3& at = field.max_at;
          std::printf("  deviation field (per vertex, %s): max %.6g (%s) at (%.6g, %.6g, %.6g) -> %s\n",
                      field.sign == DistanceSign::Outside     ? "signed, + outside the reference"
                      : field.sign == DistanceSign::FrontSide ? "signed, + on the side the reference faces"
                                                              : "unsigned: the reference's orientation is inconsistent",
                      field.max_abs, percent(field.max_abs, diag).c_str(), at[0], at[1], at[2],
                      check_deviation.c_str());
        }
      }
      json += "}";
      if (!check_report.empty()) write_text(check_report, with_source(json, source_of(check_input, mesh)));
      if (require_valid && !d.valid_closed_surface()) return exit_code(ErrorKind::WrapFailed);
      return 0;
    }
  } catch (const Error& e) {
    std::fprintf(stderr, "vdbwrap: error: %s\n", e.what());
    return exit_code(e.kind());
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "vdbwrap: error: out of memory\n");
    return exit_code(ErrorKind::Internal);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vdbwrap: internal error: %s\n", e.what());
    return exit_code(ErrorKind::Internal);
  }
  return 0;
}
