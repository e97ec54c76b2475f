#include "evaluation/carmen_log.hpp"

#include <charconv>
#include <cmath>

namespace pex::evaluation {
namespace {

// Splits on blanks without allocating per token.
std::vector<std::string_view> split_tokens(std::string_view line) {
  std::vector<std::string_view> tokens;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    const std::size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > start) tokens.push_back(line.substr(start, i - start));
  }
  return tokens;
}

bool to_double(std::string_view token, double& value) {
  const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  return ec == std::errc() && ptr == token.data() + token.size() && std::isfinite(value);
}

bool to_count(std::string_view token, std::size_t& value) {
  const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  return ec == std::errc() && ptr == token.data() + token.size();
}

// Reads tokens[at..at+n) as doubles.
bool read_doubles(const std::vector<std::string_view>& tokens, std::size_t at, std::size_t n,
                  double* out) {
  if (at + n > tokens.size()) return false;
  for (std::size_t i = 0; i < n; ++i)
    if (!to_double(tokens[at + i], out[i])) return false;
  return true;
}

// Reads tokens[at..at+n) as ranges in [0, max_m]: one beyond a float's range
// would make its conversion undefined.
bool read_ranges(const std::vector<std::string_view>& tokens, std::size_t at, std::size_t n, double max_m,
                 std::vector<float>& ranges) {
  if (at + n > tokens.size()) return false;
  ranges.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    double r = 0.0;
    if (!to_double(tokens[at + i], r) || r < 0.0 || r > max_m) return false;
    ranges[i] = static_cast<float>(r);
  }
  return true;
}

// "" if the pose, stamp and velocities are within the options' limits, else what is not.
std::string implausible(const CarmenParseOptions& o, const geometry::Pose2& pose, double timestamp_s, double tv = 0.0,
                        double rv = 0.0) {
  if (std::abs(pose.x_m) > o.max_abs_coordinate_m || std::abs(pose.y_m) > o.max_abs_coordinate_m ||
      std::abs(pose.theta_rad) > o.max_abs_coordinate_m)
    return "pose beyond " + std::to_string(o.max_abs_coordinate_m) + " m";
  if (timestamp_s < 0.0 || timestamp_s > o.max_timestamp_s)
    return "timestamp " + std::to_string(timestamp_s) + " s not in [0, " + std::to_string(o.max_timestamp_s) + "]";
  if (std::abs(tv) > o.max_abs_velocity || std::abs(rv) > o.max_abs_velocity) return "velocity beyond the limit";
  return "";
}

LineKind malformed(std::string& error, std::string_view what) {
  error = std::string(what);
  return LineKind::kMalformed;
}

}  // namespace

LineKind parse_carmen_line(std::string_view line, const CarmenParseOptions& options,
                           CarmenMessage& message, std::string& error) {
  const auto tokens = split_tokens(line);
  if (tokens.empty() || tokens[0].front() == '#') return LineKind::kSkipped;
  const std::string_view name = tokens[0];
  if (name == "ODOM") {
    // ODOM x y theta tv rv accel ipc_timestamp ipc_hostname logger_timestamp
    double v[6];
    double ts = 0.0;
    if (tokens.size() < 10 || !read_doubles(tokens, 1, 6, v) || !to_double(tokens[7], ts))
      return malformed(error, "ODOM: expected x y theta tv rv accel timestamp host logger_timestamp");
    CarmenOdometry odom;
    odom.timestamp_s = ts;
    odom.pose = {v[0], v[1], v[2]};
    odom.tv_mps = v[3];
    odom.rv_radps = v[4];
    if (auto why = implausible(options, odom.pose, ts, odom.tv_mps, odom.rv_radps); !why.empty())
      return malformed(error, "ODOM: " + why);
    message = odom;
    return LineKind::kMessage;
  }
  if (name == "FLASER") {
    // FLASER n r1..rn x y theta odom_x odom_y odom_theta ipc_timestamp host logger_timestamp
    std::size_t n = 0;
    if (tokens.size() < 2 || !to_count(tokens[1], n) || n == 0 || n > options.max_beams)
      return malformed(error, "FLASER: bad beam count");
    CarmenLaser laser;
    double poses[6];
    double ts = 0.0;
    if (tokens.size() < 2 + n + 9 || !read_ranges(tokens, 2, n, options.max_range_m, laser.ranges_m) ||
        !read_doubles(tokens, 2 + n, 6, poses) || !to_double(tokens[2 + n + 6], ts))
      return malformed(error, "FLASER: expected n ranges, two poses, timestamp host logger_timestamp");
    const double fov = options.flaser_field_of_view_rad;
    laser.timestamp_s = ts;
    laser.angle_min_rad = -fov / 2.0;
    laser.angle_increment_rad = n % 2 == 1 && n > 1 ? fov / static_cast<double>(n - 1)
                                                    : fov / static_cast<double>(n);
    laser.max_range_m = options.flaser_max_range_m;
    laser.laser_pose = {poses[0], poses[1], poses[2]};
    laser.odometry = {poses[3], poses[4], poses[5]};
    for (const auto& pose : {laser.laser_pose, laser.odometry})
      if (auto why = implausible(options, pose, ts); !why.empty()) return malformed(error, "FLASER: " + why);
    message = std::move(laser);
    return LineKind::kMessage;
  }
  if (name == "ROBOTLASER1") {
    // ROBOTLASER1 type start_angle fov resolution max_range accuracy remission_mode
    //   n r1..rn m e1..em laser_x laser_y laser_theta robot_x robot_y robot_theta
    //   tv rv forward_safety side_safety turn_axis ipc_timestamp host logger_timestamp
    double header[6];
    std::size_t n = 0;
    if (tokens.size() < 9 || !read_doubles(tokens, 1, 6, header) || !to_count(tokens[8], n) ||
        n == 0 || n > options.max_beams)
      return malformed(error, "ROBOTLASER1: bad header or beam count");
    CarmenLaser laser;
    std::size_t m = 0;
    if (tokens.size() < 9 + n + 1 || !read_ranges(tokens, 9, n, options.max_range_m, laser.ranges_m) ||
        !to_count(tokens[9 + n], m) || m > options.max_beams)
      return malformed(error, "ROBOTLASER1: bad ranges or remission count");
    const std::size_t at = 9 + n + 1 + m;
    double tail[11];
    double ts = 0.0;
    if (tokens.size() < at + 14 || !read_doubles(tokens, at, 11, tail) ||
        !to_double(tokens[at + 11], ts))
      return malformed(error, "ROBOTLASER1: bad poses or timestamp");
    laser.timestamp_s = ts;
    laser.angle_min_rad = header[1];
    laser.angle_increment_rad = header[3];
    laser.max_range_m = header[4];
    laser.laser_pose = {tail[0], tail[1], tail[2]};
    laser.odometry = {tail[3], tail[4], tail[5]};
    constexpr double kTwoPi = 2 * 3.141592653589793;
    if (std::abs(header[1]) > kTwoPi || !(header[2] > 0.0 && header[2] <= kTwoPi) ||
        !(header[3] > 0.0 && header[3] <= kTwoPi) || !(header[4] > 0.0 && header[4] <= options.max_range_m))
      return malformed(error, "ROBOTLASER1: start angle, field of view, resolution or maximum range not a laser's");
    for (const auto& pose : {laser.laser_pose, laser.odometry})
      if (auto why = implausible(options, pose, ts, tail[6], tail[7]); !why.empty())
        return malformed(error, "ROBOTLASER1: " + why);
    message = std::move(laser);
    return LineKind::kMessage;
  }
  return LineKind::kSkipped;
}

CarmenLog parse_carmen_log(std::istream& in, const CarmenParseOptions& options) {
  CarmenLog log;
  std::string line;
  std::string error;
  CarmenMessage message;
  while (std::getline(in, line)) {
    switch (parse_carmen_line(line, options, message, error)) {
      case LineKind::kSkipped:
        break;
      case LineKind::kMalformed:
        if (log.malformed_lines++ == 0) log.first_error = error;
        break;
      case LineKind::kMessage:
        if (auto* laser = std::get_if<CarmenLaser>(&message)) {
          log.order.push_back({true, log.lasers.size()});
          log.lasers.push_back(std::move(*laser));
        } else {
          log.order.push_back({false, log.odometry.size()});
          log.odometry.push_back(std::get<CarmenOdometry>(message));
        }
        break;
    }
  }
  return log;
}

}  // namespace pex::evaluation
