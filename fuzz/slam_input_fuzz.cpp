// What pex-slam takes from the bus, by content: LIDAR_SCAN and ODOMETRY
// messages that decode fine but carry any values (NaN, 1e300, zero or
// negative angle steps, ranges below the minimum, stamps going back), into
// the daemon's handlers (SlamNode, the code pex-slam runs live and on --log),
// and a checkpoint file of any text into SlamNode::restore.
//
// Input: records; the first byte of each says what follows:
//   op % 3 == 0  ODOMETRY: stamp step (2 bytes, ms), then x, y, theta: a byte
//                each of small values, or (op bit 2) 8-byte doubles of any value
//   op % 3 == 1  LIDAR_SCAN: stamp step, beam count (0..40), a flags byte
//                choosing any-value angles/limits/mounting, ranges as bytes
//   op % 3 == 2  the rest of the input is a checkpoint for restore()
// Invariants: nothing crashes; bad content is refused with
// std::invalid_argument (pex-slam's refusal), nothing else escapes; every
// SLAM_UPDATE and SLAM_POSE published is finite; a refused checkpoint says why.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "archive/byte_archive.hpp"
#include "fuzz_check.hpp"
#include "fuzz_input.hpp"
#include "slam_node.hpp"

namespace {

using namespace pex;

// slam_node.cpp's checkpoint header.
constexpr std::string_view kCheckpointMagic = "PEXSLAMN";
constexpr std::uint32_t kCheckpointVersion = 1;

double small(fuzz::Input& in, double scale) { return static_cast<std::int8_t>(in.byte()) * scale; }

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::Input in(data, size);
  slam_daemon::SlamNodeOptions options;
  options.filter.particle_count = 4;
  slam_daemon::SlamOutputs outputs;
  outputs.publish_update = [](const slam_update_t& m) {
    PEX_FUZZ_CHECK(m.nparticles == static_cast<std::int32_t>(m.particles.size()), "nparticles");
    for (const auto& p : m.particles)
      PEX_FUZZ_CHECK(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.theta), "a particle not finite");
  };
  outputs.publish_pose = [](const pose_t& m) {
    PEX_FUZZ_CHECK(std::isfinite(m.x) && std::isfinite(m.y) && std::isfinite(m.theta), "a pose not finite");
  };
  slam_daemon::SlamNode node(options, outputs);
  std::int64_t utime = 1'700'000'000'000'000;
  while (!in.empty()) {
    const std::uint8_t op = in.byte();
    try {
      if (op % 3 == 0) {
        odometry_t m{};
        utime += static_cast<std::int16_t>(in.u16()) * 1000;
        m.utime = utime;
        const bool any = op & 4;
        m.x = any ? in.any_double() : small(in, 0.05);
        m.y = any ? in.any_double() : small(in, 0.05);
        m.theta = any ? in.any_double() : small(in, 0.05);
        m.covariance[0] = m.covariance[4] = 1e-4;
        m.covariance[8] = (op & 8) ? in.any_double() : 1e-4;
        node.on_odometry(m);
      } else if (op % 3 == 1) {
        laser_scan_t m{};
        utime += static_cast<std::int16_t>(in.u16()) * 1000;
        m.utime = utime;
        const std::uint8_t flags = in.byte();
        m.angle_min = (flags & 1) ? static_cast<float>(in.any_double()) : -1.5f;
        m.angle_increment = (flags & 2) ? static_cast<float>(in.any_double()) : 0.08f;
        m.range_min = (flags & 4) ? static_cast<float>(in.any_double()) : 0.05f;
        m.range_max = (flags & 8) ? static_cast<float>(in.any_double()) : 20.0f;
        m.scan_time = 0.04f;
        if (flags & 16) {
          m.sensor_x = static_cast<float>(in.any_double());
          m.sensor_y = static_cast<float>(in.any_double());
          m.sensor_theta = static_cast<float>(in.any_double());
        }
        const int n = in.byte() % 41;
        for (int i = 0; i < n; ++i) {
          const std::uint8_t r = in.byte();
          m.ranges.push_back(r == 255 ? ((flags & 32) ? static_cast<float>(in.any_double()) : NAN) : r * 0.05f);
        }
        m.nranges = (flags & 64) ? n + 1 : n;  // a count that disagrees
        node.on_scan(m);
      } else {
        // A checkpoint: the text as it is (bit 2 clear); or resealed, so the
        // checksum holds and the parsing behind it is reached: the rest of
        // the input (bit 3 clear) or the node's own checkpoint with the rest
        // of the input written over it from a given byte.
        const std::uint16_t offset = (op & 8) ? in.u16() : 0;
        std::string payload(in.rest());
        if (op & 8) {
          std::string own = archive::unseal(kCheckpointMagic, kCheckpointVersion, node.checkpoint());
          const std::size_t at = own.empty() ? 0 : offset % own.size();
          own.replace(at, std::min(payload.size(), own.size() - at), payload);
          payload = own;
        }
        const std::string why =
            node.restore(op & 4 ? archive::seal(kCheckpointMagic, kCheckpointVersion, payload) : payload);
        (void)why;  // "" = taken; else why not
      }
    } catch (const std::invalid_argument&) {
      // refused content: pex-slam counts it as rejected and goes on
    }
  }
  node.flush();
  (void)node.trajectory_text();
  return 0;
}
