// A daemon's TOML config file, as `--config` reads it: ConfigReader, the keys
// every daemon has (load_runtime_options), the daemon's own load_options and
// finish() (no unknown key).
//
// Input: byte 0 picks the daemon (lidar_reader, base_driver, slam,
// polygon_mapper, explorer, sim); the rest is the file's text.
// Invariants: nothing crashes, hangs or throws anything but ConfigError
// (exit 78 with one line naming the file and key).
#include <cstdint>
#include <exception>
#include <string>
#include <string_view>

#include "driver.hpp"
#include "explorer_options.hpp"
#include "fuzz_check.hpp"
#include "fuzz_input.hpp"
#include "mapper.hpp"
#include "reader.hpp"
#include "runtime/config.hpp"
#include "runtime/daemon.hpp"
#include "simulator.hpp"
#include "slam_options.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace pex;
  fuzz::Input in(data, size);
  const int daemon = in.byte() % 6;
  const std::string_view text = in.rest();
  // Relative paths in a config are taken from its folder: the shipped one, so
  // a seed made of a shipped file finds its world and data.
  const std::string origin = std::string(PEX_SOURCE_DIR) + "/config/fuzz.toml";
  try {
    auto config = runtime::ConfigReader::from_string(text, origin);
    (void)runtime::load_runtime_options(config, daemon == 5);
    switch (daemon) {
      case 0: (void)lidar_reader::load_options(config); break;
      case 1: (void)base_driver::load_options(config); break;
      case 2: (void)slam_daemon::load_options(config); break;
      case 3: (void)polygon_mapper::load_options(config); break;
      case 4: (void)explorer::load_options(config); break;
      default: (void)simd::load_options(config); break;
    }
    config.finish();
  } catch (const runtime::ConfigError& e) {
    PEX_FUZZ_CHECK(std::string_view(e.what()).find(origin) != std::string_view::npos,
                   std::string("a config error without the file: ") + e.what());
  } catch (const std::exception& e) {
    PEX_FUZZ_CHECK(false, std::string("not a ConfigError: ") + e.what());
  }
  return 0;
}
