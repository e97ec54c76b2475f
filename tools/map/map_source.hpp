#pragma once
// Where a map comes from for the map tools (pex-map, pex-render-map): the MAP
// messages of an LCM log, the next MAP on the bus, or a saved map file.
#include <chrono>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <pex/polygon_map_t.hpp>

namespace pex::map_files {

struct LogMaps {
  std::optional<pex::polygon_map_t> last;  // the last decodable MAP
  std::vector<std::pair<double, double>> robot_path;  // each MAP's robot position, repeats dropped
  long rejected = 0;                        // messages on the channel that did not decode
};

// Every message on `channel` of the LCM log at `path`. Throws std::runtime_error
// if the log cannot be opened.
LogMaps read_log_maps(const std::string& path, const std::string& channel);

// fn(message) for every message on `channel` of the LCM log at `path` that
// decodes, in the log's order; returns how many did not. Throws
// std::runtime_error if the log cannot be opened.
long for_each_log_map(const std::string& path, const std::string& channel,
                      const std::function<void(pex::polygon_map_t&&)>& fn);

// The next message on `channel` of the bus at `lcm_url` ("" = LCM's default),
// waiting at most `timeout`; nullopt if none came. Throws std::runtime_error if
// LCM cannot be opened.
std::optional<pex::polygon_map_t> next_bus_map(const std::string& lcm_url, const std::string& channel,
                                                std::chrono::milliseconds timeout);

// A saved map file (GeoJSON, map_files.hpp). Throws MapFileError for bad
// content (exit 65 in the tools), std::runtime_error naming the file and why
// if it cannot be read (exit 66).
pex::polygon_map_t read_map_file(const std::string& path);

// For the tools: the map of `map_file` if given, else the last `channel`
// message of the log `log`, with the robot's path. 0 on success; else prints
// "<program>: why" to stderr and returns the exit code: 65 (EX_DATAERR) for a
// bad map file or a log without the channel, 66 (EX_NOINPUT) for a file that
// cannot be read.
int load_map(const std::string& program, const std::string& map_file, const std::string& log,
             const std::string& channel, LogMaps& out);

}  // namespace pex::map_files
