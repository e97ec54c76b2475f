// pex-slam: skeleton until its issue lands. It starts, loads its config,
// publishes DAEMON_STATUS, and does nothing else (and says so at start).
#include <spdlog/spdlog.h>

#include "runtime/daemon.hpp"

int main(int argc, char** argv) {
  return pex::runtime::run_daemon(argc, argv, {"slam", "slam (skeleton: not implemented yet)"},
                                  [](pex::runtime::Node&, pex::runtime::ConfigReader&) {
                                    spdlog::warn("slam is a skeleton: it only reports its health");
                                  });
}
