// A bad config makes every daemon exit at start with EX_CONFIG (78) and one
// line naming the file and the key. Generated from the shipped configs, so a
// new key in config/<daemon>.toml is covered without touching this test.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <functional>
#include <thread>
#include <sstream>
#include <toml++/toml.h>

#include "harness.hpp"

using namespace pex::testing;
using namespace std::chrono_literals;
using testing::HasSubstr;
using testing::Not;

namespace {

constexpr int kExitConfig = 78;

RunResult run_with_config(const std::string& daemon, const std::string& toml_text,
                          const std::string& path) {
  write_file(path, toml_text);
  return run_to_completion({bin_path(program_of(daemon)), "--config", path, "--lcm-url", kTestLcmUrl},
                           10s);
}

std::string serialise(const toml::table& t) {
  std::ostringstream os;
  os << t;
  return os.str();
}

// Every leaf key of the table, as dotted paths.
void leaf_keys(const toml::table& t, const std::string& prefix, std::vector<std::string>& out) {
  for (const auto& [k, v] : t) {
    const std::string path = prefix + std::string(k.str());
    if (const auto* sub = v.as_table())
      leaf_keys(*sub, path + ".", out);
    else
      out.push_back(path);
  }
}

std::string robot_config_of(const std::string& daemon) {
  const std::string robot = source_path("config/robot/" + daemon + ".toml");
  return std::filesystem::exists(robot) ? robot : sim_config_of(daemon);
}

// Keys of the robot's config and of the simulator deployment's config together.
std::vector<std::string> shipped_keys(const std::string& daemon) {
  std::vector<std::string> keys;
  leaf_keys(toml::parse_file(robot_config_of(daemon)), "", keys);
  leaf_keys(toml::parse_file(sim_config_of(daemon)), "", keys);
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  return keys;
}

// The value a shipped config gives `key` (robot config first).
toml::table value_source(const std::string& daemon, const std::string& key) {
  toml::table robot = toml::parse_file(robot_config_of(daemon));
  if (robot.at_path(key).node()) return robot;
  return toml::parse_file(sim_config_of(daemon));
}

// The config file at `path` with relative `*_file` paths made absolute, so a
// copy in a temporary folder still finds the shipped data.
toml::table parse_with_absolute_paths(const std::string& path) {
  toml::table t = toml::parse_file(path);
  const std::string dir = path.substr(0, path.rfind('/') + 1);
  std::function<void(toml::table&)> fix = [&](toml::table& tbl) {
    for (auto&& [k, v] : tbl) {
      if (auto* sub = v.as_table()) {
        fix(*sub);
      } else if (auto* str = v.as_string(); str && k.str().ends_with("_file")) {
        const std::string value = str->get();
        if (!value.empty() && value.front() != '/') *str = dir + value;
      }
    }
  };
  fix(t);
  return t;
}

// The simulator deployment's config (the one every daemon can start with on
// this machine) with `key` set to `value`, creating its [section] if needed.
template <class V>
toml::table sim_config_with(const std::string& daemon, const std::string& key, V value) {
  toml::table t = parse_with_absolute_paths(sim_config_of(daemon));
  toml::table* parent = &t;
  std::string rest = key;
  for (auto dot = rest.find('.'); dot != std::string::npos; dot = rest.find('.')) {
    const std::string section = rest.substr(0, dot);
    if (!parent->contains(section)) parent->insert(section, toml::table{});
    parent = (*parent)[section].as_table();
    rest = rest.substr(dot + 1);
  }
  parent->insert_or_assign(rest, value);
  return t;
}

class BadConfig : public testing::TestWithParam<std::string> {
 protected:
  void SetUp() override { dir_ = make_temp_dir("badcfg"); }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string dir_;
};

}  // namespace

// The robot's configs name devices this machine does not have (SocketCAN, the
// real laser's address); the simulator deployment's config must start here.
TEST_P(BadConfig, SimulatorDeploymentConfigStarts) {
  {
    const std::string cfg = sim_config_of(GetParam());
    const std::string log = dir_ + "/ok.log";
    Bus bus;
    Process p({bin_path(program_of(GetParam())), "--config", cfg, "--lcm-url", kTestLcmUrl}, log);
    // Up: its first DAEMON_STATUS is on the bus (whatever its state: the
    // daemons on the simulator's clock wait for it, DEGRADED).
    const bool up = bus.spin_until([&] { return bus.status().count(GetParam()) > 0 || !p.running(); }, 30s);
    const bool alive = p.running();
    const int code = p.stop();
    EXPECT_TRUE(up && alive) << cfg << "\n" << p.output();
    EXPECT_EQ(code, 0) << cfg << "\n" << p.output();
  }
}

TEST_P(BadConfig, UnknownKeyExits78NamingFileAndKey) {
  const std::string path = dir_ + "/unknown.toml";
  toml::table t = parse_with_absolute_paths(sim_config_of(GetParam()));
  t.insert("max_sped_mps", 1.0);  // misspelt max_speed_mps
  const auto r = run_with_config(GetParam(), serialise(t), path);
  EXPECT_EQ(r.exit_code, kExitConfig) << r.output;
  EXPECT_THAT(r.output, HasSubstr(path));
  EXPECT_THAT(r.output, HasSubstr("max_sped_mps"));
}

// Every daemon names itself as installed (pex-polygon-mapper, not
// pex-polygon_mapper) and says its version.
TEST_P(BadConfig, VersionAndHelpNameTheProgramAsInstalled) {
  const std::string program = program_of(GetParam());
  const auto version = run_to_completion({bin_path(program), "--version"});
  EXPECT_EQ(version.exit_code, 0) << version.output;
  EXPECT_THAT(version.output, HasSubstr(program + " " + PEX_VERSION));
  const auto help = run_to_completion({bin_path(program), "--help"});
  EXPECT_EQ(help.exit_code, 0) << help.output;
  EXPECT_THAT(help.output, HasSubstr(program));
  if (GetParam().find('_') != std::string::npos) {
    EXPECT_THAT(help.output, Not(HasSubstr("pex-" + GetParam())));
  }
  const auto bad_flag = run_to_completion({bin_path(program), "--no-such-flag"});
  EXPECT_EQ(bad_flag.exit_code, 64) << bad_flag.output;
}

TEST_P(BadConfig, NegativeHeartbeatPeriodExits78) {
  const std::string path = dir_ + "/neg.toml";
  const auto r = run_with_config(GetParam(), "heartbeat_period_ms = -5\n", path);
  EXPECT_EQ(r.exit_code, kExitConfig) << r.output;
  EXPECT_THAT(r.output, HasSubstr(path));
  EXPECT_THAT(r.output, HasSubstr("heartbeat_period_ms"));
  EXPECT_THAT(r.output, HasSubstr("-5"));
}

TEST_P(BadConfig, EveryShippedKeyWithAWrongTypeExits78) {
  for (const auto& key : shipped_keys(GetParam())) {
    const toml::table source = value_source(GetParam(), key);
    const toml::node* n = source.at_path(key).node();
    ASSERT_NE(n, nullptr) << key;
    const toml::table bad = n->is_string() ? sim_config_with(GetParam(), key, 12345)
                                           : sim_config_with(GetParam(), key, "not-a-number");
    const std::string path = dir_ + "/wrongtype.toml";
    const auto r = run_with_config(GetParam(), serialise(bad), path);
    EXPECT_EQ(r.exit_code, kExitConfig) << key << ":\n" << r.output;
    EXPECT_THAT(r.output, HasSubstr(key)) << r.output;
  }
}

TEST_P(BadConfig, EveryShippedDurationOrRateKeyRejectsNegativeValues) {
  for (const auto& key : shipped_keys(GetParam())) {
    const bool is_time = key.ends_with("_ms") || key.ends_with("_s") || key.ends_with("_hz");
    const toml::table source = value_source(GetParam(), key);
    const toml::node* n = source.at_path(key).node();
    if (!is_time || !(n->is_integer() || n->is_floating_point())) continue;
    const toml::table bad = n->is_integer() ? sim_config_with(GetParam(), key, int64_t{-5})
                                            : sim_config_with(GetParam(), key, -5.0);
    const std::string path = dir_ + "/negative.toml";
    const auto r = run_with_config(GetParam(), serialise(bad), path);
    EXPECT_EQ(r.exit_code, kExitConfig) << key << ":\n" << r.output;
    EXPECT_THAT(r.output, HasSubstr(key)) << r.output;
  }
}

TEST_P(BadConfig, SyntaxErrorExits78NamingFile) {
  const std::string path = dir_ + "/syntax.toml";
  const auto r = run_with_config(GetParam(), "heartbeat_period_ms = = 3\n", path);
  EXPECT_EQ(r.exit_code, kExitConfig) << r.output;
  EXPECT_THAT(r.output, HasSubstr(path));
}

TEST_P(BadConfig, HelpDescribesTheCommonOptions) {
  const auto r = run_to_completion({bin_path(program_of(GetParam())), "--help"});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_THAT(r.output, HasSubstr("--config"));
  EXPECT_THAT(r.output, HasSubstr("--lcm-url"));
  EXPECT_THAT(r.output, HasSubstr("--log-level"));
}

INSTANTIATE_TEST_SUITE_P(EveryDaemon, BadConfig, testing::ValuesIn(kAllDaemons),
                         [](const auto& info) { return info.param; });
// pex-viewer is no daemon of the exploration set (nothing depends on it) but
// reads its config the same way.
INSTANTIATE_TEST_SUITE_P(Viewer, BadConfig, testing::Values("viewer"), [](const auto& info) { return info.param; });

// The robot's base driver config (config/base_driver.toml and the robot's overlay over
// it, as the unit reads them) names SocketCAN interface can0, which this machine cannot have: the driver must refuse to start with EX_UNAVAILABLE (69)
// and say which interface and what to load, not crash.
TEST(RobotConfig, BaseDriverWithoutSocketCanExits69NamingTheInterface) {
  const auto r = run_to_completion({bin_path("pex-base-driver"), "--config", source_path("config/base_driver.toml"),
                                    "--config", source_path("config/robot/base_driver.toml"), "--lcm-url", kTestLcmUrl});
  EXPECT_EQ(r.exit_code, 69) << r.output;
  EXPECT_THAT(r.output, HasSubstr("can0"));
}
