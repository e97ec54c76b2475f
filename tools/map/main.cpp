// pex-map: map files from the polygonal map (docs/map_files.md).
//   pex-map save OUT.geojson [--log IN.lcm]             the current MAP (next on the bus, or a log's last) as GeoJSON
//   pex-map export --pgm OUT.pgm [--resolution-m 0.05]  a ROS map_server grid (OUT.pgm + OUT.yaml)
//                  [--map IN.geojson | --log IN.lcm]    ... of a saved map, a log's last MAP, or the bus's next
//   pex-map check [--log IN.lcm | --map IN.geojson]     the geometry of every MAP of a log (or of a map file,
//                                                       or the bus's next) checked: valid, by OGC's rules
// Exit codes: 0 written (or every map checked valid); 64 bad command line; 65 no
// MAP in the log, a bad map file, or a map checked not valid; 66 an input cannot
// be opened; 69 no MAP on the bus in time; 73 an output cannot be written.
#include <sysexits.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>

#include <CLI/CLI.hpp>

#include "cli/command_line.hpp"
#include "map_files.hpp"
#include "map_source.hpp"
#include "runtime/channels.hpp"
#include "runtime/files.hpp"

namespace {

struct Source {
  std::string map_file, log, channel{pex::runtime::channels::kMap}, lcm_url;
  double timeout_s = 10.0;
};

// Prints why and returns the exit code when the map cannot be had.
int load(const Source& src, pex::polygon_map_t& out) {
  if (!src.map_file.empty() || !src.log.empty()) {
    pex::map_files::LogMaps maps;
    if (int rc = pex::map_files::load_map("pex-map", src.map_file, src.log, src.channel, maps); rc != 0) return rc;
    out = std::move(*maps.last);
    return 0;
  }
  std::optional<pex::polygon_map_t> map;
  try {
    map = pex::map_files::next_bus_map(src.lcm_url, src.channel,
                                       std::chrono::milliseconds(static_cast<long>(src.timeout_s * 1000)));
  } catch (const std::runtime_error& e) {
    std::fprintf(stderr, "pex-map: %s\n", e.what());
    return EX_UNAVAILABLE;
  }
  if (!map) {
    std::fprintf(stderr, "pex-map: no %s on the bus within %.1f s: is pex-polygon-mapper running?\n",
                 src.channel.c_str(), src.timeout_s);
    return EX_UNAVAILABLE;
  }
  out = std::move(*map);
  return 0;
}

int write(const std::string& path, const std::string& bytes) {
  if (auto why = pex::runtime::write_file_atomically(path, bytes); !why.empty()) {
    std::fprintf(stderr, "pex-map: cannot write %s: %s\n", path.c_str(), why.c_str());
    return EX_CANTCREAT;
  }
  return 0;
}

// Every map of the source checked (geometry_problem); prints the first few
// that are not valid and a summary line.
int check(const Source& src) {
  constexpr long kShown = 5;
  long checked = 0, invalid = 0, rejected = 0;
  auto check_one = [&](const pex::polygon_map_t& map) {
    ++checked;
    if (const auto why = pex::map_files::geometry_problem(map); !why.empty() && ++invalid <= kShown)
      std::printf("not valid: %s #%ld (utime %lld, particle %d, %d rings): %s\n", src.channel.c_str(), checked,
                  static_cast<long long>(map.utime), map.particle, map.nrings, why.c_str());
  };
  if (!src.log.empty()) {
    try {
      rejected = pex::map_files::for_each_log_map(src.log, src.channel, check_one);
    } catch (const std::runtime_error& e) {
      std::fprintf(stderr, "pex-map: %s\n", e.what());
      return EX_NOINPUT;
    }
    if (checked == 0) {
      std::fprintf(stderr, "pex-map: no decodable %s message in %s (%ld rejected)\n", src.channel.c_str(),
                   src.log.c_str(), rejected);
      return EX_DATAERR;
    }
  } else {
    pex::polygon_map_t map{};
    if (int rc = load(src, map); rc != 0) return rc;
    check_one(map);
  }
  std::printf("checked %ld %s message%s: %ld not valid, %ld undecodable\n", checked, src.channel.c_str(),
              checked == 1 ? "" : "s", invalid, rejected);
  return invalid > 0 || rejected > 0 ? EX_DATAERR : 0;
}

void add_source_options(CLI::App& cmd, Source& src, bool with_map_file,
                        const std::string& log_help = "read the last MAP of this LCM log (default: the next MAP on the bus)") {
  auto* log = cmd.add_option("--log", src.log, log_help);
  if (with_map_file)
    cmd.add_option("--map", src.map_file, "read a saved map file (GeoJSON, from pex-map save)")->excludes(log);
  cmd.add_option("--channel", src.channel, "channel of the pex.polygon_map_t messages");
  cmd.add_option("--lcm-url", src.lcm_url, "LCM URL for the bus (default: $LCM_DEFAULT_URL or LCM's)");
  cmd.add_option("--timeout-s", src.timeout_s, "seconds to wait for a MAP on the bus")->check(CLI::PositiveNumber);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Save the polygonal map to a file (GeoJSON), export it as a ROS occupancy grid (PGM + YAML), or check it",
               "pex-map"};
  app.require_subcommand(1);
  Source save_src, export_src;
  std::string save_out, pgm_out;
  double resolution_m = 0.05, margin_m = 0.5;
  auto* save = app.add_subcommand("save", "write the map as GeoJSON (docs/map_files.md)");
  save->add_option("output", save_out, "the GeoJSON file to write")->required();
  add_source_options(*save, save_src, false);
  auto* exp = app.add_subcommand("export", "write the map as a ROS map_server occupancy grid");
  exp->add_option("--pgm", pgm_out, "the PGM to write; the YAML goes beside it (.yaml)")->required();
  exp->add_option("--resolution-m", resolution_m, "cell side, m")->check(CLI::Range(0.001, 10.0));
  exp->add_option("--margin-m", margin_m, "unknown space around the map, m")->check(CLI::Range(0.0, 100.0));
  add_source_options(*exp, export_src, true);
  Source check_src;
  auto* chk = app.add_subcommand("check", "check that the map's geometry is valid (exit 65 if not)");
  add_source_options(*chk, check_src, true, "check every MAP of this LCM log (default: the next MAP on the bus)");
  if (const auto code = pex::cli::parse_command_line(app, "pex-map", argc, argv)) return *code;

  if (chk->parsed()) return check(check_src);

  pex::polygon_map_t map{};
  if (save->parsed()) {
    if (int rc = load(save_src, map); rc != 0) return rc;
    std::string text;
    try {
      text = pex::map_files::to_geojson(map);
    } catch (const pex::map_files::MapFileError& e) {
      std::fprintf(stderr, "pex-map: %s\n", e.what());
      return EX_DATAERR;
    }
    if (int rc = write(save_out, text); rc != 0) return rc;
    std::printf("saved %d rings, %d vertices, %.1f m2 free to %s\n", map.nrings, map.vertex_count, map.free_area_m2,
                save_out.c_str());
    return 0;
  }
  if (int rc = load(export_src, map); rc != 0) return rc;
  pex::map_files::OccupancyGrid grid;
  try {
    grid = pex::map_files::rasterise(map, resolution_m, margin_m);
  } catch (const pex::map_files::MapFileError& e) {
    std::fprintf(stderr, "pex-map: %s\n", e.what());
    return EX_DATAERR;
  }
  const std::filesystem::path pgm(pgm_out);
  const std::string yaml_out = std::filesystem::path(pgm).replace_extension(".yaml").string();
  if (int rc = write(pgm_out, pex::map_files::to_pgm(grid)); rc != 0) return rc;
  if (int rc = write(yaml_out, pex::map_files::to_yaml(grid, pgm.filename().string())); rc != 0) return rc;
  std::printf("exported %d x %d cells of %.3f m to %s and %s\n", grid.width, grid.height, grid.resolution_m,
              pgm_out.c_str(), yaml_out.c_str());
  return 0;
}
