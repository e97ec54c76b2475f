#include "runtime/channels.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <set>
#include <sstream>

// docs/channels.md documents the registry; this keeps the two from drifting.
TEST(Channels, DocumentationListsEveryRegisteredChannel) {
  std::ifstream in(std::string(PEX_SOURCE_DIR) + "/docs/channels.md");
  ASSERT_TRUE(in.good());
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string doc = ss.str();
  std::set<std::string> documented;
  const std::regex row(R"(\n\|\s*`([A-Z_]+)`\s*\|\s*`(pex\.[a-z_0-9]+)`)");
  for (std::sregex_iterator it(doc.begin(), doc.end(), row), end; it != end; ++it) {
    const std::string name = (*it)[1];
    documented.insert(name);
    const auto* info = pex::runtime::channels::find(name);
    ASSERT_NE(info, nullptr) << name << " is documented but not registered";
    EXPECT_EQ(std::string(info->type), (*it)[2].str()) << name;
  }
  for (const auto& c : pex::runtime::channels::kRegistry)
    EXPECT_TRUE(documented.count(std::string(c.name))) << c.name << " is not documented";
}

TEST(Channels, NamesAreUnique) {
  std::set<std::string_view> names;
  for (const auto& c : pex::runtime::channels::kRegistry) EXPECT_TRUE(names.insert(c.name).second);
}
