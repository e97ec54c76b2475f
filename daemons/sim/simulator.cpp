#include "simulator.hpp"

#include "runtime/channels.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace pex::simd {

using runtime::ConfigError;
using runtime::in_range;
using runtime::one_of;
using runtime::positive;

SimOptions load_options(runtime::ConfigReader& config) {
  SimOptions o;
  o.world_file = config.get_path("world_file", o.world_file);
  o.seed = static_cast<std::uint64_t>(config.get<std::int64_t>("seed", 1, runtime::non_negative<std::int64_t>()));
  o.speed_factor = config.get<double>("speed_factor", o.speed_factor, in_range(0.01, 100.0));
  o.physics_rate_hz = config.get<double>("physics_rate_hz", o.physics_rate_hz, in_range(100.0, 2000.0));
  o.truth_rate_hz = config.get<double>("truth_rate_hz", o.truth_rate_hz, in_range(1.0, 500.0));
  o.clock_rate_hz = config.get<double>("clock_rate_hz", o.clock_rate_hz, in_range(1.0, 2000.0));
  // The clock moves in physics steps: it cannot tick more often than they do.
  if (o.clock_rate_hz > o.physics_rate_hz) config.fail("clock_rate_hz", "must be <= physics_rate_hz");
  o.pacing.channels = config.get<std::vector<std::string>>("pace_channels", o.pacing.channels);
  for (const auto& name : o.pacing.channels) {
    const auto* info = runtime::channels::find(name);
    if (!info) config.fail("pace_channels", "'" + name + "' is not a registered channel");
    // A timer-driven channel (MAP at 1 Hz) is up to one period old while it keeps up.
    o.pacing.periods_us.push_back(info->expected_rate_hz > 0 ? static_cast<std::int64_t>(1e6 / info->expected_rate_hz) : 0);
  }
  o.pacing.max_lag_us =
      1000ll * config.get<int>("pace_max_lag_ms", static_cast<int>(o.pacing.max_lag_us / 1000), in_range(0, 10'000));
  o.pacing.silence_wall_s = config.get<double>("pace_silence_s", o.pacing.silence_wall_s, in_range(0.1, 60.0));
  std::vector<double> start = config.get<std::vector<double>>("start_pose_m_m_rad", {});
  if (!start.empty()) {
    if (start.size() != 3 || !std::isfinite(start[0]) || !std::isfinite(start[1]) || !std::isfinite(start[2])) {
      throw ConfigError(config.origin() + ": start_pose_m_m_rad: needs [x_m, y_m, theta_rad], finite");
    }
    o.start_override = true;
    o.start = geometry::Pose2{start[0], start[1], geometry::wrap_angle(start[2])};
  }

  runtime::ConfigReader lidar = config.section("lidar");
  o.cola_port = lidar.get<int>("cola_port", o.cola_port, in_range(1, 65535));
  o.max_clients = lidar.get<int>("max_clients", o.max_clients, in_range(1, 64));
  o.lidar_serial_number = static_cast<std::uint32_t>(
      lidar.get<std::int64_t>("serial_number", o.lidar_serial_number, in_range<std::int64_t>(0, 0xFFFFFFFFll)));
  o.laser.fov_deg = lidar.get<double>("fov_deg", o.laser.fov_deg, in_range(1.0, 360.0));
  o.laser.step_deg = lidar.get<double>("step_deg", o.laser.step_deg, in_range(0.0625, 10.0));
  o.laser.max_range_m = lidar.get<double>("max_range_m", o.laser.max_range_m, in_range(0.5, 65.0));
  o.laser.min_range_m = lidar.get<double>("min_range_m", o.laser.min_range_m, in_range(0.0, 10.0));
  o.laser.range_noise_sigma_m =
      lidar.get<double>("range_noise_sigma_m", o.laser.range_noise_sigma_m, in_range(0.0, 0.5));
  o.laser.rate_hz = lidar.get<double>("rate_hz", o.laser.rate_hz, in_range(1.0, 100.0));
  o.laser.glass_max_incidence_deg =
      lidar.get<double>("glass_max_incidence_deg", o.laser.glass_max_incidence_deg, in_range(0.0, 90.0));
  o.laser.mount_x_m = lidar.get<double>("mount_x_m", o.laser.mount_x_m, in_range(-5.0, 5.0));
  o.laser.mount_y_m = lidar.get<double>("mount_y_m", o.laser.mount_y_m, in_range(-5.0, 5.0));
  o.laser.mount_theta_rad = lidar.get<double>("mount_theta_rad", o.laser.mount_theta_rad, in_range(-4.0, 4.0));
  if (std::string e = o.laser.validate(); !e.empty()) throw ConfigError(config.origin() + ": [lidar]: " + e);

  runtime::ConfigReader base = config.section("base");
  o.can_transport = base.get<std::string>("can_transport", o.can_transport, one_of({"local", "socketcan"}));
  o.can_interface = base.get<std::string>("can_interface", o.can_interface);
  o.can_local_path = base.get<std::string>("can_local_path", o.can_local_path);
  o.left_node_id = static_cast<std::uint8_t>(base.get<int>("left_node_id", o.left_node_id, in_range(1, 127)));
  o.right_node_id = static_cast<std::uint8_t>(base.get<int>("right_node_id", o.right_node_id, in_range(1, 127)));
  if (o.left_node_id == o.right_node_id) throw ConfigError(config.origin() + ": [base]: node ids must differ");
  o.geometry.counts_per_rev = base.get<double>("counts_per_rev", o.geometry.counts_per_rev, positive<double>());
  o.geometry.gear_ratio = base.get<double>("gear_ratio", o.geometry.gear_ratio, positive<double>());
  o.geometry.wheel_radius_m = base.get<double>("wheel_radius_m", o.geometry.wheel_radius_m, in_range(0.01, 2.0));
  o.geometry.wheel_base_m = base.get<double>("wheel_base_m", o.geometry.wheel_base_m, in_range(0.05, 5.0));
  o.plant.wheel_radius_m = o.geometry.wheel_radius_m;
  o.plant.wheel_base_m = o.geometry.wheel_base_m;
  o.plant.left_radius_bias = base.get<double>("left_radius_bias", 0.0, in_range(-0.2, 0.2));
  o.plant.right_radius_bias = base.get<double>("right_radius_bias", 0.0, in_range(-0.2, 0.2));
  o.plant.wheel_base_bias = base.get<double>("wheel_base_bias", 0.0, in_range(-0.2, 0.2));
  o.plant.slip_sigma = base.get<double>("slip_sigma", 0.0, in_range(0.0, 0.3));
  o.plant.robot_radius_m = base.get<double>("robot_radius_m", o.plant.robot_radius_m, in_range(0.0, 5.0));
  o.heartbeat_period_us =
      1000ll * base.get<int>("heartbeat_period_ms", static_cast<int>(o.heartbeat_period_us / 1000), in_range(10, 10'000));
  o.max_motor_accel_counts_per_s2 =
      base.get<double>("max_motor_accel_counts_per_s2", o.max_motor_accel_counts_per_s2, positive<double>());
  return o;
}

// ----------------------------------------------------------------- protocol --

namespace {

// Sopas error numbers answered with sFA (SICK telegram listing).
constexpr int kErrorAccessDenied = 1;
constexpr int kErrorUnknownMethod = 2;
constexpr int kErrorUnknownVariable = 3;
constexpr int kErrorInvalidData = 5;
constexpr int kErrorUnknownCommand = 12;

std::string error_reply(int code) { return cola::encode_reply("sFA", "", {cola::hex(static_cast<std::uint32_t>(code))}); }

}  // namespace

Lms111Protocol::Lms111Protocol(const SimOptions& options) : options_(options) {
  // The device frame has 0 deg to the sensor's right and 90 deg straight
  // ahead; our beams start at -fov/2 from straight ahead.
  const sim::LaserOptions& l = options.laser;
  device_config_.frequency_centihz = static_cast<std::uint32_t>(std::lround(l.rate_hz * 100.0));
  device_config_.angular_step_1e4deg = static_cast<std::uint32_t>(std::lround(l.step_deg * 1e4));
  device_config_.start_angle_1e4deg = static_cast<std::int32_t>(std::lround((90.0 - 0.5 * l.fov_deg) * 1e4));
  device_config_.stop_angle_1e4deg = static_cast<std::int32_t>(std::lround((90.0 + 0.5 * l.fov_deg) * 1e4));
}

std::string Lms111Protocol::answer(ColaClient& client, const cola::Telegram& t) {
  const auto& a = t.args;
  const std::string key = t.type + " " + t.name;
  if (key == "sMN SetAccessMode") {
    if (a.size() != 2) return error_reply(kErrorInvalidData);
    auto level = cola::parse_uint(a[0], 0xFF);
    auto hash = cola::parse_uint(a[1], 0xFFFFFFFF);
    const bool ok = level && hash &&
                    ((*level == cola::kUserLevelAuthorizedClient && *hash == cola::kPasswordAuthorizedClient) ||
                     (*level == cola::kUserLevelMaintenance && *hash == cola::kPasswordMaintenance));
    if (ok) client.access_level = static_cast<int>(*level);
    return cola::encode_reply("sAN", t.name, {ok ? "1" : "0"});
  }
  if (key == "sMN mLMPsetscancfg") {
    if (client.access_level < cola::kUserLevelAuthorizedClient - 1) return error_reply(kErrorAccessDenied);
    if (a.size() != 5) return error_reply(kErrorInvalidData);
    auto freq = cola::parse_uint(a[0], 0xFFFFFFFF);
    auto step = cola::parse_uint(a[2], 0xFFFFFFFF);
    auto start = cola::parse_int32(a[3]);
    auto stop = cola::parse_int32(a[4]);
    if (!freq || !step || !start || !stop) return error_reply(kErrorInvalidData);
    // The simulated device has one configuration (the config file's): status
    // 1 = frequency, 2 = resolution, 3 = both, 4 = scan area, as the listing.
    int status = 0;
    if (*freq != device_config_.frequency_centihz) status |= 1;
    if (*step != device_config_.angular_step_1e4deg) status |= 2;
    if (status == 0 && (*start < device_config_.start_angle_1e4deg || *stop > device_config_.stop_angle_1e4deg)) {
      status = 4;
    }
    return cola::encode_reply("sAN", t.name,
                              {cola::hex(static_cast<std::uint32_t>(status)), cola::hex(device_config_.frequency_centihz),
                               "1", cola::hex(device_config_.angular_step_1e4deg),
                               cola::hex_int32(device_config_.start_angle_1e4deg),
                               cola::hex_int32(device_config_.stop_angle_1e4deg)});
  }
  if (key == "sRN LMPscancfg") {
    return cola::encode_reply("sRA", t.name,
                              {cola::hex(device_config_.frequency_centihz), "1",
                               cola::hex(device_config_.angular_step_1e4deg),
                               cola::hex_int32(device_config_.start_angle_1e4deg),
                               cola::hex_int32(device_config_.stop_angle_1e4deg)});
  }
  if (key == "sWN LMDscandatacfg") {
    if (client.access_level < cola::kUserLevelMaintenance) return error_reply(kErrorAccessDenied);
    // 01 00 <remission> <resolution> <unit> 00 00 <position> <name> <comment> <time> <interval>
    if (a.size() != 12) return error_reply(kErrorInvalidData);
    client.remission = a[2] == "1";
    client.remission_16bit = a[3] == "1";
    return cola::encode_reply("sWA", t.name);
  }
  if (key == "sWN LMPoutputRange") {
    if (client.access_level < cola::kUserLevelMaintenance) return error_reply(kErrorAccessDenied);
    if (a.size() != 4) return error_reply(kErrorInvalidData);
    return cola::encode_reply("sWA", t.name);
  }
  if (key == "sMN mEEwriteall") return cola::encode_reply("sAN", t.name, {"1"});
  if (key == "sMN LMCstartmeas") return cola::encode_reply("sAN", t.name, {"0"});
  if (key == "sMN LMCstopmeas") return cola::encode_reply("sAN", t.name, {"0"});
  if (key == "sMN Run") {
    client.access_level = 0;
    return cola::encode_reply("sAN", t.name, {"1"});
  }
  if (key == "sEN LMDscandata") {
    if (a.size() != 1 || (a[0] != "0" && a[0] != "1")) return error_reply(kErrorInvalidData);
    client.streaming = a[0] == "1";
    return cola::encode_reply("sEA", t.name, {a[0]});
  }
  if (key == "sRN LCMstate") {
    // The lens contamination measurement: an enum8, 0 none, 1 warning, 2 error, 3 serious error.
    return cola::encode_reply("sRA", t.name, {std::to_string(contamination_level_)});
  }
  if (key == "sRN STlms") {
    // status 7 = measuring; temperature flag, time and date strings as the device sends them
    return cola::encode_reply("sRA", t.name, {"7", "0", "8", "00:00:00", "8", "01.01.2026", "0", "0", "0"});
  }
  if (t.type == "sMN") return error_reply(kErrorUnknownMethod);
  if (t.type == "sRN" || t.type == "sWN" || t.type == "sEN") return error_reply(kErrorUnknownVariable);
  return error_reply(kErrorUnknownCommand);
}

std::uint32_t Lms111Protocol::transmission_delay_us() const {
  return static_cast<std::uint32_t>(1e6 / options_.laser.rate_hz * 0.75);
}

void Lms111Protocol::begin_scan() {
  ++scan_counter_;
  ++telegram_counter_;
}

cola::ScanData Lms111Protocol::make_scan(const std::vector<float>& ranges_m, std::uint32_t device_time_us,
                                         bool remission, bool remission_16bit) {
  cola::ScanData s;
  s.version = 1;
  s.device_number = 1;
  s.serial_number = options_.lidar_serial_number;
  s.telegram_counter = telegram_counter_;
  s.scan_counter = scan_counter_;
  s.time_since_startup_us = device_time_us;
  s.time_of_transmission_us = device_time_us + transmission_delay_us();
  s.scan_frequency_centihz = device_config_.frequency_centihz;
  s.measurement_frequency_100hz = static_cast<std::uint32_t>(
      std::lround(options_.laser.rate_hz * static_cast<double>(360.0 / options_.laser.step_deg) / 100.0));
  cola::Channel dist{"DIST1", 1.0f, 0.0f, device_config_.start_angle_1e4deg,
                     static_cast<std::uint16_t>(device_config_.angular_step_1e4deg), {}};
  dist.data.reserve(ranges_m.size());
  cola::Channel rssi = dist;
  rssi.content = "RSSI1";
  for (float r : ranges_m) {
    const bool echo = std::isfinite(r) && r < options_.laser.max_range_m;
    const double mm = echo ? std::clamp(std::round(r * 1000.0), 16.0, 65535.0) : 0.0;  // 0 = no echo
    dist.data.push_back(static_cast<std::uint16_t>(mm));
    // A plausible remission: strong up close, weaker far away; 0 without echo.
    const double strength = echo ? std::clamp(255.0 - 10.0 * r, 20.0, 255.0) : 0.0;
    rssi.data.push_back(static_cast<std::uint16_t>(remission_16bit ? strength * 256.0 : strength));
  }
  s.channels16.push_back(std::move(dist));
  if (remission) (remission_16bit ? s.channels16 : s.channels8).push_back(std::move(rssi));
  return s;
}

}  // namespace pex::simd

// ----------------------------------------------------------------- simulator --

#include <chrono>
#include <fstream>
#include <sstream>

#include <pex/pose_t.hpp>
#include <pex/daemon_status_t.hpp>
#include <pex/sim_clock_t.hpp>
#include <pex/sim_fault_t.hpp>
#include <spdlog/spdlog.h>

#include "runtime/channels.hpp"
#include "runtime/daemon.hpp"
#include "runtime/node.hpp"

namespace pex::simd {

namespace {

sim::World load_world(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw runtime::ConfigError("world_file: cannot read '" + path + "'");
  std::stringstream text;
  text << in.rdbuf();
  auto parsed = sim::parse_world(text.str(), path);
  if (auto* e = std::get_if<sim::WorldError>(&parsed)) throw runtime::ConfigError("world_file: " + e->message);
  return std::get<sim::World>(std::move(parsed));
}

}  // namespace

Simulator::Simulator(runtime::Node& node, SimOptions options)
    : node_(node),
      options_(std::move(options)),
      world_(load_world(options_.world_file)),
      protocol_(options_),
      pacer_(options_.pacing) {
  caster_ = std::make_unique<sim::RayCaster>(world_);
  // The world file's START must leave the robot clear of the walls; a start
  // given in the config is taken as given (tests park the robot at a wall).
  if (!options_.start_override)
    if (const std::string why = sim::check_start_clearance(world_, *caster_, options_.plant.robot_radius_m); !why.empty())
      throw runtime::ConfigError("world_file: " + why);
  // Independent streams for the laser noise and the wheel slip, both from the seed.
  laser_ = std::make_unique<sim::Laser>(options_.laser, options_.seed * 2 + 1);
  plant_ = std::make_unique<sim::DiffDrivePlant>(options_.plant, options_.start_override ? options_.start : world_.start,
                                                 options_.seed * 2 + 2);
  if (!open_listener()) throw runtime::Unavailable("lidar CoLa server: cannot listen on port " +
                                                   std::to_string(options_.cola_port));

  auto can = options_.can_transport == "socketcan"
                 ? hwio::open_socketcan(hwio::SocketCanOptions{options_.can_interface, {}, false})
                 : hwio::open_local_bus(options_.can_local_path);
  if (!can) throw runtime::Unavailable("CAN: " + can.error());
  can_ = std::move(*can);
  for (std::uint8_t id : {options_.left_node_id, options_.right_node_id}) {
    drives_.emplace_back(canopen::DriveNode::Options{id, options_.heartbeat_period_us,
                                                     options_.max_motor_accel_counts_per_s2});
  }

  // Present from the start, so "no collision" reads 0 rather than absent.
  node_.counter("collisions") = 0;
  node_.counter("collision_steps") = 0;
  node_.watch_fd(can_->fd(), [this] { receive_can(); });
  node_.subscribe<pex::sim_fault_t>(runtime::channels::kSimFault, [this](const pex::sim_fault_t& msg) {
    if (msg.fault != pex::sim_fault_t::FAULT_LASER_STALL && msg.fault != pex::sim_fault_t::FAULT_LASER_REFUSE &&
        msg.fault != pex::sim_fault_t::FAULT_LASER_BLIND && msg.fault != pex::sim_fault_t::FAULT_LASER_BLIND_SECTOR &&
        msg.fault != pex::sim_fault_t::FAULT_LASER_HELD && msg.fault != pex::sim_fault_t::FAULT_LASER_CONTAMINATED)
      throw std::invalid_argument("unknown fault " + std::to_string(msg.fault));
    if (!std::isfinite(msg.duration_s) || msg.duration_s < 0.0 || msg.duration_s > 3600.0)
      throw std::invalid_argument("fault duration " + std::to_string(msg.duration_s) + " s not in [0, 3600]");
    const bool sector = msg.fault == pex::sim_fault_t::FAULT_LASER_BLIND_SECTOR;
    if (sector && !(std::isfinite(msg.sector_from_rad) && std::isfinite(msg.sector_to_rad) &&
                    msg.sector_from_rad < msg.sector_to_rad && msg.sector_from_rad >= -std::numbers::pi &&
                    msg.sector_to_rad <= std::numbers::pi))
      throw std::invalid_argument("blind sector [" + std::to_string(msg.sector_from_rad) + ", " +
                                  std::to_string(msg.sector_to_rad) + "] rad is not an interval within [-pi, pi]");
    const bool contaminated = msg.fault == pex::sim_fault_t::FAULT_LASER_CONTAMINATED;
    if (contaminated && (msg.contamination_level < 1 || msg.contamination_level > 3))
      throw std::invalid_argument("contamination level " + std::to_string(msg.contamination_level) + " not in [1, 3]");
    spdlog::warn("fault from {}: laser {} for {} s", msg.source,
                 msg.fault == pex::sim_fault_t::FAULT_LASER_STALL    ? "stall"
                 : msg.fault == pex::sim_fault_t::FAULT_LASER_REFUSE ? "refuses connections"
                 : msg.fault == pex::sim_fault_t::FAULT_LASER_HELD   ? "telegrams held (delivered at once at the end)"
                 : contaminated ? fmt::format("window dirty (LCMstate {})", msg.contamination_level)
                 : sector ? fmt::format("blind from {:.2f} to {:.2f} rad (no echo there)", msg.sector_from_rad,
                                        msg.sector_to_rad)
                          : std::string("blind (no echo on any beam)"),
                 msg.duration_s);
    blind_from_rad_ = sector ? msg.sector_from_rad : -std::numbers::pi;
    blind_to_rad_ = sector ? msg.sector_to_rad : std::numbers::pi;
    start_laser_fault(msg.fault, msg.duration_s);
    if (contaminated && laser_fault_ == msg.fault) protocol_.set_contamination_level(msg.contamination_level);
  });
  // The sim is the clock source: its node runs on the system clock (run_daemon
  // refuses clock = "sim" for it), and it paces simulated time by the
  // monotonic clock x speed_factor.
  wall_start_s_ = node_.monotonic_us() * 1e-6;
  wall_start_utime_ = node_.now_utime();
  // Every periodic output falls on its period's grid of simulated time (k x
  // period), so SIM_TRUTH at 50 Hz is stamped at ticks of SIM_CLOCK at 100 Hz.
  next_laser_us_ = static_cast<std::int64_t>(std::llround(1e6 / options_.laser.rate_hz));
  next_truth_us_ = static_cast<std::int64_t>(std::llround(1e6 / options_.truth_rate_hz));
  next_clock_us_ = static_cast<std::int64_t>(std::llround(1e6 / options_.clock_rate_hz));
  // The timer only wakes the loop; tick() runs as many fixed physics steps as
  // the simulated clock (wall time x speed) is due, so the simulation is the
  // same whatever the timer's jitter.
  node_.every(std::chrono::milliseconds(2), [this](std::int64_t) { tick(); });
  // Pacing: the newest stamp of each paced channel. Every message of ours
  // starts with its int64 utime right after LCM's 8-byte fingerprint
  // (docs/channels.md), so no channel's type needs decoding here.
  for (std::size_t i = 0; i < options_.pacing.channels.size(); ++i) {
    node_.subscribe_raw(options_.pacing.channels[i], [this, i](const void* data, int size, std::int64_t) {
      if (size < 16) return;
      const auto* b = static_cast<const unsigned char*>(data) + 8;
      std::uint64_t v = 0;
      for (int k = 0; k < 8; ++k) v = (v << 8) | b[k];
      pacer_.on_stamp(i, static_cast<std::int64_t>(v), node_.monotonic_us() * 1e-6);
    });
  }
  node_.set_state(pex::daemon_status_t::STATE_OK);
  spdlog::info("world {} ({} walls), start ({:.2f}, {:.2f}, {:.2f}), CoLa on 127.0.0.1:{}, CAN {}, speed x{}",
               world_.origin, world_.walls.size(), plant_->pose().x_m, plant_->pose().y_m,
               plant_->pose().theta_rad, listener_.port(), can_->describe(), options_.speed_factor);
}

Simulator::~Simulator() = default;

bool Simulator::open_listener() {
  auto listener = hwio::TcpListener::open_loopback(static_cast<std::uint16_t>(options_.cola_port));
  if (!listener) {
    spdlog::error("lidar CoLa server: {}", listener.error());
    return false;
  }
  listener_ = std::move(*listener);
  listener_watch_ = node_.watch_fd(listener_.fd(), [this] { accept_clients(); });
  return true;
}

void Simulator::start_laser_fault(std::int8_t fault, double duration_s) {
  if (laser_fault_ != 0) end_laser_fault();
  if (duration_s <= 0.0) return;
  laser_fault_ = fault;
  laser_fault_until_us_ = sim_time_us_ + static_cast<std::int64_t>(duration_s * 1e6);
  ++node_.counter("laser_faults");
  if (fault == pex::sim_fault_t::FAULT_LASER_REFUSE) {
    // The device's server is gone: its connections close, its port is shut.
    for (auto& client : clients_) client->closed = true;
    drop_closed_clients();
    node_.unwatch_fd(listener_watch_);
    listener_ = hwio::TcpListener{};
  }
}

void Simulator::end_laser_fault() {
  const bool refused = laser_fault_ == pex::sim_fault_t::FAULT_LASER_REFUSE;
  laser_fault_ = 0;
  protocol_.set_contamination_level(0);
  // What waited reaches the clients now, in one go.
  for (auto& client : clients_) {
    if (client->held.empty() || client->closed) continue;
    send_or_drop(*client, client->held, 200);
    client->held.clear();
  }
  if (refused && !open_listener()) {
    // The port is taken meanwhile: try again next tick.
    laser_fault_ = pex::sim_fault_t::FAULT_LASER_REFUSE;
    return;
  }
  spdlog::info("laser fault over");
}

void Simulator::tick() {
  if (laser_fault_ != 0 && sim_time_us_ >= laser_fault_until_us_) end_laser_fault();
  drop_closed_clients();
  const double step_s = 1.0 / options_.physics_rate_hz;
  const double wall_s = node_.monotonic_us() * 1e-6;
  const auto due = static_cast<std::int64_t>((wall_s - wall_start_s_) * options_.speed_factor / step_s);
  // At most 0.25 s of simulated time per call, so the loop stays responsive
  // when the host cannot keep up (the simulation then runs slower than asked).
  const std::int64_t limit = steps_done_ + static_cast<std::int64_t>(options_.physics_rate_hz / 4) + 1;
  bool held = false;
  while (steps_done_ < std::min(due, limit)) {
    // The set lags: the world waits for it (pacer.hpp).
    if (!pacer_.may_advance(sim_utime(), wall_s)) {
      held = true;
      break;
    }
    const auto next_us = static_cast<std::int64_t>(std::llround((steps_done_ + 1) * step_s * 1e6));
    if (drive_watchdog_waits(next_us, wall_s)) {
      held = true;
      ++node_.counter("watchdog_holds");
      break;
    }
    ++steps_done_;
    sim_time_us_ = next_us;
    physics_step();
  }
  if (held) {
    // Waiting is not a backlog: the clock resumes at the asked speed.
    wall_start_s_ = wall_s - static_cast<double>(steps_done_) * step_s / options_.speed_factor;
    ++node_.counter("paced_holds");
  } else if (due > limit) {
    // Behind: forget the backlog instead of bursting.
    wall_start_s_ += (due - limit) * step_s / options_.speed_factor;
    ++node_.counter("physics_overruns");
  }
}

// A drive's heartbeat watchdog (0x1016) fires when its master has died, hung
// or lost the bus, not because the master's next heartbeat is late in wall
// time while the simulated clock runs ten times faster: on the robot the
// master is never 150 ms late. So, as the pacer does for the bus channels,
// the clock waits at a drive's deadline while the master's heartbeats were
// heard within pacing's silence time (wall); after that it goes on and the
// watchdog fires as on the robot (the fault tests kill the driver).
bool Simulator::drive_watchdog_waits(std::int64_t next_sim_us, double wall_s) const {
  if (options_.pacing.max_lag_us <= 0 || wall_s - master_heartbeat_wall_s_ > options_.pacing.silence_wall_s)
    return false;
  return std::any_of(drives_.begin(), drives_.end(), [next_sim_us](const canopen::DriveNode& drive) {
    const auto deadline = drive.heartbeat_deadline_us();
    return deadline && next_sim_us > *deadline;
  });
}

void Simulator::physics_step() {
  receive_can();
  for (auto& drive : drives_) send_can(drive.step(sim_time_us_));
  const double step_s = 1.0 / options_.physics_rate_hz;
  const double counts_per_wheel_rad = options_.geometry.counts_per_rev * options_.geometry.gear_ratio /
                                      (2.0 * std::numbers::pi);
  plant_->step(step_s, drives_[0].velocity_actual() / counts_per_wheel_rad,
               drives_[1].velocity_actual() / counts_per_wheel_rad, caster_.get());
  node_.counter("collisions") = static_cast<std::int64_t>(plant_->contacts());
  node_.counter("collision_steps") = static_cast<std::int64_t>(plant_->refused_steps());
  // The clock first: a daemon that gets this step's scan or truth has its time.
  if (sim_time_us_ >= next_clock_us_) {
    next_clock_us_ += static_cast<std::int64_t>(std::llround(1e6 / options_.clock_rate_hz));
    publish_clock();
  }
  if (send_scan_us_ != 0 && sim_time_us_ >= send_scan_us_) send_scan();
  if (sim_time_us_ >= next_laser_us_) {
    next_laser_us_ += static_cast<std::int64_t>(std::llround(1e6 / options_.laser.rate_hz));
    laser_step();
  }
  if (sim_time_us_ >= next_truth_us_) {
    next_truth_us_ += static_cast<std::int64_t>(std::llround(1e6 / options_.truth_rate_hz));
    pex::pose_t truth{};
    truth.utime = sim_utime();
    truth.x = plant_->pose().x_m;
    truth.y = plant_->pose().y_m;
    truth.theta = plant_->pose().theta_rad;
    node_.publish(runtime::channels::kSimTruth, truth);
  }
}

void Simulator::publish_clock() {
  pex::sim_clock_t clock{};
  clock.utime = sim_utime();
  clock.sim_time_us = sim_time_us_;
  clock.speed_factor = options_.speed_factor;
  clock.collisions = static_cast<std::int64_t>(plant_->contacts());
  clock.collision_steps = static_cast<std::int64_t>(plant_->refused_steps());
  node_.publish(runtime::channels::kSimClock, clock);
}

void Simulator::laser_step() {
  // The scan is the world at this instant; the device sends it once the
  // mirror has swept its field of view, at the time of transmission the
  // telegram states. Sent then, the reader's clock at reception maps the
  // device time onto simulated time exactly, as SIM_TRUTH is stamped.
  pending_scan_ = laser_->scan(*caster_, plant_->pose());
  pending_scan_device_us_ = static_cast<std::uint32_t>(sim_time_us_);  // wraps as the device's does
  send_scan_us_ = sim_time_us_ + protocol_.transmission_delay_us();
  ++node_.counter("scans");
  protocol_.begin_scan();
}

void Simulator::send_scan() {
  send_scan_us_ = 0;
  if (laser_fault_ == pex::sim_fault_t::FAULT_LASER_STALL) return;  // a hung device sends nothing
  // One telegram per channel configuration among the streaming clients.
  std::string encoded[2][2];
  // Blind (in a sector): the same telegrams, the beams there at the laser's
  // range (no echo).
  std::vector<float> no_echo;
  if (laser_fault_ == pex::sim_fault_t::FAULT_LASER_BLIND || laser_fault_ == pex::sim_fault_t::FAULT_LASER_BLIND_SECTOR) {
    no_echo = pending_scan_;
    const double first = options_.laser.first_angle_rad(), step = options_.laser.step_deg * std::numbers::pi / 180.0;
    for (std::size_t i = 0; i < no_echo.size(); ++i) {
      const double a = first + step * static_cast<double>(i);
      if (a >= blind_from_rad_ && a <= blind_to_rad_) no_echo[i] = static_cast<float>(options_.laser.max_range_m);
    }
  }
  const std::vector<float>& ranges = no_echo.empty() ? pending_scan_ : no_echo;
  const std::uint32_t device_time = pending_scan_device_us_;
  for (auto& client : clients_) {
    if (!client->streaming || client->closed) continue;
    std::string& bytes = encoded[client->remission][client->remission_16bit];
    if (bytes.empty()) {
      bytes = cola::encode_scan_data(
          protocol_.make_scan(ranges, device_time, client->remission, client->remission_16bit));
    }
    if (laser_fault_ == pex::sim_fault_t::FAULT_LASER_HELD) {
      // Bounded as a link's buffers are (about a minute of scans): beyond, the connection is lost.
      constexpr std::size_t kMaxHeldBytes = 8u << 20;
      if (client->held.size() + bytes.size() > kMaxHeldBytes) {
        spdlog::warn("CoLa client dropped: {} bytes held", client->held.size());
        client->closed = true;
        client->held.clear();
      } else {
        client->held += bytes;
      }
      continue;
    }
    // A client that does not keep up (its socket buffer of several scans is
    // full for 20 ms) is dropped rather than allowed to stall the simulation.
    send_or_drop(*client, bytes, 20);
  }
}

void Simulator::send_or_drop(ColaClient& client, std::string_view bytes, int timeout_ms) {
  std::string error;
  if (!hwio::write_all(client.fd.get(), bytes, timeout_ms, &error)) {
    spdlog::warn("CoLa client dropped: {}", error);
    client.closed = true;
  }
}

void Simulator::accept_clients() {
  while (auto fd = listener_.accept()) {
    if (static_cast<int>(clients_.size()) >= options_.max_clients) {
      ++node_.counter("clients_refused");
      continue;  // closing the fd refuses it
    }
    auto client = std::make_unique<ColaClient>();
    client->fd = std::move(*fd);
    ColaClient* raw = client.get();
    client->watch_id = node_.watch_fd(client->fd.get(), [this, raw] { read_client(*raw); });
    clients_.push_back(std::move(client));
    ++node_.counter("clients_accepted");
    spdlog::info("CoLa client connected ({} now)", clients_.size());
  }
}

void Simulator::read_client(ColaClient& client) {
  char buffer[4096];
  for (;;) {
    hwio::ReadResult r = hwio::read_some(client.fd.get(), buffer, sizeof buffer);
    if (r.closed) {
      client.closed = true;
      break;
    }
    if (r.bytes == 0) break;
    if (laser_fault_ == pex::sim_fault_t::FAULT_LASER_STALL) continue;  // read, never answered
    for (auto& event : client.parser.push(std::string_view(buffer, r.bytes))) {
      if (auto* reply = std::get_if<cola::ReplyEvent>(&event)) {
        send_or_drop(client, protocol_.answer(client, reply->telegram), 200);
      } else if (auto* bad = std::get_if<cola::ErrorEvent>(&event)) {
        node_.reject("cola", "malformed request: " + bad->message);
      }
    }
  }
  // A closed client is erased by tick(), not here inside its own fd callback.
}

void Simulator::drop_closed_clients() {
  for (auto it = clients_.begin(); it != clients_.end();) {
    if ((*it)->closed) {
      node_.unwatch_fd((*it)->watch_id);
      it = clients_.erase(it);
      spdlog::info("CoLa client disconnected ({} left)", clients_.size());
    } else {
      ++it;
    }
  }
}

void Simulator::receive_can() {
  while (auto frame = can_->receive()) {
    ++node_.counter("can_frames_in");
    for (auto& drive : drives_) {
      if (drive.consumes(*frame)) master_heartbeat_wall_s_ = node_.monotonic_us() * 1e-6;
      send_can(drive.handle(*frame));
    }
  }
  node_.counter("can_malformed") = static_cast<std::int64_t>(can_->malformed());
}

void Simulator::send_can(const std::vector<canopen::Frame>& frames) {
  for (const auto& f : frames) {
    std::string error;
    if (!can_->send(f, &error)) {
      ++node_.counter("can_send_errors");
    }
  }
}

}  // namespace pex::simd
