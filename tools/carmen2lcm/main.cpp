// pex-carmen2lcm IN.clf OUT.lcm: a CARMEN log (FLASER, ROBOTLASER1, ODOM) as an
// LCM log of our types, so lcm-logplayer replays real data into the daemon set
// and `pex-slam --log` runs on it.
//
// Odometry: by default every laser line's own odometry pose becomes an ODOMETRY
// message with the scan's time stamp, written just before its LIDAR_SCAN. Those
// poses were taken by the robot for exactly that scan, while ODOM lines come at
// their own rate with IPC time stamps that in the benchmark logs sometimes run
// backwards (the Intel log's do, by up to 0.6 s). `--odometry odom` writes the
// ODOM lines instead (a log without ODOM lines always uses the laser lines').
//
// Direction: some logs (FR079) integrate the ODOM lines' speed without its sign,
// so driving backwards advances the poses. By default the odometry is rebuilt
// with those steps turned round where the ODOM lines' `tv` says the robot went
// backwards (evaluation::correct_odometry_direction; a log whose poses agree
// with its speeds, or without ODOM lines, is written unchanged). `--raw-odometry`
// writes the poses as logged.
//
// Time: message utime fields are the lines' ipc_timestamp (µs); the log events'
// time stamps are the same but never decrease (lcm-logplayer paces by them).
//
// Laps: `--laps N` writes the log driven N times, alternately forwards and back
// along the same path (evaluation::lap_log; laser lines' odometry only): a long
// run of real data, to measure SLAM's memory over run length (docs/slam.md).
#include <CLI/CLI.hpp>
#include <sysexits.h>  // EX_USAGE 64, EX_DATAERR 65, EX_NOINPUT 66, EX_UNAVAILABLE 69, EX_CANTCREAT 73, EX_CONFIG 78

#include <lcm/lcm-cpp.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <pex/laser_scan_t.hpp>
#include <pex/odometry_t.hpp>

#include "cli/command_line.hpp"
#include "evaluation/carmen_log.hpp"
#include "evaluation/laps.hpp"
#include "evaluation/odometry_direction.hpp"
#include "runtime/channels.hpp"

namespace {

namespace ch = pex::runtime::channels;
namespace ev = pex::evaluation;

std::int64_t to_utime(double seconds) { return static_cast<std::int64_t>(std::llround(seconds * 1e6)); }

class LogWriter {
 public:
  explicit LogWriter(const std::string& path) : log_(path, "w") {}
  bool good() { return log_.good(); }

  template <class Msg>
  bool write(std::string_view channel, std::int64_t utime, const Msg& msg) {
    std::vector<std::uint8_t> buffer(static_cast<std::size_t>(msg.getEncodedSize()));
    if (msg.encode(buffer.data(), 0, static_cast<int>(buffer.size())) < 0) return false;
    lcm::LogEvent event{};
    last_utime_ = std::max(last_utime_, utime);
    event.timestamp = last_utime_;
    event.channel = std::string(channel);
    event.datalen = static_cast<std::int32_t>(buffer.size());
    event.data = buffer.data();
    ++events_;
    return log_.writeEvent(&event) == 0;
  }
  std::int64_t events() const { return events_; }

 private:
  lcm::LogFile log_;
  std::int64_t last_utime_ = 0;
  std::int64_t events_ = 0;
};

pex::odometry_t odometry_message(std::int64_t utime, const pex::geometry::Pose2& pose, double v, double omega) {
  pex::odometry_t msg{};
  msg.utime = utime;
  msg.x = pose.x_m;
  msg.y = pose.y_m;
  msg.theta = pex::geometry::wrap_angle(pose.theta_rad);
  msg.v = v;
  msg.omega = omega;
  return msg;
}

// The laser's mounting in the robot frame. CARMEN writes a laser line's laser
// pose as the robot's odometry pose composed with the mounting offset, so their
// difference is the offset; where it is implausible for a front laser (some
// logs write a corrected pose there) the PARAM robot_frontlaser_offset is used.
pex::geometry::Pose2 sensor_mounting(const ev::CarmenLaser& laser, double frontlaser_offset_m) {
  const pex::geometry::Pose2 offset = pex::geometry::relative(laser.odometry, laser.laser_pose);
  // (+ 0.0 turns the -0.0 of an exactly zero offset into +0.0.)
  if (std::hypot(offset.x_m, offset.y_m) <= 1.0 && std::abs(offset.theta_rad) <= 0.2)
    return {offset.x_m + 0.0, offset.y_m + 0.0, offset.theta_rad + 0.0};
  return {frontlaser_offset_m, 0.0, 0.0};
}

pex::laser_scan_t scan_message(const ev::CarmenLaser& laser, std::int32_t counter, const pex::geometry::Pose2& sensor) {
  pex::laser_scan_t msg{};
  msg.utime = to_utime(laser.timestamp_s);
  msg.device_utime = 0;
  msg.scan_counter = counter;
  msg.angle_min = static_cast<float>(laser.angle_min_rad);
  msg.angle_increment = static_cast<float>(laser.angle_increment_rad);
  msg.range_min = 0.0f;
  msg.range_max = static_cast<float>(laser.max_range_m);
  msg.scan_time = 0.0f;
  msg.sensor_x = static_cast<float>(sensor.x_m);
  msg.sensor_y = static_cast<float>(sensor.y_m);
  msg.sensor_theta = static_cast<float>(sensor.theta_rad);
  msg.nranges = static_cast<std::int32_t>(laser.ranges_m.size());
  msg.ranges = laser.ranges_m;
  msg.nintensities = 0;
  return msg;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"CARMEN log (FLASER, ROBOTLASER1, ODOM) -> LCM log (LIDAR_SCAN, ODOMETRY)"};
  std::string in_path;
  std::string out_path;
  std::string odometry_source = "laser";
  ev::CarmenParseOptions parse;
  app.add_option("IN", in_path, "CARMEN log (.clf / .log)")->required();
  app.add_option("OUT", out_path, "LCM log to write")->required();
  app.add_option("--odometry", odometry_source, "odometry from the laser lines' poses or the ODOM lines")
      ->check(CLI::IsMember({"laser", "odom"}))
      ->capture_default_str();
  bool raw_odometry = false;
  app.add_flag("--raw-odometry", raw_odometry,
               "odometry poses as logged (no reversal of steps the ODOM lines' speed says went backwards)");
  app.add_option("--flaser-max-range-m", parse.flaser_max_range_m,
                 "FLASER readings at or beyond this are no return")
      ->capture_default_str();
  int laps = 1;
  double lap_gap_s = 1.0;
  app.add_option("--laps", laps, "drive the log this many times, alternately forwards and backwards (laser lines' odometry)")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  app.add_option("--lap-gap-s", lap_gap_s, "time between the end of a pass and the start of the next")
      ->check(CLI::Range(0.0, 3600.0))
      ->capture_default_str();
  if (const auto code = pex::cli::parse_command_line(app, "pex-carmen2lcm", argc, argv)) return *code;

  std::ifstream in(in_path);
  if (!in) {
    std::fprintf(stderr, "pex-carmen2lcm: cannot open %s\n", in_path.c_str());
    return EX_NOINPUT;
  }
  // First pass: does the log have ODOM lines, and where is the front laser.
  bool has_odom = false;
  double frontlaser_offset_m = 0.0;
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("ODOM ", 0) == 0) has_odom = true;
    if (line.rfind("PARAM robot_frontlaser_offset ", 0) == 0) {
      std::istringstream fields(line.substr(30));
      double offset = 0.0;
      if (fields >> offset && std::isfinite(offset)) frontlaser_offset_m = offset;
    }
  }
  const bool odometry_from_laser = odometry_source == "laser" || !has_odom;
  if (laps > 1 && !odometry_from_laser) {
    std::fprintf(stderr, "pex-carmen2lcm: --laps needs the laser lines' odometry (not --odometry odom)\n");
    return EX_USAGE;
  }
  in.clear();
  in.seekg(0);

  LogWriter out(out_path);
  if (!out.good()) {
    std::fprintf(stderr, "pex-carmen2lcm: cannot write %s\n", out_path.c_str());
    return EX_CANTCREAT;
  }
  // Parse every line first: the direction of the odometry is decided over the whole log.
  ev::CarmenLog log;
  std::size_t line_number = 0;
  std::string error;
  ev::CarmenMessage message;
  while (std::getline(in, line)) {
    ++line_number;
    const ev::LineKind kind = ev::parse_carmen_line(line, parse, message, error);
    if (kind == ev::LineKind::kSkipped) continue;
    if (kind == ev::LineKind::kMalformed) {
      if (log.malformed_lines++ < 5) std::fprintf(stderr, "pex-carmen2lcm: line %zu: %s\n", line_number, error.c_str());
      continue;
    }
    if (auto* laser = std::get_if<ev::CarmenLaser>(&message)) {
      log.order.push_back({true, log.lasers.size()});
      log.lasers.push_back(std::move(*laser));
    } else {
      log.order.push_back({false, log.odometry.size()});
      log.odometry.push_back(std::get<ev::CarmenOdometry>(message));
    }
  }
  const ev::OdometryDirectionResult direction =
      raw_odometry ? ev::OdometryDirectionResult{} : ev::correct_odometry_direction(log);
  if (laps > 1) log = ev::lap_log(log, laps, lap_gap_s);

  std::size_t scans = 0, odometry = 0;
  for (const ev::CarmenLog::Entry& entry : log.order) {
    bool ok = true;
    if (entry.is_laser) {
      const ev::CarmenLaser& laser = log.lasers[entry.index];
      const std::int64_t utime = to_utime(laser.timestamp_s);
      if (odometry_from_laser) {
        ok = ok && out.write(ch::kOdometry, utime, odometry_message(utime, laser.odometry, 0.0, 0.0));
        ++odometry;
      }
      ok = ok && out.write(ch::kLidarScan, utime, scan_message(laser, static_cast<std::int32_t>(scans), sensor_mounting(laser, frontlaser_offset_m)));
      ++scans;
    } else if (!odometry_from_laser) {
      const ev::CarmenOdometry& odom = log.odometry[entry.index];
      const std::int64_t utime = to_utime(odom.timestamp_s);
      ok = out.write(ch::kOdometry, utime, odometry_message(utime, odom.pose, odom.tv_mps, odom.rv_radps));
      ++odometry;
    }
    if (!ok) {
      std::fprintf(stderr, "pex-carmen2lcm: cannot write %s\n", out_path.c_str());
      return EX_IOERR;  // 74: the output went bad while writing
    }
  }
  if (direction.reversed_steps > 0)
    std::fprintf(stderr, "pex-carmen2lcm: %zu odometry steps driven backwards but logged forwards reversed (%zu laser poses moved)\n",
                 direction.reversed_steps, direction.changed_laser_poses);
  std::fprintf(stderr, "pex-carmen2lcm: %zu scans, %zu odometry readings (%s), %zu malformed lines%s\n",
               scans, odometry, odometry_from_laser ? "from laser lines" : "from ODOM lines", log.malformed_lines,
               laps > 1 ? (", " + std::to_string(laps) + " laps").c_str() : "");
  return scans > 0 ? 0 : 1;
}
