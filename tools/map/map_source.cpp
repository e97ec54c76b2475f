#include "map_source.hpp"

#include <sysexits.h>

#include <cstdio>
#include <stdexcept>

#include <lcm/lcm-cpp.hpp>

#include "map_files.hpp"
#include "runtime/files.hpp"

namespace pex::map_files {

long for_each_log_map(const std::string& path, const std::string& channel,
                      const std::function<void(pex::polygon_map_t&&)>& fn) {
  lcm::LogFile log(path, "r");
  if (!log.good()) throw std::runtime_error("cannot read " + path);
  long rejected = 0;
  for (const lcm::LogEvent* event = log.readNextEvent(); event; event = log.readNextEvent()) {
    if (event->channel != channel) continue;
    pex::polygon_map_t msg{};
    if (msg.decode(event->data, 0, event->datalen) != event->datalen) {
      ++rejected;
      continue;
    }
    fn(std::move(msg));
  }
  return rejected;
}

LogMaps read_log_maps(const std::string& path, const std::string& channel) {
  LogMaps out;
  out.rejected = for_each_log_map(path, channel, [&](pex::polygon_map_t&& msg) {
    if (out.robot_path.empty() || out.robot_path.back() != std::make_pair(msg.robot_x, msg.robot_y))
      out.robot_path.emplace_back(msg.robot_x, msg.robot_y);
    out.last = std::move(msg);
  });
  return out;
}

std::optional<pex::polygon_map_t> next_bus_map(const std::string& lcm_url, const std::string& channel,
                                                std::chrono::milliseconds timeout) {
  lcm::LCM lcm(lcm_url);
  if (!lcm.good()) throw std::runtime_error("cannot open LCM at '" + lcm_url + "'");
  std::optional<pex::polygon_map_t> got;
  auto* sub = lcm.subscribeFunction(
      channel,
      +[](const lcm::ReceiveBuffer* rb, const std::string&, std::optional<pex::polygon_map_t>* out) {
        pex::polygon_map_t msg{};
        if (msg.decode(rb->data, 0, static_cast<int>(rb->data_size)) == static_cast<int>(rb->data_size))
          *out = std::move(msg);
      },
      &got);
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (!got) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(end - std::chrono::steady_clock::now());
    if (left.count() <= 0) break;
    lcm.handleTimeout(static_cast<int>(std::min<long>(left.count(), 100)));
  }
  lcm.unsubscribe(sub);
  return got;
}

pex::polygon_map_t read_map_file(const std::string& path) {
  std::string why;
  const auto text = runtime::read_whole_file(path, &why);
  if (!text) throw std::runtime_error("cannot read " + path + ": " + why);
  try {
    return from_geojson(*text);
  } catch (const MapFileError& e) {
    throw MapFileError(path + ": " + e.what());
  }
}

int load_map(const std::string& program, const std::string& map_file, const std::string& log,
             const std::string& channel, LogMaps& out) {
  try {
    if (!map_file.empty()) {
      out.last = read_map_file(map_file);
      out.robot_path = {{out.last->robot_x, out.last->robot_y}};
      return 0;
    }
    out = read_log_maps(log, channel);
  } catch (const MapFileError& e) {
    std::fprintf(stderr, "%s: %s\n", program.c_str(), e.what());
    return EX_DATAERR;
  } catch (const std::runtime_error& e) {
    std::fprintf(stderr, "%s: %s\n", program.c_str(), e.what());
    return EX_NOINPUT;
  }
  if (!out.last) {
    std::fprintf(stderr, "%s: no decodable %s message in %s (%ld rejected)\n", program.c_str(), channel.c_str(),
                 log.c_str(), out.rejected);
    return EX_DATAERR;
  }
  return 0;
}

}  // namespace pex::map_files
