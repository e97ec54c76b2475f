#include "runtime/files.hpp"

#include <gtest/gtest.h>

#include <filesystem>

using pex::runtime::read_whole_file;
using pex::runtime::write_file_atomically;

TEST(Files, AtomicWriteReplacesTheFileWholeAndLeavesNoTemporary) {
  const auto dir = std::filesystem::temp_directory_path() / ("pex-files-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "state.txt").string();
  EXPECT_FALSE(read_whole_file(path));
  ASSERT_EQ(write_file_atomically(path, "first\n"), "");
  EXPECT_EQ(read_whole_file(path).value_or(""), "first\n");
  ASSERT_EQ(write_file_atomically(path, std::string(100'000, 'x')), "");
  EXPECT_EQ(read_whole_file(path).value_or("").size(), 100'000u);
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  // A folder that does not exist: a clear reason, the old file untouched.
  const std::string why = write_file_atomically((dir / "no" / "such.txt").string(), "x");
  EXPECT_NE(why.find("cannot create"), std::string::npos) << why;
  std::filesystem::remove_all(dir);
}
