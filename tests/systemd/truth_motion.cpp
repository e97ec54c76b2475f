// truth_motion LOG FROM_US TO_US: how far the simulated robot moved (SIM_TRUTH) in an
// LCM log (lcm-logger's, possibly still being written) between two wall-clock times,
// taken from each event's log timestamp (when lcm-logger received it). Prints
//   events N moved_m D max_speed_mps V max_omega_radps O stood_after_ms W sim_ms S
// where D is the largest distance of any pose in the window from the window's first
// pose, V and O the largest speed and turn rate between two poses at least 0.1 s
// (simulated) apart; the robot stood (its wheels did not turn: neither moved nor
// turned) from some pose of the window to its end, every later pose within 1 mm and
// 1 mrad of it: W is that pose's log time after FROM_US (wall clock), S its SIM_TRUTH time after
// that of the last pose logged before FROM_US (the simulator's clock, which pex-sim
// holds while a paced channel lags: wall time can run ahead of it); -1 if none.
// For tests/systemd/nspawn_boot.sh: the wheels stand while pex-base-driver is dead,
// and the robot drove before. Exit 0, 66 if the log cannot be opened.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <utility>
#include <vector>

#include <lcm/lcm-cpp.hpp>
#include <pex/pose_t.hpp>

#include "runtime/channels.hpp"

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: truth_motion LOG FROM_US TO_US\n");
    return 64;
  }
  lcm::LogFile log(argv[1], "r");
  if (!log.good()) {
    std::fprintf(stderr, "truth_motion: cannot open %s\n", argv[1]);
    return 66;
  }
  const long long from = std::atoll(argv[2]), to = std::atoll(argv[3]);
  int events = 0;
  double moved = 0.0, max_speed = 0.0, max_omega = 0.0;
  pex::pose_t first{}, before{};  // the window's first pose, the last pose before it
  before.utime = -1;
  std::deque<pex::pose_t> recent;  // poses of the last 0.1 s and one before
  std::vector<std::pair<long long, pex::pose_t>> window;
  // A partly written last event (the logger is still at it) ends the read.
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    if (ev->timestamp > to || ev->channel != pex::runtime::channels::kSimTruth) continue;
    pex::pose_t p{};
    if (p.decode(ev->data, 0, ev->datalen) != ev->datalen) continue;
    if (ev->timestamp < from) {
      before = p;
      continue;
    }
    if (events++ == 0) first = p;
    window.emplace_back(ev->timestamp, p);
    moved = std::max(moved, std::hypot(p.x - first.x, p.y - first.y));
    recent.push_back(p);
    while (recent.size() > 2 && p.utime - recent[1].utime >= 100'000) recent.pop_front();
    const pex::pose_t& q = recent.front();
    if (p.utime - q.utime >= 100'000) {
      const double dt = (p.utime - q.utime) * 1e-6;
      max_speed = std::max(max_speed, std::hypot(p.x - q.x, p.y - q.y) / dt);
      max_omega = std::max(max_omega, std::abs(std::remainder(p.theta - q.theta, 2 * M_PI)) / dt);
    }
  }
  long long stood_wall_ms = -1, stood_sim_ms = -1;
  for (auto it = window.rbegin(); it != window.rend(); ++it) {
    const pex::pose_t& last = window.back().second;
    if (std::hypot(it->second.x - last.x, it->second.y - last.y) > 0.001 ||
        std::abs(std::remainder(it->second.theta - last.theta, 2 * M_PI)) > 0.001)
      break;
    stood_wall_ms = (it->first - from) / 1000;
    stood_sim_ms = before.utime < 0 ? -1 : (it->second.utime - before.utime) / 1000;
  }
  std::printf("events %d moved_m %.4f max_speed_mps %.3f max_omega_radps %.3f stood_after_ms %lld sim_ms %lld\n",
              events, moved, max_speed, max_omega, stood_wall_ms, stood_sim_ms);
  return 0;
}
