// lidar_reader: its config (the shipped file is read completely; bad values
// are refused) and its core against a scripted LMS1xx, time passed in: no
// process, no socket, no sleep.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include <pex/daemon_status_t.hpp>

#include "reader.hpp"
#include "reader_core.hpp"
#include "runtime/config.hpp"
#include "runtime/daemon.hpp"

namespace pex::lidar_reader {
namespace {

TEST(LidarReaderOptions, ShippedConfigLoadsCompletelyAndGivesTheLms111Setup) {
  auto config = runtime::ConfigReader::from_file(std::string(PEX_SOURCE_DIR) + "/config/lidar_reader.toml");
  runtime::load_runtime_options(config);  // read by run_daemon
  ReaderOptions o = load_options(config);
  EXPECT_NO_THROW(config.finish());
  const cola::ScanConfig c = o.scan_config();
  EXPECT_EQ(c.frequency_centihz, 2500u);
  EXPECT_EQ(c.angular_step_1e4deg, 5000u);
  EXPECT_EQ(c.start_angle_1e4deg, -450000);
  EXPECT_EQ(c.stop_angle_1e4deg, 2250000);
}

TEST(LidarReaderOptions, BadValuesAreRefused) {
  for (const char* text : {"port = 0\n", "reconnect_initial_ms = 5000\nreconnect_max_ms = 100\n",
                           "angular_step_deg = 0.0\n", "connect_timeout_ms = \"soon\"\n", "host = \"\"\n",
                           "max_device_time_jump_ms = 0\n"}) {
    auto config = runtime::ConfigReader::from_string(text, "bad.toml");
    EXPECT_THROW(load_options(config), runtime::ConfigError) << text;
  }
}

// The stamping clock is another epoch than the monotonic one.
constexpr std::int64_t kUtimeOffset = 1'700'000'000'000'000;
// From the start of a scan to its transmission (3/4 of a turn at 25 Hz).
constexpr std::uint32_t kTransmissionDelayUs = 30'000;

// One LMS111 scan as the device encodes it: 541 beams from -45 to 225 deg
// (device frame) at 0.5 deg; beam 0 has no echo, beam i is at 1000 + i mm.
cola::ScanData scan_data(std::uint16_t counter, std::uint32_t device_us) {
  cola::ScanData s;
  s.device_number = 1;
  s.serial_number = 0x1234567;
  s.telegram_counter = counter;
  s.scan_counter = counter;
  s.time_since_startup_us = device_us;
  s.time_of_transmission_us = device_us + kTransmissionDelayUs;
  s.scan_frequency_centihz = 2500;
  s.measurement_frequency_100hz = 540;
  cola::Channel dist{"DIST1", 1.0f, 0.0f, -450000, 5000, {}};
  cola::Channel rssi{"RSSI1", 1.0f, 0.0f, -450000, 5000, {}};
  for (std::uint16_t i = 0; i < 541; ++i) {
    dist.data.push_back(i == 0 ? 0 : static_cast<std::uint16_t>(1000 + i));
    rssi.data.push_back(i == 0 ? 0 : 200);
  }
  s.channels16.push_back(std::move(dist));
  s.channels8.push_back(std::move(rssi));
  return s;
}

// An LMS1xx played by the test: each request is answered as SICK's telegram
// listing says, unless `answers` has another answer for its name ("" = none);
// after "sEN LMDscandata 1" it streams a scan every 40 ms of run time.
struct Device {
  Device() {
    answers["SetAccessMode"] = cola::encode_reply("sAN", "SetAccessMode", {"1"});
    answers["mLMPsetscancfg"] =
        cola::encode_reply("sAN", "mLMPsetscancfg", {"0", "9C4", "1", "1388", "FFF92230", "225510"});
    answers["LMDscandatacfg"] = cola::encode_reply("sWA", "LMDscandatacfg");
    answers["LMPoutputRange"] = cola::encode_reply("sWA", "LMPoutputRange");
    answers["LMCstartmeas"] = cola::encode_reply("sAN", "LMCstartmeas", {"0"});
    answers["Run"] = cola::encode_reply("sAN", "Run", {"1"});
    answers["LMDscandata"] = cola::encode_reply("sEA", "LMDscandata", {"1"});
    answers["LCMstate"] = cola::encode_reply("sRA", "LCMstate", {"0"});  // a clean window
  }
  void receive(std::string_view bytes) {
    for (auto& event : parser.push(bytes)) {
      auto* request = std::get_if<cola::ReplyEvent>(&event);
      ASSERT_NE(request, nullptr) << "the reader sent something that is not a request";
      const cola::Telegram& t = request->telegram;
      requests.push_back(t.type + " " + t.name);
      to_reader += answers[t.name];
      if (t.type == "sEN" && t.name == "LMDscandata") streaming = !t.args.empty() && t.args[0] == "1";
    }
  }
  // A new connection: a new session.
  void reset() {
    parser.reset();
    to_reader.clear();
    streaming = false;
  }

  std::map<std::string, std::string> answers;
  std::vector<std::string> requests;  // "type name", in order, over all connections
  std::string to_reader;              // bytes on their way to the reader
  bool streaming = false;
  bool stalled = false;               // streaming, but no scans come
  std::uint16_t scan_counter = 0;
  cola::StreamParser parser;
};

// A ReaderCore, the Device at the other end of its connection, and the
// daemon's 20 ms poll. What the device sends is read in the same period.
class Rig {
 public:
  explicit Rig(const ReaderOptions& options = {}) : core(options, outputs()) {}

  void run(int ms) {
    for (int t = 0; t < ms; t += 20) {
      tick();
      core.poll(now_us);
      deliver();
    }
  }
  // The reader does not run for `ms` (a loaded computer): the device sends
  // on, and what it sent is read at once when the reader runs again.
  void stall(int ms) {
    for (int t = 0; t < ms; t += 20) tick();
  }
  // Bytes from the device now, in the order given, each in its own read.
  void receive(const std::vector<std::string>& reads) {
    for (const auto& bytes : reads) core.on_bytes(bytes, now_us, now_us + kUtimeOffset);
  }
  std::uint32_t device_us() const { return static_cast<std::uint32_t>(now_us - 1'000'000 + 5'000'000); }
  bool streaming() const { return core.phase() == ReaderCore::Phase::kStreaming; }
  bool ok() const { return health.state == pex::daemon_status_t::STATE_OK; }

  std::int64_t now_us = 1'000'000;
  bool refuse = false;      // connect() fails with "connection refused"
  bool send_fails = false;  // send() fails with "Broken pipe"
  bool connected = false;
  std::vector<std::int64_t> connect_times_us;
  int closes = 0;
  std::string sent_bytes;
  std::vector<pex::laser_scan_t> scans;
  runtime::DaemonHealth health;
  std::vector<std::string> notes;
  std::vector<std::pair<std::string, std::string>> errors, rejects;  // (key, text)
  Device device;
  ReaderCore core;

 private:
  ReaderOutputs outputs() {
    ReaderOutputs out;
    out.connect = [this](std::string* error) {
      connect_times_us.push_back(now_us);
      if (refuse) {
        *error = "connection refused";
        return false;
      }
      connected = true;
      device.reset();
      return true;
    };
    out.close = [this] {
      EXPECT_TRUE(connected) << "close without a connection";
      connected = false;
      ++closes;
    };
    out.send = [this](std::string_view bytes, std::string* error) {
      EXPECT_TRUE(connected) << "send without a connection";
      if (send_fails) {
        *error = "Broken pipe";
        return false;
      }
      sent_bytes += bytes;
      device.receive(bytes);
      return true;
    };
    out.publish_scan = [this](const pex::laser_scan_t& msg) { scans.push_back(msg); };
    out.report = [this](const runtime::DaemonHealth& h) { health = h; };
    out.note = [this](const std::string& text) { notes.push_back(text); };
    out.error = [this](std::string_view key, const std::string& text) { errors.emplace_back(key, text); };
    out.reject = [this](std::string_view key, const std::string& text) { rejects.emplace_back(key, text); };
    return out;
  }
  // 20 ms go by; the device sends a scan every other tick while it streams.
  void tick() {
    now_us += 20'000;
    if (connected && device.streaming && !device.stalled && (ticks++ % 2 == 0)) {
      device.to_reader += cola::encode_scan_data(scan_data(++device.scan_counter, device_us()));
    }
  }
  // What the device sent, read as the shell's fd watch would: until none is left.
  void deliver() {
    while (connected && !device.to_reader.empty()) {
      const std::string bytes = std::exchange(device.to_reader, {});
      core.on_bytes(bytes, now_us, now_us + kUtimeOffset);
    }
  }
  int ticks = 0;
};

const std::vector<std::string> kConfigureSequence = {
    "sMN SetAccessMode", "sMN mLMPsetscancfg", "sWN LMDscandatacfg", "sWN LMPoutputRange",
    "sMN LMCstartmeas",  "sMN Run",            "sEN LMDscandata"};

TEST(ReaderCore, LogsInConfiguresAndStreamsAsTheTelegramListingSays) {
  Rig rig;
  EXPECT_TRUE(rig.connect_times_us.empty());
  rig.run(20);
  ASSERT_EQ(rig.connect_times_us.size(), 1u);  // at the first poll
  EXPECT_EQ(rig.device.requests, kConfigureSequence);
  EXPECT_TRUE(rig.streaming());
  EXPECT_EQ(rig.health.state, +pex::daemon_status_t::STATE_DEGRADED);
  EXPECT_EQ(rig.health.reason, "configuring the sensor");
  EXPECT_EQ(rig.notes, (std::vector<std::string>{"connected to 192.168.0.1:2111, configuring",
                                                 "streaming scans from 192.168.0.1:2111"}));
  rig.run(20);
  ASSERT_EQ(rig.scans.size(), 1u);
  EXPECT_TRUE(rig.ok());
  EXPECT_EQ(rig.health.reason, "");
  EXPECT_EQ(rig.core.counters().connect_attempts, 1);
  EXPECT_EQ(rig.core.counters().scans_published, 1);
  EXPECT_TRUE(rig.errors.empty());
  EXPECT_TRUE(rig.rejects.empty());
}

TEST(ReaderCore, SendsTheRequestsTheOptionsSay) {
  ReaderOptions options;
  options.remission = false;
  options.scan_frequency_hz = 50.0;
  options.angular_step_deg = 0.25;
  options.fov_deg = 180.0;
  Rig rig(options);
  rig.run(20);
  cola::ScanDataConfig data;
  data.remission = false;
  EXPECT_EQ(rig.sent_bytes,
            cola::set_access_mode_request(cola::kUserLevelAuthorizedClient, cola::kPasswordAuthorizedClient) +
                cola::set_scan_config_request(cola::ScanConfig{5000, 2500, 0, 1800000}) +
                cola::scan_data_config_request(data) +
                cola::output_range_request(cola::ScanConfig{5000, 2500, 0, 1800000}) +
                cola::start_measurement_request() + cola::run_request() + cola::scan_output_request(true));
  // Without configure_scan the device's scan configuration is kept.
  ReaderOptions keep;
  keep.configure_scan = false;
  Rig rig2(keep);
  rig2.run(20);
  std::vector<std::string> expected = kConfigureSequence;
  expected.erase(expected.begin() + 1);
  EXPECT_EQ(rig2.device.requests, expected);
  EXPECT_TRUE(rig2.streaming());
}

TEST(ReaderCore, ScanBecomesALaserScanOnTheHostClock) {
  ReaderOptions options;
  options.sensor_x_m = 0.2;
  options.sensor_theta_rad = 0.1;
  Rig rig(options);
  rig.run(40);
  ASSERT_EQ(rig.scans.size(), 1u);
  const pex::laser_scan_t& s = rig.scans[0];
  constexpr double kDeg = std::numbers::pi / 180.0;
  EXPECT_FLOAT_EQ(s.angle_min, static_cast<float>(-135.0 * kDeg));
  EXPECT_FLOAT_EQ(s.angle_increment, static_cast<float>(0.5 * kDeg));
  ASSERT_EQ(s.nranges, 541);
  ASSERT_EQ(s.ranges.size(), 541u);
  EXPECT_TRUE(std::isnan(s.ranges[0]));  // no echo
  EXPECT_FLOAT_EQ(s.ranges[1], 1.001f);
  EXPECT_FLOAT_EQ(s.ranges[540], 1.540f);
  ASSERT_EQ(s.nintensities, 541);
  EXPECT_EQ(s.intensities[1], 200.0f);
  EXPECT_FLOAT_EQ(s.scan_time, 0.04f);
  EXPECT_FLOAT_EQ(s.range_min, 0.05f);
  EXPECT_FLOAT_EQ(s.range_max, 20.0f);
  EXPECT_FLOAT_EQ(s.sensor_x, 0.2f);
  EXPECT_FLOAT_EQ(s.sensor_theta, 0.1f);
  EXPECT_EQ(s.scan_counter, 1);
  // The scan started kTransmissionDelayUs before it was sent, and it was
  // received (with no delay here) at the stamping clock's now.
  EXPECT_EQ(s.utime, rig.now_us + kUtimeOffset - kTransmissionDelayUs);
  EXPECT_EQ(s.device_utime, rig.device_us());
}

// The reader stalls for 0.8 s, short of the stale timeout: the scans sent
// meanwhile are read at once and each keeps its own time (the device clock's
// estimate started afresh on them stamped them all with the time they were
// read: a turning robot's scans drawn at one pose, walls across a door).
TEST(ReaderCore, ScansThatWaitedForAStalledReaderKeepTheirOwnTimes) {
  Rig rig;
  rig.run(11'000);  // 10 s of scans: the device clock's estimate settled
  ASSERT_TRUE(rig.streaming());
  const std::size_t before = rig.scans.size();
  ASSERT_GT(before, 200u);
  const std::int64_t offset = rig.scans.back().utime - rig.scans.back().device_utime;
  rig.stall(800);
  rig.run(20);
  ASSERT_TRUE(rig.streaming());
  ASSERT_GE(rig.scans.size(), before + 20);
  for (std::size_t i = before; i < rig.scans.size(); ++i) {
    EXPECT_EQ(rig.scans[i].utime - rig.scans[i].device_utime, offset) << "scan " << i - before << " after the stall";
    EXPECT_EQ(rig.scans[i].device_utime - rig.scans[i - 1].device_utime, 40'000);
  }
  EXPECT_GT(rig.core.counters().device_clock_outliers, 0);
  EXPECT_EQ(rig.core.counters().device_clock_resets, 0);
}

TEST(ReaderCore, FailedConnectionsBackOffDoublingUpToTheMaximum) {
  Rig rig;
  rig.refuse = true;
  rig.run(25'000);
  std::vector<std::int64_t> waits_ms;
  for (std::size_t i = 1; i < rig.connect_times_us.size(); ++i)
    waits_ms.push_back((rig.connect_times_us[i] - rig.connect_times_us[i - 1]) / 1000);
  ASSERT_GE(waits_ms.size(), 8u);
  EXPECT_EQ(std::vector<std::int64_t>(waits_ms.begin(), waits_ms.begin() + 8),
            (std::vector<std::int64_t>{200, 400, 800, 1600, 3200, 5000, 5000, 5000}));
  EXPECT_EQ(rig.health.state, +pex::daemon_status_t::STATE_ERROR);
  EXPECT_EQ(rig.health.reason, "sensor 192.168.0.1:2111 unavailable: connection refused");
  ASSERT_GE(rig.errors.size(), 2u);
  EXPECT_EQ(rig.errors[0], (std::pair<std::string, std::string>{"connection", "connection refused; retry in 200 ms"}));
  EXPECT_EQ(rig.errors[1].second, "connection refused; retry in 400 ms");
  EXPECT_EQ(rig.core.counters().connect_attempts, static_cast<std::int64_t>(rig.connect_times_us.size()));
  EXPECT_EQ(rig.core.counters().disconnects, 0);  // never connected
  EXPECT_EQ(rig.closes, 0);
}

TEST(ReaderCore, BackOffStartsAgainOnceScansFlowed) {
  Rig rig;
  rig.refuse = true;
  rig.run(700);  // attempts at 0, 200 and 600 ms; the next at 1400 ms
  ASSERT_EQ(rig.connect_times_us.size(), 3u);
  EXPECT_EQ(rig.core.backoff_ms(), 1600);
  rig.refuse = false;
  rig.run(800);
  ASSERT_EQ(rig.connect_times_us.size(), 4u);
  ASSERT_TRUE(rig.streaming());
  EXPECT_EQ(rig.core.backoff_ms(), 200);
  rig.core.on_closed("", rig.now_us);
  EXPECT_EQ(rig.errors.back().second, "sensor closed the connection; retry in 200 ms");
  EXPECT_EQ(rig.health.reason, "sensor 192.168.0.1:2111 unavailable: sensor closed the connection");
  EXPECT_EQ(rig.closes, 1);
  EXPECT_EQ(rig.core.counters().disconnects, 1);
  const std::int64_t closed_us = rig.now_us;
  rig.run(300);
  ASSERT_EQ(rig.connect_times_us.size(), 5u);
  EXPECT_EQ(rig.connect_times_us.back() - closed_us, 200'000);
  EXPECT_TRUE(rig.streaming());
}

// A telegram cut by a lost connection does not run into the next connection's first one.
TEST(ReaderCore, PartTelegramOfALostConnectionIsForgotten) {
  Rig rig;
  rig.run(200);
  const std::string scan = cola::encode_scan_data(scan_data(70, rig.device_us()));
  rig.receive({scan.substr(0, scan.size() / 2)});
  rig.core.on_closed("Connection reset by peer", rig.now_us);
  EXPECT_EQ(rig.health.reason, "sensor 192.168.0.1:2111 unavailable: Connection reset by peer");
  rig.run(400);
  ASSERT_TRUE(rig.streaming());
  EXPECT_EQ(rig.core.counters().truncated_telegrams, 0);
  EXPECT_TRUE(rig.rejects.empty());
}

TEST(ReaderCore, StaleStreamIsDroppedAndTheSensorConfiguredAgain) {
  Rig rig;
  rig.run(1000);
  ASSERT_TRUE(rig.ok());
  const std::size_t scans = rig.scans.size();
  rig.device.stalled = true;  // connected, but no more scans (the laser hung)
  rig.run(1000);              // stale_timeout_ms = 1000 since the last scan
  EXPECT_TRUE(rig.streaming());
  EXPECT_EQ(rig.closes, 0);
  rig.run(40);
  EXPECT_EQ(rig.closes, 1);
  EXPECT_EQ(rig.core.counters().disconnects, 1);
  EXPECT_EQ(rig.health.state, +pex::daemon_status_t::STATE_ERROR);
  EXPECT_EQ(rig.health.reason, "sensor 192.168.0.1:2111 unavailable: no scan for 1000 ms");
  rig.device.stalled = false;
  rig.run(400);
  EXPECT_EQ(rig.core.counters().connect_attempts, 2);
  const auto configuring = std::count_if(rig.device.requests.begin(), rig.device.requests.end(),
                                         [](const std::string& r) { return r != "sRN LCMstate"; });
  EXPECT_EQ(configuring, static_cast<std::ptrdiff_t>(2 * kConfigureSequence.size()));
  EXPECT_GT(rig.scans.size(), scans);
  EXPECT_TRUE(rig.ok());
}

// The window's contamination (sRN LCMstate) is asked as soon as the scans
// stream and every contamination_poll_ms after: a warning or an error makes
// the reader DEGRADED, saying which, while the scans go on; a clean window
// again makes it OK.
TEST(ReaderCore, AsksTheWindowsContaminationAndSaysWhenItIsDirty) {
  Rig rig;
  auto asked = [&] { return std::count(rig.device.requests.begin(), rig.device.requests.end(), "sRN LCMstate"); };
  rig.run(20);
  ASSERT_TRUE(rig.streaming());
  EXPECT_EQ(asked(), 0);
  EXPECT_EQ(rig.core.counters().contamination_level, -1);
  rig.run(20);
  EXPECT_EQ(asked(), 1);
  EXPECT_EQ(rig.core.counters().contamination_level, 0);
  EXPECT_TRUE(rig.ok());
  rig.device.answers["LCMstate"] = cola::encode_reply("sRA", "LCMstate", {"2"});
  rig.run(9900);
  EXPECT_EQ(asked(), 1) << "asked again before contamination_poll_ms";
  EXPECT_TRUE(rig.ok());
  rig.run(200);
  EXPECT_EQ(asked(), 2);
  EXPECT_EQ(rig.core.counters().contamination_level, 2);
  EXPECT_EQ(rig.health.state, +pex::daemon_status_t::STATE_DEGRADED);
  EXPECT_EQ(rig.health.reason,
            "lens contamination error (LCMstate 2): the laser's window is dirty, echoes are lost; clean it");
  const std::size_t scans = rig.scans.size();
  rig.run(1000);
  EXPECT_GT(rig.scans.size(), scans + 20) << "the scans go on";
  EXPECT_EQ(rig.health.state, +pex::daemon_status_t::STATE_DEGRADED) << "each scan keeps the state";
  rig.device.answers["LCMstate"] = cola::encode_reply("sRA", "LCMstate", {"1"});
  rig.run(10000);
  EXPECT_EQ(rig.health.reason, "lens contamination warning (LCMstate 1): clean the laser's window");
  rig.device.answers["LCMstate"] = cola::encode_reply("sRA", "LCMstate", {"0"});
  rig.run(10000);
  EXPECT_TRUE(rig.ok());
  EXPECT_EQ(rig.core.counters().contamination_level, 0);
  EXPECT_EQ(rig.closes, 0);
  EXPECT_TRUE(rig.errors.empty());
}

// A device without the measurement refuses it (sFA): not asked again on that
// connection, and the scans are taken as ever. An answer out of range is
// refused and the last level kept; an answer that does not come is counted,
// and the connection stays (its scans flow).
TEST(ReaderCore, ARefusedUnansweredOrMalformedContaminationAnswerLeavesTheStreamAlone) {
  {
    Rig rig;
    rig.device.answers["LCMstate"] = cola::encode_reply("sFA", "", {"3"});
    rig.run(30000);
    EXPECT_EQ(std::count(rig.device.requests.begin(), rig.device.requests.end(), "sRN LCMstate"), 1);
    EXPECT_TRUE(rig.streaming());
    EXPECT_TRUE(rig.ok());
    EXPECT_EQ(rig.core.counters().contamination_level, -1);
    EXPECT_EQ(rig.core.counters().unexpected_replies, 0);
    EXPECT_NE(rig.notes.back().find("refused LCMstate (sFA 3)"), std::string::npos) << rig.notes.back();
  }
  {
    Rig rig;
    rig.run(40);
    ASSERT_EQ(rig.core.counters().contamination_level, 0);
    rig.device.answers["LCMstate"] = cola::encode_reply("sRA", "LCMstate", {"7"});
    rig.run(10000);
    EXPECT_EQ(rig.core.counters().contamination_level, 0) << "the last good level kept";
    ASSERT_EQ(rig.rejects.size(), 1u);
    EXPECT_EQ(rig.rejects[0].first, "contamination");
    EXPECT_TRUE(rig.ok());
  }
  {
    Rig rig;
    rig.device.answers["LCMstate"] = "";
    rig.run(2100);  // reply_timeout_ms = 2000 after the first request
    EXPECT_EQ(rig.core.counters().contamination_unanswered, 1);
    EXPECT_TRUE(rig.streaming());
    EXPECT_EQ(rig.closes, 0);
    rig.run(10000);
    EXPECT_EQ(std::count(rig.device.requests.begin(), rig.device.requests.end(), "sRN LCMstate"), 2);
    EXPECT_TRUE(rig.ok());
  }
}

TEST(ReaderCore, UnansweredRequestEndsTheConnectionAfterTheReplyTimeout) {
  Rig rig;
  rig.device.answers["Run"] = "";
  rig.run(2000);  // reply_timeout_ms = 2000
  EXPECT_EQ(rig.core.phase(), ReaderCore::Phase::kConfiguring);
  rig.run(40);
  EXPECT_EQ(rig.core.phase(), ReaderCore::Phase::kDisconnected);
  EXPECT_EQ(rig.closes, 1);
  EXPECT_EQ(rig.health.reason, "sensor 192.168.0.1:2111 unavailable: no answer to Run within 2000 ms");
}

TEST(ReaderCore, RefusedOrFailedConfigurationEndsTheConnection) {
  struct Case {
    std::string name, answer, reason;
  };
  for (const Case& c : {Case{"SetAccessMode", cola::encode_reply("sAN", "SetAccessMode", {"0"}),
                             "sensor answered SetAccessMode 0"},
                        Case{"mLMPsetscancfg", cola::encode_reply("sAN", "mLMPsetscancfg", {"1"}),
                             "sensor answered mLMPsetscancfg 1"},
                        Case{"LMDscandatacfg", cola::encode_reply("sFA", "", {"5"}),
                             "sensor refused LMDscandatacfg (sFA 5)"},
                        Case{"Run", cola::encode_reply("sAN", "Run", {"0"}), "sensor answered Run 0"}}) {
    Rig rig;
    rig.device.answers[c.name] = c.answer;
    rig.run(20);
    EXPECT_EQ(rig.core.phase(), ReaderCore::Phase::kDisconnected) << c.name;
    EXPECT_EQ(rig.closes, 1) << c.name;
    EXPECT_EQ(rig.health.reason, "sensor 192.168.0.1:2111 unavailable: " + c.reason);
    EXPECT_EQ(rig.device.requests.back().substr(4), c.name);  // nothing sent after the refusal
    EXPECT_TRUE(rig.scans.empty());
  }
}

TEST(ReaderCore, RequestThatCannotBeSentEndsTheConnection) {
  Rig rig;
  rig.send_fails = true;
  rig.run(20);
  EXPECT_EQ(rig.core.phase(), ReaderCore::Phase::kDisconnected);
  EXPECT_EQ(rig.closes, 1);
  EXPECT_EQ(rig.health.reason, "sensor 192.168.0.1:2111 unavailable: sending SetAccessMode: Broken pipe");
}

TEST(ReaderCore, LateOrStrayAnswersAreCountedAndTheAwaitedOneStillTaken) {
  Rig rig;
  rig.device.answers["SetAccessMode"] = cola::encode_reply("sWA", "LMPoutputRange") + rig.device.answers["SetAccessMode"];
  rig.run(20);
  EXPECT_EQ(rig.core.counters().unexpected_replies, 1);
  EXPECT_TRUE(rig.streaming());
  rig.receive({cola::encode_reply("sAN", "Run", {"1"})});  // while streaming
  EXPECT_EQ(rig.core.counters().unexpected_replies, 2);
  EXPECT_TRUE(rig.streaming());
}

TEST(ReaderCore, ScansBeforeTheConfigurationIsDoneAreNotPublished) {
  Rig rig;
  rig.device.answers["Run"] = cola::encode_scan_data(scan_data(7, 1000)) + rig.device.answers["Run"];
  rig.run(20);
  EXPECT_EQ(rig.core.counters().unexpected_scans, 1);
  EXPECT_TRUE(rig.scans.empty());
  EXPECT_TRUE(rig.streaming());
}

TEST(ReaderCore, MalformedTelegramIsCountedAndTheStreamGoesOn) {
  Rig rig;
  rig.run(200);
  ASSERT_TRUE(rig.ok());
  const std::size_t scans = rig.scans.size();
  // Device times a period apart, after the last scan's (a repeated one is
  // refused), and the rig's clock as far on.
  const std::uint32_t t = rig.device_us();
  std::string cut = cola::encode_scan_data(scan_data(100, t + 80'000));
  cut.erase(cut.size() / 2, cut.size() / 4);  // fields missing, still framed
  rig.now_us += 120'000;
  rig.receive({cola::encode_scan_data(scan_data(99, t + 40'000)), cut,
               cola::frame("sSN LMDscandata 1 1 ZZZ"), cola::encode_scan_data(scan_data(101, t + 120'000))});
  EXPECT_EQ(rig.core.counters().malformed_telegrams, 2);
  ASSERT_EQ(rig.rejects.size(), 2u);
  EXPECT_EQ(rig.rejects[0].first, "telegram");
  EXPECT_EQ(rig.rejects[0].second.rfind("malformed telegram: ", 0), 0u) << rig.rejects[0].second;
  ASSERT_EQ(rig.scans.size(), scans + 2);
  EXPECT_EQ(rig.scans[scans].scan_counter, 99);
  EXPECT_EQ(rig.scans[scans + 1].scan_counter, 101);
  EXPECT_TRUE(rig.ok());
  EXPECT_TRUE(rig.streaming());
  EXPECT_EQ(rig.closes, 0);
  rig.run(200);
  EXPECT_GT(rig.scans.size(), scans + 2);
}

TEST(ReaderCore, ScanWithoutDistancesIsRefusedAndTheStateKept) {
  Rig rig;
  rig.run(200);
  const std::size_t scans = rig.scans.size();
  cola::ScanData no_dist = scan_data(50, rig.device_us());
  no_dist.channels16.clear();
  rig.receive({cola::encode_scan_data(no_dist)});
  EXPECT_EQ(rig.scans.size(), scans);
  ASSERT_EQ(rig.rejects.size(), 1u);
  EXPECT_EQ(rig.rejects[0], (std::pair<std::string, std::string>{"scan", "scan telegram without a usable DIST1 channel"}));
  EXPECT_TRUE(rig.ok());
}

TEST(ReaderCore, TelegramsSplitAcrossReadsAreJoinedAndFramingProblemsCounted) {
  Rig rig;
  rig.run(200);
  const std::size_t scans = rig.scans.size();
  rig.now_us += 40'000;  // a period after the last scan
  const std::string scan = cola::encode_scan_data(scan_data(60, rig.device_us()));
  std::vector<std::string> reads;
  for (std::size_t at = 0; at < scan.size(); at += 100) reads.push_back(scan.substr(at, 100));
  rig.receive(reads);
  EXPECT_EQ(rig.scans.size(), scans + 1);
  // Garbage between telegrams, and a telegram cut off by the next one's STX.
  rig.now_us += 40'000;
  const std::string next = cola::encode_scan_data(scan_data(61, rig.device_us()));
  rig.receive({"noise", next.substr(0, 50), next});
  EXPECT_EQ(rig.scans.size(), scans + 2);
  EXPECT_TRUE(rig.rejects.empty());  // framing problems are reported by the poll ...
  rig.run(20);
  EXPECT_EQ(rig.core.counters().skipped_bytes, 5);
  EXPECT_EQ(rig.core.counters().truncated_telegrams, 1);
  ASSERT_EQ(rig.rejects.size(), 1u);  // ... once
  EXPECT_EQ(rig.rejects[0].second, "truncated or oversize telegram dropped");
  rig.run(100);
  EXPECT_EQ(rig.rejects.size(), 1u);
  EXPECT_TRUE(rig.ok());
}

TEST(ReaderCore, OversizeTelegramIsDroppedAndCounted) {
  ReaderOptions options;
  options.max_telegram_bytes = 1024;  // a full scan is ~4 KiB
  Rig rig(options);
  rig.run(100);
  EXPECT_TRUE(rig.scans.empty());
  EXPECT_TRUE(rig.streaming());
  EXPECT_GE(rig.core.counters().oversize_telegrams, 1);
  ASSERT_FALSE(rig.rejects.empty());
  EXPECT_EQ(rig.rejects[0].second, "truncated or oversize telegram dropped");
}

// Scans the configured sensor cannot send (issue 12's examples: a start angle
// of thousands of degrees, a 62 rad sweep, 10 000 beams over 1 deg, stamps
// minutes old, hundreds of scans a second) are refused and counted, and the
// stream goes on.
TEST(ReaderCore, ScansTheConfiguredSensorCannotSendAreRefusedAndCounted) {
  Rig rig;
  rig.run(200);
  ASSERT_TRUE(rig.streaming());
  const std::size_t published = rig.scans.size();
  ASSERT_GT(published, 0u);
  // Each one is a scan as the device would send it now, changed in one way.
  auto send = [&](const std::function<void(cola::ScanData&)>& change) {
    rig.now_us += 20'000;
    cola::ScanData s = scan_data(++rig.device.scan_counter, rig.device_us());
    change(s);
    rig.receive({cola::encode_scan_data(s)});
  };
  auto dist = [](cola::ScanData& s) -> cola::Channel& { return s.channels16[0]; };
  const std::vector<std::pair<std::string, std::function<void(cola::ScanData&)>>> cases = {
      {"start angle far out", [&](cola::ScanData& s) { dist(s).start_angle_1e4deg = 2'146'000'000; }},
      {"a 61 rad sweep", [&](cola::ScanData& s) { dist(s).angular_step_1e4deg = 65'000; }},
      {"10000 beams over 1 deg",
       [&](cola::ScanData& s) {
         dist(s).angular_step_1e4deg = 1;
         dist(s).data.assign(10'000, 1500);
         s.channels8.clear();
       }},
      {"another step than configured",
       [&](cola::ScanData& s) {
         dist(s).angular_step_1e4deg = 2500;
         dist(s).data.assign(1081, 1500);
         s.channels8.clear();
       }},
      {"another field of view",
       [&](cola::ScanData& s) {
         dist(s).start_angle_1e4deg = 0;
         dist(s).data.resize(361);
         s.channels8.clear();
       }},
      {"another frequency", [&](cola::ScanData& s) { s.scan_frequency_centihz = 5000; }},
      // Found by the fuzz target cola: ranges of -3e29 m were published.
      {"a negative scale factor", [&](cola::ScanData& s) { dist(s).scale_factor = -1e26f; }},
      {"a scale factor of 1000", [&](cola::ScanData& s) { dist(s).scale_factor = 1000.0f; }},
      {"an offset", [&](cola::ScanData& s) { dist(s).scale_offset = -5000.0f; }},
      {"the last scan's device time again",
       [&](cola::ScanData& s) {
         s.time_since_startup_us = static_cast<std::uint32_t>(rig.scans.back().device_utime);
         s.time_of_transmission_us = s.time_since_startup_us + kTransmissionDelayUs;
       }},
      {"a minute old",
       [&](cola::ScanData& s) {
         s.time_since_startup_us -= 60'000'000;
         s.time_of_transmission_us -= 60'000'000;
       }},
      {"71 minutes old (the device clock's wrap)",
       [&](cola::ScanData& s) {
         s.time_since_startup_us -= 4'260'000'000u;
         s.time_of_transmission_us -= 4'260'000'000u;
       }},
      {"a minute ahead",
       [&](cola::ScanData& s) {
         s.time_since_startup_us += 60'000'000;
         s.time_of_transmission_us += 60'000'000;
       }},
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const std::size_t rejects = rig.rejects.size();
    send(cases[i].second);
    EXPECT_EQ(rig.scans.size(), published) << cases[i].first << ": published";
    EXPECT_EQ(rig.core.counters().implausible_scans, static_cast<std::int64_t>(i + 1)) << cases[i].first;
    ASSERT_EQ(rig.rejects.size(), rejects + 1) << cases[i].first;
    EXPECT_EQ(rig.rejects.back().first, "implausible scan") << cases[i].first;
  }
  // The unchanged scan is taken, and the stream goes on.
  send([](cola::ScanData&) {});
  EXPECT_EQ(rig.scans.size(), published + 1);
  rig.run(200);
  EXPECT_GT(rig.scans.size(), published + 3);
  EXPECT_TRUE(rig.ok());
}

TEST(ReaderCore, WithoutConfiguringTheDeviceAnyLms1xxSetupIsTaken) {
  ReaderOptions options;
  options.configure_scan = false;
  Rig rig(options);
  rig.run(200);
  ASSERT_TRUE(rig.streaming());
  const std::size_t published = rig.scans.size();
  rig.now_us += 80'000;
  cola::ScanData s = scan_data(++rig.device.scan_counter, rig.device_us());
  s.channels16[0].angular_step_1e4deg = 2500;  // 0.25 deg over 270 deg
  s.channels16[0].data.assign(1081, 1500);
  s.channels8.clear();
  s.scan_frequency_centihz = 1500;
  rig.receive({cola::encode_scan_data(s)});
  EXPECT_EQ(rig.scans.size(), published + 1);
  EXPECT_EQ(rig.core.counters().implausible_scans, 0);
}

}  // namespace
}  // namespace pex::lidar_reader
