#include "explorer_node.hpp"

#include <cmath>

namespace pex::explorer {

ExplorerNode::ExplorerNode(ExplorerOptions options)
    : options_(std::move(options)), mission_(options_.mission) {}

std::string ExplorerNode::on_map(const pex::polygon_map_t& msg, std::int64_t now_utime) {
  DecodedMap decoded = decode_map(msg, options_.map);
  if (!decoded.ok) return decoded.error;
  counters_.maps_accepted++;
  counters_.map_polygons_dropped += decoded.polygons_dropped;
  counters_.map_rings_reoriented += decoded.rings_reoriented;
  mission_.on_map(std::move(decoded.polygons), now_utime);
  return {};
}

std::string ExplorerNode::on_pose(const pex::pose_t& msg, std::int64_t now_utime) {
  if (!std::isfinite(msg.x) || !std::isfinite(msg.y) || !std::isfinite(msg.theta)) return "non-finite pose";
  mission_.on_pose(planning::Pose2{msg.x, msg.y, msg.theta}, now_utime);
  return {};
}

pex::velocity_cmd_t ExplorerNode::step(std::int64_t now_utime) {
  const std::size_t visited_before = mission_.visited_goals().size();
  const std::size_t blacklisted_before = mission_.blacklist().size();
  last_ = mission_.step(now_utime);
  if (last_.planned) counters_.plans++;
  const std::size_t reached = mission_.visited_goals().size() - visited_before;
  counters_.goals_reached += static_cast<std::int64_t>(reached);
  counters_.goals_given_up += static_cast<std::int64_t>(mission_.blacklist().size() - blacklisted_before - reached);
  pex::velocity_cmd_t cmd = stop_command(now_utime);
  cmd.v = last_.command.v_mps;
  cmd.omega = last_.command.omega_radps;
  return cmd;
}

pex::velocity_cmd_t ExplorerNode::stop_command(std::int64_t now_utime) {
  pex::velocity_cmd_t cmd{};
  cmd.utime = now_utime;
  cmd.v = 0.0;
  cmd.omega = 0.0;
  cmd.source = "explorer";
  return cmd;
}

pex::explore_state_t ExplorerNode::state_message(std::int64_t now_utime) const {
  pex::explore_state_t s{};
  s.utime = now_utime;
  s.phase = static_cast<std::int8_t>(last_.phase);
  s.status = last_.degraded ? "DEGRADED: " + last_.status : last_.status;
  if (last_.goal) {
    s.goal_x = last_.goal->x();
    s.goal_y = last_.goal->y();
  }
  s.goal_candidates = last_.goal_candidates;
  for (const auto& p : last_.path) {
    s.path_x.push_back(p.x());
    s.path_y.push_back(p.y());
  }
  s.npath = static_cast<std::int32_t>(s.path_x.size());
  s.explored_area_m2 = last_.explored_area_m2;
  s.distance_travelled_m = last_.distance_travelled_m;
  return s;
}

}  // namespace pex::explorer
