#pragma once
// pex-sim's parts: options read from config/sim.toml, the simulated LMS111 on
// a CoLa-A TCP server, the CiA 402 wheel drives on a CAN transport, and the
// world/plant stepping in simulated time.
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "canopen/canopen.hpp"
#include "cola/cola.hpp"
#include "hwio/hwio.hpp"
#include "kinematics/kinematics.hpp"
#include "pacer.hpp"
#include "runtime/config.hpp"
#include "sim/sim.hpp"

namespace pex::simd {

struct SimOptions {
  std::string world_file = "worlds/office.wkt";  // relative: to the config file's folder (without one: the working directory)
  std::uint64_t seed = 1;
  double speed_factor = 1.0;        // simulated seconds per wall second
  double physics_rate_hz = 200.0;   // plant and drives step rate (simulated time)
  double truth_rate_hz = 50.0;      // SIM_TRUTH publication rate (simulated time)
  double clock_rate_hz = 100.0;     // SIM_CLOCK publication rate (simulated time, <= physics_rate_hz)
  PacingOptions pacing;             // hold the clock while the set lags (pacer.hpp)
  // Override of the world's START pose (all three or none).
  bool start_override = false;
  geometry::Pose2 start;

  // The laser and its CoLa-A server.
  sim::LaserOptions laser;
  int cola_port = 2111;             // TCP on 127.0.0.1
  std::uint32_t lidar_serial_number = 0x1234567;
  int max_clients = 4;

  // The base: geometry, error model, CAN.
  std::string can_transport = "local";      // "local" | "socketcan"
  std::string can_interface = "vcan0";       // socketcan only
  std::string can_local_path = "@pex-can";
  std::uint8_t left_node_id = 1;
  std::uint8_t right_node_id = 2;
  kinematics::DriveGeometry geometry;
  sim::DiffDrivePlant::Options plant;
  std::int64_t heartbeat_period_us = 100'000;
  double max_motor_accel_counts_per_s2 = 500'000.0;
};

// Reads and validates every key of the sim's config (throws ConfigError).
SimOptions load_options(runtime::ConfigReader& config);

// One connected CoLa-A client and what it asked for.
struct ColaClient {
  hwio::Fd fd;
  int watch_id = -1;
  cola::StreamParser parser;
  int access_level = 0;
  bool streaming = false;
  bool remission = true;
  bool remission_16bit = false;
  bool closed = false;
  std::string held;  // scan telegrams held back by FAULT_LASER_HELD
};

// The simulated LMS111's protocol side: answers requests as SICK's telegram
// listing describes and builds the sSN LMDscandata telegrams.
class Lms111Protocol {
 public:
  explicit Lms111Protocol(const SimOptions& options);
  // Answers one request telegram of `client` (the bytes to send back).
  std::string answer(ColaClient& client, const cola::Telegram& request);
  // Counts a new scan (scan and telegram counters).
  void begin_scan();
  // The current scan's telegram content for the ranges (m; >= max range = no echo).
  cola::ScanData make_scan(const std::vector<float>& ranges_m, std::uint32_t device_time_us,
                           bool remission, bool remission_16bit);
  std::uint16_t scan_counter() const { return scan_counter_; }
  // What "sRN LCMstate" answers: 0 no contamination, 1 warning, 2 error, 3 serious error.
  void set_contamination_level(int level) { contamination_level_ = level; }
  // From the start of a scan to its transmission: the mirror sweeps the
  // 270 deg field of view in 3/4 of a turn.
  std::uint32_t transmission_delay_us() const;

 private:
  const SimOptions& options_;
  cola::ScanConfig device_config_;
  std::uint16_t scan_counter_ = 0;
  std::uint16_t telegram_counter_ = 0;
  int contamination_level_ = 0;
};

}  // namespace pex::simd

namespace pex::runtime {
class Node;
}

namespace pex::simd {

// Wires the simulator into a node: loads the world, opens the CoLa server and
// the CAN transport (throws runtime::Unavailable / ConfigError), and steps
// the simulation from a timer in simulated time.
class Simulator {
 public:
  Simulator(runtime::Node& node, SimOptions options);
  ~Simulator();

 private:
  void tick();                      // runs the simulation steps that are due
  void physics_step();
  void publish_clock();
  void laser_step();
  void send_scan();
  // Bytes to a client (scan telegrams, replies); one that cannot take them within timeout_ms is dropped, with a log line.
  void send_or_drop(ColaClient& client, std::string_view bytes, int timeout_ms);
  // SIM_CLOCK's utime, and every stamp of ours: the wall time the simulation
  // started plus the simulated time since.
  std::int64_t sim_utime() const { return wall_start_utime_ + sim_time_us_; }
  void accept_clients();
  void read_client(ColaClient& client);
  void drop_closed_clients();
  void receive_can();
  // Whether the step to next_sim_us must wait: a drive's heartbeat watchdog
  // would fire while its master is alive, only late in wall time.
  bool drive_watchdog_waits(std::int64_t next_sim_us, double wall_s) const;
  void send_can(const std::vector<canopen::Frame>& frames);
  // SIM_FAULT: the laser stalls or refuses connections for a while.
  void start_laser_fault(std::int8_t fault, double duration_s);
  void end_laser_fault();
  bool open_listener();

  runtime::Node& node_;
  SimOptions options_;
  sim::World world_;
  std::unique_ptr<sim::RayCaster> caster_;
  std::unique_ptr<sim::Laser> laser_;
  std::unique_ptr<sim::DiffDrivePlant> plant_;
  Lms111Protocol protocol_;
  Pacer pacer_;
  hwio::TcpListener listener_;
  std::vector<std::unique_ptr<ColaClient>> clients_;
  std::unique_ptr<hwio::FrameTransport> can_;
  std::vector<canopen::DriveNode> drives_;  // left, right
  // Steady clock (s) at the last heartbeat of the drives' master (-inf: none yet).
  double master_heartbeat_wall_s_ = -std::numeric_limits<double>::infinity();

  std::int64_t sim_time_us_ = 0;
  std::int64_t next_laser_us_ = 0;
  // The scan taken at pending_scan_device_us_, sent at its time of
  // transmission (send_scan_us_; 0 = none pending), as the device does.
  std::vector<float> pending_scan_;
  std::uint32_t pending_scan_device_us_ = 0;
  std::int64_t send_scan_us_ = 0;
  std::int64_t next_truth_us_ = 0;
  std::int64_t next_clock_us_ = 0;
  std::int64_t wall_start_utime_ = 0;
  double wall_start_s_ = 0.0;        // steady clock at start
  std::int64_t steps_done_ = 0;
  int listener_watch_ = -1;
  std::int8_t laser_fault_ = 0;            // sim_fault_t::FAULT_*, 0: none
  std::int64_t laser_fault_until_us_ = 0;  // simulated time
  // FAULT_LASER_BLIND(_SECTOR): the beams between these angles (sensor frame) have no echo.
  double blind_from_rad_ = 0.0, blind_to_rad_ = 0.0;
};

}  // namespace pex::simd
