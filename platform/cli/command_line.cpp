#include "cli/command_line.hpp"

#include <sysexits.h>

#include <string>

namespace pex::cli {

std::optional<int> parse_command_line(CLI::App& app, std::string_view program, int argc, const char* const* argv) {
  app.name(std::string(program));
  app.set_version_flag("--version", std::string(program) + " " + PEX_VERSION);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version end here too: CLI11 prints them and gives 0.
    return app.exit(e) == 0 ? 0 : EX_USAGE;
  }
  return std::nullopt;
}

}  // namespace pex::cli
