#pragma once
// Typed, validated configuration from TOML (toml++).
//
// Contract: every key has a default in code; a key in the file must be read by
// the daemon (ConfigReader::finish() rejects unknown keys, as Cartographer's
// parameter dictionary does); a value of the wrong type or outside its
// constraint throws ConfigError whose message names the file, the key and the
// bad value, in one line. Keys carry their unit in the name (`timeout_ms`).
//
// Layering, the one rule (docs/deployment.md): the defaults in code, then each
// file given in order (`--config A --config B`), key by key: a key takes the value of
// the last file that sets it, else its default. So a robot overlay (config/robot/X.toml)
// need hold only what differs from config/X.toml, and a file given last (on the robot
// /etc/polyexplore/X.toml) wins over both. Arrays are values (replaced whole), tables
// merge. A relative path is taken relative to the folder of the file that set it.
// effective() lists every key read with its value and where it came from
// (`pex-<daemon> --print-config`).
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace pex::runtime {

class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A constraint returns an error text for a bad value, nothing for a good one.
template <class T>
using Constraint = std::function<std::optional<std::string>(const T&)>;

template <class T>
Constraint<T> positive() {
  return [](const T& v) -> std::optional<std::string> {
    if (v > T{}) return std::nullopt;
    return "must be > 0";
  };
}
template <class T>
Constraint<T> non_negative() {
  return [](const T& v) -> std::optional<std::string> {
    if (v >= T{}) return std::nullopt;
    return "must be >= 0";
  };
}
template <class T>
Constraint<T> in_range(T lo, T hi) {
  return [lo, hi](const T& v) -> std::optional<std::string> {
    if (v >= lo && v <= hi) return std::nullopt;
    return "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  };
}
Constraint<std::string> one_of(std::vector<std::string> allowed);
// The name of a channel in the registry (runtime/channels.hpp) whose type is
// `type` ("pex.pose_t"); `names` (e.g. "SLAM_POSE or SIM_TRUTH") go into the error text.
Constraint<std::string> registered_channel_of_type(std::string type, std::string names);

class ConfigReader {
 public:
  // An empty configuration: every get() returns its default (no file given).
  ConfigReader();
  // Throws ConfigError if the file cannot be read or is not valid TOML.
  static ConfigReader from_file(const std::string& path);
  // The layers, lowest first (an empty list: the defaults). Throws ConfigError for a
  // file that cannot be read, is not valid TOML, or makes a table of an earlier value.
  static ConfigReader from_files(const std::vector<std::string>& paths);
  static ConfigReader from_string(std::string_view toml_text, std::string origin);

  // Value at `key` (in this reader's table) or `default_value` if absent.
  // Supported T: bool, int, int64_t, double, std::string, std::vector<double>,
  // std::vector<std::string>. Integers are accepted where a double is asked.
  template <class T>
  T get(std::string_view key, T default_value, Constraint<T> check = {});

  // A file path: relative paths are taken relative to the config file's folder,
  // so a shipped config finds shipped data from any working directory. With
  // `must_exist`, a path that cannot be opened for reading is a ConfigError.
  std::string get_path(std::string_view key, std::string default_value, bool must_exist = true);

  // Throws ConfigError naming the file and `key` (for checks done after get()).
  [[noreturn]] void fail(std::string_view key, const std::string& what) const;

  // A nested table `[name]`; absent tables read as empty (all defaults).
  ConfigReader section(std::string_view name) const;
  bool has(std::string_view key) const;

  // Throws ConfigError naming every key of the file that nobody read.
  void finish() const;

  // The file name (or "<defaults>") that errors name; several files: "A + B".
  const std::string& origin() const;

  // A key read so far: its value as TOML text and where the value came from.
  struct Effective {
    std::string key;     // dotted path: "map.obstacle_end_trim_m"
    std::string value;   // TOML: 0.05, "sim", [1.0, 2.0], true
    std::string source;  // "default" or "FILE:LINE"
  };
  // Every key read, in the order the daemon read them.
  std::vector<Effective> effective() const;
  // effective() as a TOML file, each value with its source in a comment (itself a
  // valid config: the same daemon reads it back to the same values).
  std::string effective_toml() const;

 private:
  struct State;  // the parsed toml++ table and the keys read so far
  ConfigReader(std::shared_ptr<State> state, std::string prefix);
  std::string path_of(std::string_view key) const;
  void note_effective(const std::string& path, std::string value);
  static void add_layer(State& state, const void* toml_table, const std::string& file);

  std::shared_ptr<State> state_;
  std::string prefix_;  // "" or "section." for nested readers
};

}  // namespace pex::runtime
