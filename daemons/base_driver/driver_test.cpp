// base_driver's config: the shipped file is read completely; bad values are refused.
#include <gtest/gtest.h>

#include "driver.hpp"
#include "runtime/config.hpp"
#include "runtime/daemon.hpp"

namespace pex::base_driver {
namespace {

TEST(BaseDriverOptions, ShippedConfigLoadsCompletely) {
  auto config = runtime::ConfigReader::from_file(std::string(PEX_SOURCE_DIR) + "/config/base_driver.toml");
  runtime::load_runtime_options(config);  // read by run_daemon
  DriverOptions o = load_options(config);
  EXPECT_NO_THROW(config.finish());
  EXPECT_EQ(o.cmd_timeout_ms, 250);
  EXPECT_EQ(o.geometry.validate(), "");
  EXPECT_GE(o.odometry_rate_hz, 50.0);
}

TEST(BaseDriverOptions, BadValuesAreRefused) {
  for (const char* text : {"can_transport = \"usb\"\n", "left_node_id = 0\n", "left_node_id = 5\nright_node_id = 5\n",
                           "wheel_radius_m = -0.1\n", "cmd_timeout_ms = 0\n", "max_wheel_accel_mps2 = \"fast\"\n"}) {
    auto config = runtime::ConfigReader::from_string(text, "bad.toml");
    EXPECT_THROW(load_options(config), runtime::ConfigError) << text;
  }
}

}  // namespace
}  // namespace pex::base_driver
