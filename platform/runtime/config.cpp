#include "runtime/config.hpp"

#include "runtime/channels.hpp"

#include <toml++/toml.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>

namespace pex::runtime {

struct ConfigReader::State {
  std::string origin;
  toml::table root;                 // the layers merged
  std::set<std::string> read_keys;  // dotted paths of every key asked for
  struct Source {
    std::string file;
    int line = 0;
  };
  std::map<std::string, Source> sources;  // dotted path of every value in root -> the file that set it
  std::vector<Effective> effective;       // every key read, in order
  std::map<std::string, std::size_t> effective_index;
  // The file that set `path` ("" if none: a default).
  std::string file_of(const std::string& path) const {
    const auto it = sources.find(path);
    return it == sources.end() ? std::string() : it->second.file;
  }
};

Constraint<std::string> one_of(std::vector<std::string> allowed) {
  return [allowed](const std::string& v) -> std::optional<std::string> {
    for (const auto& a : allowed)
      if (a == v) return std::nullopt;
    std::string text = "must be one of";
    for (const auto& a : allowed) text += " \"" + a + "\"";
    return text;
  };
}

Constraint<std::string> registered_channel_of_type(std::string type, std::string names) {
  return [type, names](const std::string& name) -> std::optional<std::string> {
    const auto* info = channels::find(name);
    if (info && info->type == type) return std::nullopt;
    return "must be a registered channel of type " + type + " (" + names + ")";
  };
}

ConfigReader::ConfigReader() : ConfigReader(std::make_shared<State>(), "") {
  state_->origin = "<defaults>";
}

ConfigReader::ConfigReader(std::shared_ptr<State> state, std::string prefix)
    : state_(std::move(state)), prefix_(std::move(prefix)) {}

// `toml_table` (a toml::table) over state.root: values replace, tables merge; every
// value's file and line noted.
void ConfigReader::add_layer(State& state, const void* toml_table, const std::string& file) {
  std::function<void(toml::table&, const toml::table&, const std::string&)> merge =
      [&](toml::table& into, const toml::table& from, const std::string& prefix) {
        for (const auto& [k, v] : from) {
          const std::string key(k.str());
          const std::string dotted = prefix + key;
          toml::node* existing = into.get(key);
          if (const toml::table* sub = v.as_table()) {
            if (existing && !existing->is_table())
              throw ConfigError(file + ": '" + dotted + "' is a table here but a value in " + state.file_of(dotted));
            if (!existing) into.insert(key, toml::table{});
            merge(*into.get(key)->as_table(), *sub, dotted + ".");
            continue;
          }
          if (existing && existing->is_table())
            throw ConfigError(file + ": '" + dotted + "' is a value here but a table in an earlier file");
          v.visit([&](const auto& value) { into.insert_or_assign(key, value); });
          state.sources[dotted] = {file, static_cast<int>(v.source().begin.line)};
        }
      };
  merge(state.root, *static_cast<const toml::table*>(toml_table), "");
}

ConfigReader ConfigReader::from_file(const std::string& path) { return from_files({path}); }

ConfigReader ConfigReader::from_files(const std::vector<std::string>& paths) {
  if (paths.empty()) return ConfigReader();
  auto state = std::make_shared<State>();
  for (const auto& path : paths) state->origin += (state->origin.empty() ? "" : " + ") + path;
  for (const auto& path : paths) {
    toml::table layer;
    try {
      layer = toml::parse_file(path);
    } catch (const toml::parse_error& e) {
      std::ostringstream os;
      os << path << ":" << e.source().begin.line << ":" << e.source().begin.column << ": "
         << e.description();
      throw ConfigError(os.str());
    }
    add_layer(*state, &layer, path);
  }
  return ConfigReader(std::move(state), "");
}

ConfigReader ConfigReader::from_string(std::string_view toml_text, std::string origin) {
  auto state = std::make_shared<State>();
  state->origin = std::move(origin);
  toml::table layer;
  try {
    layer = toml::parse(toml_text, state->origin);
  } catch (const toml::parse_error& e) {
    std::ostringstream os;
    os << state->origin << ":" << e.source().begin.line << ": " << e.description();
    throw ConfigError(os.str());
  }
  add_layer(*state, &layer, state->origin);
  return ConfigReader(std::move(state), "");
}

const std::string& ConfigReader::origin() const { return state_->origin; }

std::string ConfigReader::path_of(std::string_view key) const {
  return prefix_ + std::string(key);
}

void ConfigReader::fail(std::string_view key, const std::string& what) const {
  // the file that set the key, when several are layered
  const std::string file = state_->file_of(path_of(key));
  throw ConfigError((file.empty() ? state_->origin : file) + ": key '" + path_of(key) + "': " + what);
}

namespace {

const toml::node* lookup(const toml::table& root, const std::string& dotted) {
  return root.at_path(dotted).node();
}

std::string describe(const toml::node& n) {
  std::ostringstream os;
  if (n.is_string())
    os << '"' << *n.value<std::string>() << '"';
  else if (n.is_table())
    os << "a table";
  else if (n.is_array())
    os << "an array";
  else
    n.visit([&](auto&& v) { os << v; });
  return os.str();
}

// A double as TOML, the shortest text that reads back to the same value, always
// with a point or exponent (1.0, not 1: TOML's float).
std::string double_text(double v) {
  char buf[40];
  for (int precision = 1; precision <= 17; ++precision) {
    std::snprintf(buf, sizeof buf, "%.*g", precision, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  std::string text = buf;
  if (text.find_first_of(".eEni") == std::string::npos) text += ".0";  // not inf/nan either
  return text;
}

// A TOML basic string: "...", with \\, \" and control characters escaped.
std::string string_text(const std::string& v) {
  std::string out = "\"";
  for (const char ch : v) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += ch;
    } else if (c < 0x20 || c == 0x7F) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04X", c);
      out += buf;
    } else {
      out += ch;
    }
  }
  return out + "\"";
}

template <class T>
std::string to_text(const T& v) {
  std::ostringstream os;
  if constexpr (std::is_same_v<T, std::vector<double>>) {
    os << "[";
    for (size_t i = 0; i < v.size(); ++i) os << (i ? ", " : "") << double_text(v[i]);
    os << "]";
  } else if constexpr (std::is_same_v<T, std::vector<std::string>>) {
    os << "[";
    for (size_t i = 0; i < v.size(); ++i) os << (i ? ", " : "") << string_text(v[i]);
    os << "]";
  } else if constexpr (std::is_same_v<T, std::string>) {
    os << string_text(v);
  } else if constexpr (std::is_same_v<T, double>) {
    os << double_text(v);
  } else if constexpr (std::is_same_v<T, bool>) {
    os << (v ? "true" : "false");
  } else {
    os << v;
  }
  return os.str();
}

}  // namespace

template <class T>
T ConfigReader::get(std::string_view key, T default_value, Constraint<T> check) {
  const std::string path = path_of(key);
  state_->read_keys.insert(path);
  const toml::node* node = lookup(state_->root, path);
  T value = default_value;
  if (node) {
    auto wrong_type = [&](const char* expected) {
      fail(key, std::string("expected ") + expected + ", got " + describe(*node));
    };
    if constexpr (std::is_same_v<T, bool>) {
      if (!node->is_boolean()) wrong_type("true or false");
      value = *node->value<bool>();
    } else if constexpr (std::is_same_v<T, int> || std::is_same_v<T, int64_t>) {
      if (!node->is_integer()) wrong_type("an integer");
      const int64_t v = *node->value<int64_t>();
      if constexpr (std::is_same_v<T, int>) {
        if (v < INT32_MIN || v > INT32_MAX) fail(key, "integer out of range: " + describe(*node));
      }
      value = static_cast<T>(v);
    } else if constexpr (std::is_same_v<T, double>) {
      if (!node->is_floating_point() && !node->is_integer()) wrong_type("a number");
      value = *node->value<double>();
    } else if constexpr (std::is_same_v<T, std::string>) {
      if (!node->is_string()) wrong_type("a string");
      value = *node->value<std::string>();
    } else if constexpr (std::is_same_v<T, std::vector<double>>) {
      const toml::array* arr = node->as_array();
      if (!arr) wrong_type("an array of numbers");
      value.clear();
      for (const auto& el : *arr) {
        if (!el.is_floating_point() && !el.is_integer()) wrong_type("an array of numbers");
        value.push_back(*el.value<double>());
      }
    } else if constexpr (std::is_same_v<T, std::vector<std::string>>) {
      const toml::array* arr = node->as_array();
      if (!arr) wrong_type("an array of strings");
      value.clear();
      for (const auto& el : *arr) {
        if (!el.is_string()) wrong_type("an array of strings");
        value.push_back(*el.value<std::string>());
      }
    }
  }
  if constexpr (std::is_same_v<T, double>) {
    if (!std::isfinite(value)) fail(key, "must be finite, got " + to_text(value));
  }
  if (check) {
    if (auto err = check(value)) fail(key, *err + ", got " + to_text(value));
  }
  note_effective(path, to_text(value));
  return value;
}

template bool ConfigReader::get<bool>(std::string_view, bool, Constraint<bool>);
template int ConfigReader::get<int>(std::string_view, int, Constraint<int>);
template int64_t ConfigReader::get<int64_t>(std::string_view, int64_t, Constraint<int64_t>);
template double ConfigReader::get<double>(std::string_view, double, Constraint<double>);
template std::string ConfigReader::get<std::string>(std::string_view, std::string,
                                                    Constraint<std::string>);
template std::vector<double> ConfigReader::get<std::vector<double>>(
    std::string_view, std::vector<double>, Constraint<std::vector<double>>);
template std::vector<std::string> ConfigReader::get<std::vector<std::string>>(
    std::string_view, std::vector<std::string>, Constraint<std::vector<std::string>>);

std::string ConfigReader::get_path(std::string_view key, std::string default_value, bool must_exist) {
  std::string path = get<std::string>(key, std::move(default_value));
  // relative to the folder of the file that set it (a default: as it is)
  const std::string file = state_->file_of(path_of(key));
  const auto slash = file.rfind('/');
  if (!path.empty() && path.front() != '/' && !file.empty()) {
    path = (slash == std::string::npos ? std::string() : file.substr(0, slash + 1)) + path;
    note_effective(path_of(key), string_text(path));
  }
  if (must_exist && !path.empty() && !std::ifstream(path).good())
    fail(key, "cannot read '" + path + "'");
  return path;
}

ConfigReader ConfigReader::section(std::string_view name) const {
  const std::string path = path_of(name);
  if (const toml::node* node = lookup(state_->root, path); node && !node->is_table())
    fail(name, "expected a table [" + path + "], got " + describe(*node));
  return ConfigReader(state_, path + ".");
}

bool ConfigReader::has(std::string_view key) const {
  return lookup(state_->root, path_of(key)) != nullptr;
}

void ConfigReader::note_effective(const std::string& path, std::string value) {
  std::string source = "default";
  if (const auto it = state_->sources.find(path); it != state_->sources.end())
    source = it->second.file + ":" + std::to_string(it->second.line);
  const auto [it, inserted] = state_->effective_index.emplace(path, state_->effective.size());
  if (inserted) state_->effective.push_back({path, std::move(value), std::move(source)});
  else state_->effective[it->second] = {path, std::move(value), std::move(source)};
}

std::vector<ConfigReader::Effective> ConfigReader::effective() const { return state_->effective; }

std::string ConfigReader::effective_toml() const {
  std::size_t width = 0;
  for (const auto& e : state_->effective) width = std::max(width, e.key.size() + 3 + e.value.size());
  std::string out;
  for (const auto& e : state_->effective) {
    std::string line = e.key + " = " + e.value;
    line.resize(std::max(line.size(), width), ' ');
    out += line + "  # " + e.source + "\n";
  }
  return out;
}

void ConfigReader::finish() const {
  std::vector<std::string> unknown;
  // Walk every leaf; a table counts as read when any key below it was read.
  std::function<void(const toml::table&, const std::string&)> walk =
      [&](const toml::table& t, const std::string& prefix) {
        for (const auto& [k, v] : t) {
          const std::string path = prefix + std::string(k.str());
          if (const toml::table* sub = v.as_table())
            walk(*sub, path + ".");
          else if (!state_->read_keys.count(path))
            unknown.push_back(path);
        }
      };
  walk(state_->root, "");
  if (unknown.empty()) return;
  // the file of the first unknown key (several files: the one that has it)
  const std::string file = state_->file_of(unknown.front());
  std::string text = (file.empty() ? state_->origin : file) + ": unknown key";
  text += unknown.size() > 1 ? "s" : "";
  for (size_t i = 0; i < unknown.size(); ++i) text += (i ? ", '" : " '") + unknown[i] + "'";
  text += " (misspelt, or not a setting of this daemon)";
  throw ConfigError(text);
}

}  // namespace pex::runtime
