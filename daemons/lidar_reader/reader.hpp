#pragma once
// pex-lidar-reader's shell: options from config/lidar_reader.toml, and the
// reader, which wires a ReaderCore (reader_core.hpp: all the logic) to the
// node (a 20 ms timer, LIDAR_SCAN, DAEMON_STATUS) and the TCP connection to
// the sensor. Timeouts and back-off run on the node's monotonic clock
// (simulated time with clock = "sim").
#include "hwio/hwio.hpp"
#include "reader_core.hpp"
#include "runtime/config.hpp"

namespace pex::runtime {
class Node;
}

namespace pex::lidar_reader {

ReaderOptions load_options(runtime::ConfigReader& config);

class Reader {
 public:
  Reader(runtime::Node& node, const ReaderOptions& options);

 private:
  ReaderOutputs outputs();
  // Hands what the socket has to the core until it would block or closes.
  void on_readable();
  // The core's counters into DAEMON_STATUS.

  runtime::Node& node_;
  hwio::Fd fd_;
  int watch_id_ = -1;
  ReaderCore core_;
};

}  // namespace pex::lidar_reader
