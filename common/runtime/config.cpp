#include "runtime/config.hpp"

#include "runtime/channels.hpp"

#include <toml++/toml.h>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>

namespace pex::runtime {

struct ConfigReader::State {
  std::string origin;
  toml::table root;
  std::set<std::string> read_keys;  // dotted paths of every key asked for
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

ConfigReader ConfigReader::from_file(const std::string& path) {
  auto state = std::make_shared<State>();
  state->origin = path;
  try {
    state->root = toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    std::ostringstream os;
    os << path << ":" << e.source().begin.line << ":" << e.source().begin.column << ": "
       << e.description();
    throw ConfigError(os.str());
  }
  return ConfigReader(std::move(state), "");
}

ConfigReader ConfigReader::from_string(std::string_view toml_text, std::string origin) {
  auto state = std::make_shared<State>();
  state->origin = std::move(origin);
  try {
    state->root = toml::parse(toml_text, state->origin);
  } catch (const toml::parse_error& e) {
    std::ostringstream os;
    os << state->origin << ":" << e.source().begin.line << ": " << e.description();
    throw ConfigError(os.str());
  }
  return ConfigReader(std::move(state), "");
}

const std::string& ConfigReader::origin() const { return state_->origin; }

std::string ConfigReader::path_of(std::string_view key) const {
  return prefix_ + std::string(key);
}

void ConfigReader::fail(std::string_view key, const std::string& what) const {
  throw ConfigError(state_->origin + ": key '" + path_of(key) + "': " + what);
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

template <class T>
std::string to_text(const T& v) {
  std::ostringstream os;
  if constexpr (std::is_same_v<T, std::vector<double>>) {
    os << "[";
    for (size_t i = 0; i < v.size(); ++i) os << (i ? ", " : "") << v[i];
    os << "]";
  } else if constexpr (std::is_same_v<T, std::vector<std::string>>) {
    os << "[";
    for (size_t i = 0; i < v.size(); ++i) os << (i ? ", " : "") << '"' << v[i] << '"';
    os << "]";
  } else if constexpr (std::is_same_v<T, std::string>) {
    os << '"' << v << '"';
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
  const std::string& file = state_->origin;
  const auto slash = file.rfind('/');
  if (!path.empty() && path.front() != '/' && file.front() != '<')
    path = (slash == std::string::npos ? std::string() : file.substr(0, slash + 1)) + path;
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
  std::string text = state_->origin + ": unknown key";
  text += unknown.size() > 1 ? "s" : "";
  for (size_t i = 0; i < unknown.size(); ++i) text += (i ? ", '" : " '") + unknown[i] + "'";
  text += " (misspelt, or not a setting of this daemon)";
  throw ConfigError(text);
}

}  // namespace pex::runtime
