// CANopen / CiA 402 frames as a broken or hostile bus could carry them: the
// base driver's core (DriverCore: Cia402Master + odometry) and the simulated
// drives (canopen::DriveNode, as pex-sim runs them) wired to each other on
// one bus, with frames of any id, flags, length and data injected on either
// side, BASE_CMD of any value, and time going on.
//
// Input: records; the first byte of each says what happens:
//   op % 4 == 0  a frame to the driver:  id (4 bytes, flags included), dlc (1, any value), data (8)
//   op % 4 == 1  a frame to the drives:  the same
//   op % 4 == 2  a BASE_CMD:             v, omega (8 bytes each, any double)
//   op % 4 == 3  time: 1 + op / 4 ms of control periods; frames cross the bus
// Invariants: nothing crashes; every frame either side sends is a plain
// 11-bit data frame of at most 8 bytes; the wheel velocities sent fit the
// limits; every ODOMETRY is finite with theta in [-pi, pi].
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "canopen/canopen.hpp"
#include "driver_core.hpp"
#include "fuzz_check.hpp"
#include "fuzz_input.hpp"

namespace {

using namespace pex;

canopen::Frame read_frame(fuzz::Input& in) {
  canopen::Frame f{};
  f.can_id = in.u32();
  f.can_dlc = in.byte();
  for (auto& b : f.data) b = in.byte();
  return f;
}

void check_sent(const canopen::Frame& f, const char* who) {
  PEX_FUZZ_CHECK(canopen::is_plain_data_frame(f) && f.can_dlc <= 8,
                 std::string(who) + " sent id " + std::to_string(f.can_id) + " dlc " + std::to_string(f.can_dlc));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::Input in(data, size);
  base_driver::DriverOptions options;
  options.can_transport = "local";
  std::vector<canopen::Frame> to_drives;  // what the driver put on the bus
  std::int64_t odometry_count = 0;
  base_driver::DriverOutputs out;
  out.send_frame = [&](const canopen::Frame& f, std::string*) {
    check_sent(f, "driver");
    to_drives.push_back(f);
    return true;
  };
  out.publish_odometry = [&](const pex::odometry_t& m) {
    ++odometry_count;
    PEX_FUZZ_CHECK(std::isfinite(m.x) && std::isfinite(m.y) && std::isfinite(m.theta) && std::isfinite(m.v) &&
                       std::isfinite(m.omega),
                   "odometry not finite");
    PEX_FUZZ_CHECK(std::abs(m.theta) <= std::numbers::pi + 1e-9, "theta " + std::to_string(m.theta));
    for (double c : m.covariance) PEX_FUZZ_CHECK(std::isfinite(c), "covariance not finite");
  };
  out.report = [](const pex::runtime::DaemonHealth&) {};
  out.error = [](std::string_view, const std::string&) {};
  out.reject = [](std::string_view, const std::string&) {};
  base_driver::DriverCore driver(options, out);

  std::vector<canopen::DriveNode> drives;
  for (std::uint8_t id : {options.left_node_id, options.right_node_id}) {
    canopen::DriveNode::Options o;
    o.node_id = id;
    drives.emplace_back(o);
  }
  // The largest wheel velocity the limits allow, in the drives' counts/s.
  const double wheel_mps = options.limits.max_speed_mps + options.limits.max_omega_radps * options.geometry.wheel_base_m / 2;
  const double max_counts = wheel_mps / (2 * std::numbers::pi * options.geometry.wheel_radius_m) *
                            options.geometry.gear_ratio * options.geometry.counts_per_rev * 1.01 + 1;

  std::int64_t now_us = 1'000'000;
  const std::int64_t utime0 = 1'700'000'000'000'000;
  std::vector<canopen::Frame> to_driver;  // what the drives put on the bus
  auto deliver_to_drives = [&](const canopen::Frame& f) {
    for (auto& d : drives)
      for (const auto& answer : d.handle(f)) {
        check_sent(answer, "drive");
        to_driver.push_back(answer);
      }
  };
  while (!in.empty()) {
    const std::uint8_t op = in.byte();
    switch (op % 4) {
      case 0:
        driver.on_frames({read_frame(in)}, now_us, utime0 + now_us);
        break;
      case 1:
        deliver_to_drives(read_frame(in));
        break;
      case 2: {
        pex::velocity_cmd_t cmd{};
        cmd.utime = utime0 + now_us;
        cmd.v = in.any_double();
        cmd.omega = in.any_double();
        cmd.source = "fuzz";
        std::string refused;
        try {
          driver.on_command(cmd, now_us);
        } catch (const std::invalid_argument& e) {
          refused = e.what();
        }
        PEX_FUZZ_CHECK(refused.empty() || !(std::abs(cmd.v) <= options.limits.max_speed_mps &&
                                            std::abs(cmd.omega) <= options.limits.max_omega_radps),
                       "a command within the limits refused: " + refused);
        break;
      }
      default: {
        const int periods = 1 + op / 4;
        for (int p = 0; p < periods; ++p) {
          now_us += 10'000;  // control_rate_hz 100
          to_drives.clear();
          driver.control(now_us);
          for (const auto& f : to_drives) {
            if (canopen::function_of(f) == canopen::kCobRpdo1)
              if (const auto rpdo = canopen::read_rpdo1(f))
                PEX_FUZZ_CHECK(std::abs(static_cast<double>(rpdo->target_velocity)) <= max_counts,
                               "wheel velocity " + std::to_string(rpdo->target_velocity) + " counts/s");
            deliver_to_drives(f);
          }
          for (auto& d : drives)
            for (const auto& f : d.step(now_us)) {
              check_sent(f, "drive");
              to_driver.push_back(f);
            }
          driver.on_frames(to_driver, now_us, utime0 + now_us);
          to_driver.clear();
          if (p % 2 == 1) driver.publish_odometry(now_us);
        }
      }
    }
  }
  return 0;
}
