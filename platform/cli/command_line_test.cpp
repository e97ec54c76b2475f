#include "cli/command_line.hpp"

#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace pex::cli {
namespace {

struct Outcome {
  std::optional<int> code;
  std::string out, err;
};

// Parses `args` with one option (--n) declared, capturing what is printed.
Outcome parse(std::vector<const char*> args, int* n = nullptr) {
  int dummy = 0;
  CLI::App app{"a test program"};
  app.add_option("--n", n ? *n : dummy, "a number");
  args.insert(args.begin(), "pex-test");
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  Outcome r;
  r.code = parse_command_line(app, "pex-test", static_cast<int>(args.size()), args.data());
  r.out = testing::internal::GetCapturedStdout();
  r.err = testing::internal::GetCapturedStderr();
  return r;
}

TEST(ParseCommandLine, GoodOptionsGoOn) {
  int n = 0;
  const Outcome r = parse({"--n", "7"}, &n);
  EXPECT_FALSE(r.code.has_value());
  EXPECT_EQ(n, 7);
  EXPECT_EQ(r.out + r.err, "");
}

TEST(ParseCommandLine, VersionPrintsTheProgramAndThePackageVersionAndEnds) {
  const Outcome r = parse({"--version"});
  ASSERT_TRUE(r.code.has_value());
  EXPECT_EQ(*r.code, 0);
  EXPECT_EQ(r.out, std::string("pex-test ") + PEX_VERSION + "\n");
}

TEST(ParseCommandLine, HelpShowsTheOptionsAndEnds) {
  const Outcome r = parse({"--help"});
  ASSERT_TRUE(r.code.has_value());
  EXPECT_EQ(*r.code, 0);
  EXPECT_NE(r.out.find("--n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("--version"), std::string::npos) << r.out;
}

TEST(ParseCommandLine, ABadCommandLineIs64WithCli11sMessage) {
  for (const auto& args : std::vector<std::vector<const char*>>{{"--no-such-flag"}, {"--n", "seven"}, {"extra"}}) {
    const Outcome r = parse(args);
    ASSERT_TRUE(r.code.has_value()) << args.front();
    EXPECT_EQ(*r.code, 64) << args.front();
    EXPECT_NE(r.err, "") << args.front();
  }
}

}  // namespace
}  // namespace pex::cli
