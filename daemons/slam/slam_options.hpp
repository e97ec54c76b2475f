#pragma once
// Reads config/slam.toml into SlamNodeOptions: every key has the library's
// default and is validated; the file documents each key.
#include "runtime/config.hpp"
#include "slam_node.hpp"

namespace pex::slam_daemon {

SlamNodeOptions load_options(runtime::ConfigReader& config);

}  // namespace pex::slam_daemon
