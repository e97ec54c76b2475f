#include "viewer_options.hpp"

#include <arpa/inet.h>

#include <cstdint>
#include <optional>

#include "runtime/config.hpp"

namespace pex::viewer {

using runtime::in_range;
using runtime::positive;

ViewerOptions load_options(runtime::ConfigReader& config) {
  ViewerOptions o;
  o.bind_address = config.get<std::string>(
      "bind_address", o.bind_address, [](const std::string& a) -> std::optional<std::string> {
        in_addr addr{};
        if (::inet_pton(AF_INET, a.c_str(), &addr) == 1) return std::nullopt;
        return "must be an IPv4 address (127.0.0.1: this computer only)";
      });
  o.port = config.get<int>("port", o.port, in_range(1, 65535));
  o.update_rate_hz = config.get<double>("update_rate_hz", o.update_rate_hz, in_range(5.0, 50.0));
  o.pose_channel = config.get<std::string>(
      "pose_channel", o.pose_channel, runtime::registered_channel_of_type("pex.pose_t", "SLAM_POSE or SIM_TRUTH"));
  o.input_timeout_s = config.get<double>("input_timeout_s", o.input_timeout_s, in_range(0.1, 600.0));
  o.max_clients = config.get<int>("max_clients", o.max_clients, in_range(1, 64));
  auto& s = o.state;
  s.max_map_vertices = config.get<std::int64_t>("max_map_vertices", s.max_map_vertices, positive<std::int64_t>());
  s.trajectory_min_step_m =
      config.get<double>("trajectory_min_step_m", s.trajectory_min_step_m, in_range(0.001, 10.0));
  s.max_trajectory_points =
      config.get<int>("max_trajectory_points", s.max_trajectory_points, in_range(10, 1'000'000));
  s.max_scan_points = config.get<int>("max_scan_points", s.max_scan_points, in_range(10, 100'000));
  s.status_stale_s = config.get<double>("status_stale_s", s.status_stale_s, in_range(0.5, 600.0));
  return o;
}

}  // namespace pex::viewer
