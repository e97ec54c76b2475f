// lidar_reader's config: the shipped file is read completely; bad values are refused.
#include <gtest/gtest.h>

#include "reader.hpp"
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
                           "angular_step_deg = 0.0\n", "connect_timeout_ms = \"soon\"\n"}) {
    auto config = runtime::ConfigReader::from_string(text, "bad.toml");
    EXPECT_THROW(load_options(config), runtime::ConfigError) << text;
  }
}

}  // namespace
}  // namespace pex::lidar_reader
