#include "runtime/config.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <tuple>
#include <toml++/toml.h>

using pex::runtime::ConfigError;
using pex::runtime::ConfigReader;
using testing::AllOf;
using testing::HasSubstr;

namespace {

// Runs `fn` and returns the ConfigError text it throws ("" if none).
template <class Fn>
std::string error_of(Fn fn) {
  try {
    fn();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(ConfigReader, ReturnsDefaultsForAbsentKeys) {
  ConfigReader c = ConfigReader::from_string("", "x.toml");
  EXPECT_EQ(c.get<double>("max_range_m", 20.0), 20.0);
  EXPECT_EQ(c.get<int>("beams_count", 541), 541);
  EXPECT_EQ(c.get<std::string>("mode", "sim"), "sim");
  EXPECT_NO_THROW(c.finish());
}

TEST(ConfigReader, ReadsValuesOfEachType) {
  ConfigReader c = ConfigReader::from_string(
      "max_range_m = 8\nrate_hz = 2.5\non = true\nname = \"a\"\nxs_m = [1, 2.5]\n"
      "[can]\nnode_ids = [\"1\", \"2\"]\ntimeout_ms = 250\n",
      "x.toml");
  EXPECT_EQ(c.get<double>("max_range_m", 1.0), 8.0);  // integer accepted as double
  EXPECT_EQ(c.get<double>("rate_hz", 1.0), 2.5);
  EXPECT_TRUE(c.get<bool>("on", false));
  EXPECT_EQ(c.get<std::string>("name", ""), "a");
  EXPECT_EQ(c.get<std::vector<double>>("xs_m", {}), (std::vector<double>{1.0, 2.5}));
  ConfigReader can = c.section("can");
  EXPECT_EQ(can.get<std::vector<std::string>>("node_ids", {}), (std::vector<std::string>{"1", "2"}));
  EXPECT_EQ(can.get<int64_t>("timeout_ms", 1), 250);
  EXPECT_NO_THROW(c.finish());
}

TEST(ConfigReader, UnknownKeyNamesFileAndKey) {
  ConfigReader c = ConfigReader::from_string("max_range_m = 8\nmax_rnage_m = 9\n[can]\nbitrate = 1\n",
                                             "lidar.toml");
  c.get<double>("max_range_m", 1.0);
  const std::string err = error_of([&] { c.finish(); });
  EXPECT_THAT(err, AllOf(HasSubstr("lidar.toml"), HasSubstr("'max_rnage_m'"), HasSubstr("'can.bitrate'")));
  EXPECT_THAT(err, testing::Not(HasSubstr("'max_range_m'")));
}

TEST(ConfigReader, WrongTypeNamesKeyAndValue) {
  ConfigReader c = ConfigReader::from_string("timeout_ms = \"soon\"\n", "base.toml");
  const std::string err = error_of([&] { c.get<int>("timeout_ms", 250); });
  EXPECT_THAT(err, AllOf(HasSubstr("base.toml"), HasSubstr("'timeout_ms'"), HasSubstr("\"soon\""),
                         HasSubstr("integer")));
}

TEST(ConfigReader, ConstraintViolationNamesKeyAndValue) {
  ConfigReader c = ConfigReader::from_string("timeout_ms = -5\nmode = \"fast\"\n[a]\nx_m = 3\n",
                                             "base.toml");
  EXPECT_THAT(error_of([&] { c.get<int>("timeout_ms", 250, pex::runtime::positive<int>()); }),
              AllOf(HasSubstr("base.toml"), HasSubstr("'timeout_ms'"), HasSubstr("-5"),
                    HasSubstr("> 0")));
  EXPECT_THAT(error_of([&] {
                c.get<std::string>("mode", "sim", pex::runtime::one_of({"sim", "robot"}));
              }),
              AllOf(HasSubstr("'mode'"), HasSubstr("\"fast\""), HasSubstr("\"robot\"")));
  EXPECT_THAT(error_of([&] {
                c.section("a").get<double>("x_m", 0.0, pex::runtime::in_range(0.0, 1.0));
              }),
              AllOf(HasSubstr("'a.x_m'"), HasSubstr("3")));
}

TEST(ConfigReader, RegisteredChannelOfTypeTakesOnlyChannelsOfThatType) {
  ConfigReader c = ConfigReader::from_string("a = \"SIM_TRUTH\"\nb = \"MAP\"\nc = \"NO_SUCH\"\n", "p.toml");
  const auto pose = pex::runtime::registered_channel_of_type("pex.pose_t", "SLAM_POSE or SIM_TRUTH");
  EXPECT_EQ(c.get<std::string>("a", "SLAM_POSE", pose), "SIM_TRUTH");
  EXPECT_THAT(error_of([&] { c.get<std::string>("b", "SLAM_POSE", pose); }),
              AllOf(HasSubstr("'b'"), HasSubstr("\"MAP\""), HasSubstr("pex.pose_t (SLAM_POSE or SIM_TRUTH)")));
  EXPECT_THAT(error_of([&] { c.get<std::string>("c", "SLAM_POSE", pose); }), HasSubstr("\"NO_SUCH\""));
}

TEST(ConfigReader, RejectsNonFiniteNumbers) {
  ConfigReader c = ConfigReader::from_string("x_m = nan\n", "n.toml");
  EXPECT_THAT(error_of([&] { c.get<double>("x_m", 0.0); }), HasSubstr("finite"));
}

TEST(ConfigReader, SyntaxErrorNamesFileAndLine) {
  const std::string err =
      error_of([] { ConfigReader::from_string("a = 1\nb = = 2\n", "broken.toml"); });
  EXPECT_THAT(err, AllOf(HasSubstr("broken.toml"), HasSubstr(":2")));
}

TEST(ConfigReader, MissingFileIsAConfigError) {
  EXPECT_THAT(error_of([] { ConfigReader::from_file("/nonexistent/x.toml"); }),
              HasSubstr("/nonexistent/x.toml"));
}

TEST(ConfigReader, SectionThatIsNotATableIsAnError) {
  ConfigReader c = ConfigReader::from_string("can = 3\n", "s.toml");
  EXPECT_THAT(error_of([&] { c.section("can"); }), HasSubstr("'can'"));
}

TEST(ConfigReader, PathsAreRelativeToTheConfigFile) {
  ConfigReader c = ConfigReader::from_string("world_file = \"../worlds/x.wkt\"\nabs = \"/etc/hostname\"\n",
                                             "/opt/pex/config/sim.toml");
  EXPECT_EQ(c.get_path("world_file", "", /*must_exist=*/false), "/opt/pex/config/../worlds/x.wkt");
  EXPECT_EQ(c.get_path("abs", "", false), "/etc/hostname");
  EXPECT_THAT(error_of([&] { c.get_path("world_file", ""); }),
              AllOf(HasSubstr("/opt/pex/config/sim.toml"), HasSubstr("'world_file'"),
                    HasSubstr("cannot read '/opt/pex/config/../worlds/x.wkt'")));
}

// The shipped files and the `clock` key. config/X.toml is the simulator's set and the
// defaults layer; config/robot/X.toml is the robot's overlay, read after it (installed:
// /usr/share/polyexplore/config/X.toml, then /etc/polyexplore/X.toml; docs/deployment.md).
// So a daemon whose config/ file runs on "sim" needs an overlay saying "system", and an
// overlay holds only what the robot changes: a key repeating config/'s value would hide
// a later change of that value from the robot.
namespace {

void leaf_values(const toml::table& t, const std::string& prefix, std::map<std::string, const toml::node*>& out) {
  for (const auto& [k, v] : t) {
    const std::string path = prefix + std::string(k.str());
    if (const auto* sub = v.as_table())
      leaf_values(*sub, path + ".", out);
    else
      out[path] = &v;
  }
}

}  // namespace

TEST(ShippedConfig, EveryDaemonOnTheSimClockHasARobotOverlayOnTheSystemClockWithOnlyWhatItChanges) {
  const std::filesystem::path config_dir = std::filesystem::path(PEX_SOURCE_DIR) / "config";
  int on_sim = 0;
  for (const auto& entry : std::filesystem::directory_iterator(config_dir)) {
    if (entry.path().extension() != ".toml") continue;
    const toml::table sim = toml::parse_file(entry.path().string());
    const std::string clock = sim["clock"].value_or(std::string("system"));
    if (clock != "sim") continue;
    ++on_sim;
    const auto robot_path = config_dir / "robot" / entry.path().filename();
    ASSERT_TRUE(std::filesystem::exists(robot_path)) << entry.path() << " says clock = \"sim\": the robot needs " << robot_path;
    const toml::table robot = toml::parse_file(robot_path.string());
    EXPECT_EQ(robot["clock"].value_or(std::string("system")), "system") << robot_path;
    EXPECT_TRUE(robot.contains("clock")) << robot_path << ": say clock = \"system\" explicitly";
    std::map<std::string, const toml::node*> sim_values, robot_values;
    leaf_values(sim, "", sim_values);
    leaf_values(robot, "", robot_values);
    for (const auto& [key, value] : robot_values) {
      const auto base = sim_values.find(key);
      EXPECT_FALSE(base != sim_values.end() &&
                   toml::node_view<const toml::node>(base->second) == toml::node_view<const toml::node>(value))
          << robot_path << ": " << key << " repeats " << entry.path() << "'s value (an overlay holds what the robot changes)";
    }
  }
  EXPECT_GE(on_sim, 5);  // lidar_reader, base_driver, slam, polygon_mapper, explorer
  // Every overlay has its base file.
  for (const auto& entry : std::filesystem::directory_iterator(config_dir / "robot"))
    EXPECT_TRUE(std::filesystem::exists(config_dir / entry.path().filename())) << entry.path() << " has no base file in config/";
  // The simulator is the clock: it never runs on its own.
  EXPECT_NE(toml::parse_file((config_dir / "sim.toml").string())["clock"].value_or(std::string()), "sim");
}

// Layering: defaults < each file in order, key by key (docs/deployment.md).
// Each test writes its files into a folder of its own, removed after it.
class ConfigLayers : public ::testing::Test {
 protected:
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string write_file(const std::string& name, const std::string& text) {
    std::filesystem::create_directories(dir_ / "robot");
    const auto path = dir_ / name;
    std::ofstream(path) << text;
    return path.string();
  }

 private:
  const std::filesystem::path dir_ =
      std::filesystem::temp_directory_path() / ("pex_config_test_" + std::to_string(::getpid()));
};

TEST_F(ConfigLayers, EachKeyFromTheLastFileThatSetsItElseItsDefault) {
  const std::string base = write_file("slam.toml", "clock = \"sim\"\nrate_hz = 2.0\n[filter]\nparticles = 30\nseed = 7\n");
  const std::string robot = write_file("robot/slam.toml", "clock = \"system\"\n\n[filter]\nparticles = 60\n");
  ConfigReader c = ConfigReader::from_files({base, robot});
  EXPECT_EQ(c.get<std::string>("clock", "x"), "system");    // the overlay
  EXPECT_EQ(c.get<double>("rate_hz", 1.0), 2.0);             // the base file
  ConfigReader filter = c.section("filter");
  EXPECT_EQ(filter.get<int>("particles", 10), 60);            // the overlay, in a table
  EXPECT_EQ(filter.get<int>("seed", 1), 7);                   // the base, in the same table
  EXPECT_EQ(c.get<int>("timeout_ms", 500), 500);              // nobody: the default
  EXPECT_NO_THROW(c.finish());
  EXPECT_EQ(c.origin(), base + " + " + robot);
  const auto e = c.effective();
  ASSERT_EQ(e.size(), 5u);
  EXPECT_EQ(e[0].key, "clock");
  EXPECT_EQ(e[0].value, "\"system\"");
  EXPECT_EQ(e[0].source, robot + ":1");
  EXPECT_EQ(e[1].key, "rate_hz");
  EXPECT_EQ(e[1].value, "2.0");
  EXPECT_EQ(e[1].source, base + ":2");
  EXPECT_EQ(e[2].key, "filter.particles");
  EXPECT_EQ(e[2].source, robot + ":4");
  EXPECT_EQ(e[3].key, "filter.seed");
  EXPECT_EQ(e[3].source, base + ":5");
  EXPECT_EQ(e[4].key, "timeout_ms");
  EXPECT_EQ(e[4].value, "500");
  EXPECT_EQ(e[4].source, "default");
  // the other order: the base wins
  ConfigReader reversed = ConfigReader::from_files({robot, base});
  EXPECT_EQ(reversed.get<std::string>("clock", "x"), "sim");
}

TEST_F(ConfigLayers, ErrorsNameTheFileThatSetTheKey) {
  const std::string base = write_file("mapper.toml", "rate_hz = 2.0\n");
  const std::string robot = write_file("robot/mapper.toml", "rate_hz = -1.0\ntypo_m = 3\n");
  ConfigReader c = ConfigReader::from_files({base, robot});
  EXPECT_THAT(error_of([&] { c.get<double>("rate_hz", 1.0, pex::runtime::positive<double>()); }),
              AllOf(HasSubstr(robot + ": key 'rate_hz'"), HasSubstr("must be > 0")));
  EXPECT_THAT(error_of([&] { c.finish(); }), HasSubstr(robot + ": unknown key 'typo_m'"));
  // a value in one file, a table in the next: refused
  const std::string table = write_file("robot/table.toml", "[rate_hz]\nx = 1\n");
  EXPECT_THAT(error_of([&] { ConfigReader::from_files({base, table}); }),
              AllOf(HasSubstr(table), HasSubstr("'rate_hz' is a table here but a value in " + base)));
}

TEST_F(ConfigLayers, ARelativePathIsTakenFromTheFolderOfTheFileThatSetIt) {
  const std::string base = write_file("sim.toml", "world_file = \"../worlds/a.wkt\"\nlog_file = \"a.log\"\n");
  const std::string robot = write_file("robot/sim.toml", "world_file = \"b.wkt\"\n");
  ConfigReader c = ConfigReader::from_files({base, robot});
  const std::string dir = std::filesystem::path(base).parent_path().string();
  EXPECT_EQ(c.get_path("world_file", "", false), dir + "/robot/b.wkt");
  EXPECT_EQ(c.get_path("log_file", "", false), dir + "/a.log");
  EXPECT_EQ(c.effective()[0].value, "\"" + dir + "/robot/b.wkt\"");  // printed as resolved
}

TEST_F(ConfigLayers, TheEffectiveConfigIsAConfigThatReadsBackToTheSameValues) {
  const std::string base = write_file(
      "explorer.toml", "name = \"a \\\"quoted\\\" b\"\nstep_m = 0.1\nxs_m = [1, 2.5, -0.3]\non = true\nn = 3\n");
  ConfigReader c = ConfigReader::from_files({base});
  auto read_all = [](ConfigReader& r) {
    return std::make_tuple(r.get<std::string>("name", ""), r.get<double>("step_m", 0), r.get<std::vector<double>>("xs_m", {}),
                           r.get<bool>("on", false), r.get<int>("n", 0), r.get<double>("gain", 1.0 / 3.0));
  };
  const auto values = read_all(c);
  const std::string text = c.effective_toml();
  EXPECT_THAT(text, HasSubstr("step_m = 0.1"));
  EXPECT_THAT(text, HasSubstr("xs_m = [1.0, 2.5, -0.3]"));
  EXPECT_THAT(text, HasSubstr("# " + base + ":2"));
  EXPECT_THAT(text, HasSubstr("# default"));
  ConfigReader again = ConfigReader::from_string(text, "printed.toml");
  EXPECT_EQ(read_all(again), values) << text;
  EXPECT_NO_THROW(again.finish());
}
