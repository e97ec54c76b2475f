#pragma once
// pex-viewer's options: every key of config/viewer.toml, read in one place.
#include <string>

#include "viewer_state.hpp"

namespace pex::runtime {
class ConfigReader;
}

namespace pex::viewer {

struct ViewerOptions {
  // Where the page is served. Loopback by default: the page commands the
  // mission, so it is opened to a network only on purpose.
  std::string bind_address = "127.0.0.1";  // an IPv4 address literal
  int port = 8080;
  double update_rate_hz = 10.0;            // events a second to each open page
  std::string pose_channel = "SLAM_POSE";  // a registered pex.pose_t channel (SIM_TRUTH for tests)
  double input_timeout_s = 3.0;            // no MAP or pose this long: DEGRADED
  int max_clients = 8;                     // open pages at once; more get 503
  ViewerStateOptions state;
};

// Reads and validates every key; throws runtime::ConfigError on a bad value.
ViewerOptions load_options(runtime::ConfigReader& config);

}  // namespace pex::viewer
