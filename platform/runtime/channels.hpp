#pragma once
// The one channel registry: every daemon, liveness check and test takes channel
// names from here (openpilot's cereal/services.py idea). docs/channels.md
// documents it; channels_test.cpp checks the two agree.
#include <array>
#include <string_view>

namespace pex::runtime::channels {

inline constexpr std::string_view kLidarScan = "LIDAR_SCAN";
inline constexpr std::string_view kOdometry = "ODOMETRY";
inline constexpr std::string_view kBaseCmd = "BASE_CMD";
inline constexpr std::string_view kSlamUpdate = "SLAM_UPDATE";
inline constexpr std::string_view kSlamPose = "SLAM_POSE";
inline constexpr std::string_view kMap = "MAP";
inline constexpr std::string_view kMapFree = "MAP_FREE";
inline constexpr std::string_view kExploreState = "EXPLORE_STATE";
inline constexpr std::string_view kDaemonStatus = "DAEMON_STATUS";
inline constexpr std::string_view kSimTruth = "SIM_TRUTH";
inline constexpr std::string_view kSimClock = "SIM_CLOCK";
inline constexpr std::string_view kMissionCmd = "MISSION_CMD";
inline constexpr std::string_view kSimFault = "SIM_FAULT";
inline constexpr std::string_view kKeepOut = "KEEP_OUT";

struct ChannelInfo {
  std::string_view name;
  std::string_view type;        // LCM type, package pex
  double expected_rate_hz;      // nominal publication rate; 0 = event-driven
  bool logged;                  // recorded by the capture unit (lcm-logger)
  std::string_view publisher;   // daemon that publishes it
};

inline constexpr std::array<ChannelInfo, 14> kRegistry{{
    {kLidarScan, "pex.laser_scan_t", 25.0, true, "lidar_reader"},
    {kOdometry, "pex.odometry_t", 50.0, true, "base_driver"},
    {kBaseCmd, "pex.velocity_cmd_t", 10.0, true, "explorer"},
    {kSlamUpdate, "pex.slam_update_t", 0.0, true, "slam"},
    {kSlamPose, "pex.pose_t", 50.0, true, "slam"},
    {kMap, "pex.polygon_map_t", 1.0, true, "polygon_mapper"},
    {kMapFree, "pex.polygon_map_t", 1.0, true, "polygon_mapper"},
    {kExploreState, "pex.explore_state_t", 2.0, true, "explorer"},
    {kDaemonStatus, "pex.daemon_status_t", 1.0, true, "every daemon"},
    {kSimTruth, "pex.pose_t", 50.0, true, "sim"},
    {kSimClock, "pex.sim_clock_t", 100.0, true, "sim"},
    {kMissionCmd, "pex.mission_cmd_t", 0.0, true, "pex-mission"},
    {kSimFault, "pex.sim_fault_t", 0.0, true, "tests, drills"},
    // Last: the lcm_message fuzz target picks a channel by index.
    {kKeepOut, "pex.polygon_map_t", 0.2, true, "explorer"},
}};

// nullptr if the name is not registered.
constexpr const ChannelInfo* find(std::string_view name) {
  for (const auto& c : kRegistry)
    if (c.name == name) return &c;
  return nullptr;
}

}  // namespace pex::runtime::channels
