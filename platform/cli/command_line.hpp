#pragma once
// The end of every program's command-line handling, daemons and tools alike,
// so each answers --version, --help and a bad command line the same way.
#include <optional>
#include <string_view>

#include <CLI/CLI.hpp>

namespace pex::cli {

// Call once every option of `app` is declared. Adds --version, which prints
// "<program> <package version>", then parses. Returns the exit code when the
// program ends here: 0 after --help or --version (their text on stdout), 64
// (EX_USAGE) for a bad command line (CLI11's message on stderr); nullopt when
// the options are read and the program goes on.
std::optional<int> parse_command_line(CLI::App& app, std::string_view program, int argc, const char* const* argv);

}  // namespace pex::cli
