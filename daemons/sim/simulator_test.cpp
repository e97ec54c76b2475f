// The simulated LMS111's protocol side and the sim's config, without sockets.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "runtime/config.hpp"
#include "runtime/daemon.hpp"
#include "simulator.hpp"

namespace pex::simd {
namespace {

std::string body(const std::string& framed) { return framed.substr(1, framed.size() - 2); }

cola::Telegram request(const std::string& framed) {
  return std::get<cola::Telegram>(cola::split_telegram(body(framed)));
}

TEST(Lms111Protocol, AnswersTheReadersSequenceAsTheListingSays) {
  SimOptions options;
  Lms111Protocol protocol(options);
  ColaClient client;
  EXPECT_EQ(body(protocol.answer(client, request(cola::set_access_mode_request(3, cola::kPasswordAuthorizedClient)))),
            "sAN SetAccessMode 1");
  EXPECT_EQ(body(protocol.answer(client, request(cola::set_scan_config_request(cola::ScanConfig{})))),
            "sAN mLMPsetscancfg 0 9C4 1 1388 FFF92230 225510");
  cola::ScanDataConfig data;
  data.remission = true;
  data.remission_16bit = true;
  EXPECT_EQ(body(protocol.answer(client, request(cola::scan_data_config_request(data)))), "sWA LMDscandatacfg");
  EXPECT_TRUE(client.remission_16bit);
  EXPECT_EQ(body(protocol.answer(client, request(cola::output_range_request(cola::ScanConfig{})))),
            "sWA LMPoutputRange");
  EXPECT_EQ(body(protocol.answer(client, request(cola::start_measurement_request()))), "sAN LMCstartmeas 0");
  EXPECT_EQ(body(protocol.answer(client, request(cola::run_request()))), "sAN Run 1");
  EXPECT_EQ(client.access_level, 0);
  EXPECT_FALSE(client.streaming);
  EXPECT_EQ(body(protocol.answer(client, request(cola::scan_output_request(true)))), "sEA LMDscandata 1");
  EXPECT_TRUE(client.streaming);
}

TEST(Lms111Protocol, RefusesWhatADeviceRefuses) {
  SimOptions options;
  Lms111Protocol protocol(options);
  ColaClient client;
  // Configuration without login: access denied.
  EXPECT_EQ(body(protocol.answer(client, request(cola::set_scan_config_request(cola::ScanConfig{})))), "sFA 1");
  // Wrong password.
  EXPECT_EQ(body(protocol.answer(client, request(cola::set_access_mode_request(3, 0x12345678)))),
            "sAN SetAccessMode 0");
  EXPECT_EQ(client.access_level, 0);
  protocol.answer(client, request(cola::set_access_mode_request(3, cola::kPasswordAuthorizedClient)));
  // 50 Hz and 0.25 deg are not what this device is set up for: status 3.
  cola::ScanConfig other;
  other.frequency_centihz = 5000;
  other.angular_step_1e4deg = 2500;
  EXPECT_EQ(body(protocol.answer(client, request(cola::set_scan_config_request(other)))).substr(0, 21),
            "sAN mLMPsetscancfg 3 ");
  EXPECT_EQ(body(protocol.answer(client, request(cola::frame("sMN mLMPsetscancfg +2500 +1 +5000")))), "sFA 5");
  EXPECT_EQ(body(protocol.answer(client, request(cola::frame("sEN LMDscandata 2")))), "sFA 5");
  EXPECT_EQ(body(protocol.answer(client, request(cola::frame("sMN NoSuchMethod")))), "sFA 2");
  EXPECT_EQ(body(protocol.answer(client, request(cola::frame("sRN NoSuchVariable")))), "sFA 3");
  EXPECT_EQ(body(protocol.answer(client, request(cola::frame("sXX Foo")))), "sFA C");
}

TEST(Lms111Protocol, AnswersTheContaminationLevelItIsSet) {
  SimOptions options;
  Lms111Protocol protocol(options);
  ColaClient client;  // a read needs no login
  EXPECT_EQ(body(protocol.answer(client, request(cola::contamination_state_request()))), "sRA LCMstate 0");
  protocol.set_contamination_level(2);
  EXPECT_EQ(body(protocol.answer(client, request(cola::contamination_state_request()))), "sRA LCMstate 2");
}

TEST(Lms111Protocol, ScanTelegramRoundTripsToMetres) {
  SimOptions options;
  Lms111Protocol protocol(options);
  std::vector<float> ranges(541, 20.0f);  // max range = no echo
  ranges[0] = 0.5f;
  ranges[270] = 3.1234f;
  ranges[540] = std::numeric_limits<float>::quiet_NaN();
  protocol.begin_scan();
  const std::string bytes = cola::encode_scan_data(protocol.make_scan(ranges, 0xFFFFFFF0u, true, false));
  cola::StreamParser parser;
  auto events = parser.push(bytes);
  ASSERT_EQ(events.size(), 1u);
  const auto& scan = std::get<cola::ScanEvent>(events[0]).scan;
  EXPECT_EQ(scan.scan_counter, 1);
  EXPECT_EQ(scan.time_since_startup_us, 0xFFFFFFF0u);
  const cola::Channel* dist = scan.find_channel("DIST1");
  ASSERT_NE(dist, nullptr);
  EXPECT_EQ(dist->start_angle_1e4deg, -450000);  // device frame: -45 deg = 135 deg right of ahead
  EXPECT_EQ(dist->angular_step_1e4deg, 5000);
  auto metres = cola::distances_m(*dist);
  ASSERT_EQ(metres.size(), 541u);
  EXPECT_FLOAT_EQ(metres[0], 0.5f);
  EXPECT_NEAR(metres[270], 3.123f, 1e-6);
  EXPECT_TRUE(std::isnan(metres[1]));
  EXPECT_TRUE(std::isnan(metres[540]));
  const cola::Channel* rssi = scan.find_channel("RSSI1");
  ASSERT_NE(rssi, nullptr);
  EXPECT_EQ(rssi->data[1], 0);  // no echo, no remission
  EXPECT_GT(rssi->data[0], 200);
}

TEST(SimOptions, ShippedConfigLoadsAndBadValuesAreRefused) {
  auto config = runtime::ConfigReader::from_file(std::string(PEX_SOURCE_DIR) + "/config/sim.toml");
  runtime::load_runtime_options(config, /*is_clock_source=*/true);  // read by run_daemon
  SimOptions o = load_options(config);
  EXPECT_NO_THROW(config.finish());
  EXPECT_EQ(o.laser.beam_count(), 541);
  EXPECT_EQ(o.world_file, std::string(PEX_SOURCE_DIR) + "/config/../worlds/office.wkt");
  EXPECT_EQ(o.clock_rate_hz, 100.0);
  auto fast_clock = runtime::ConfigReader::from_string("physics_rate_hz = 200.0\nclock_rate_hz = 400.0\n", "clk.toml");
  EXPECT_THROW(load_options(fast_clock), runtime::ConfigError);
  auto bad = runtime::ConfigReader::from_string("[base]\ncan_transport = \"carrier-pigeon\"\n", "bad.toml");
  EXPECT_THROW(load_options(bad), runtime::ConfigError);
  auto same_ids = runtime::ConfigReader::from_string("[base]\nleft_node_id = 3\nright_node_id = 3\n", "ids.toml");
  EXPECT_THROW(load_options(same_ids), runtime::ConfigError);
  auto bad_start = runtime::ConfigReader::from_string("start_pose_m_m_rad = [1.0, 2.0]\n", "start.toml");
  EXPECT_THROW(load_options(bad_start), runtime::ConfigError);
}

}  // namespace
}  // namespace pex::simd
