#pragma once
// What every fuzz target may assert about a parser's result. A failed check
// aborts with the reason, which libFuzzer reports as a crash and the corpus
// replay (replay_main.cpp) as a failed test, naming the input.
#include <cstdio>
#include <cstdlib>
#include <string>

namespace pex::fuzz {

[[noreturn]] inline void check_failed(const char* condition, const std::string& why, const char* file, int line) {
  std::fprintf(stderr, "fuzz check failed at %s:%d: %s: %s\n", file, line, condition, why.c_str());
  std::abort();
}

}  // namespace pex::fuzz

// PEX_FUZZ_CHECK(condition, why): `why` (a std::string expression) is built only on failure.
#define PEX_FUZZ_CHECK(condition, why) \
  do {                                 \
    if (!(condition)) ::pex::fuzz::check_failed(#condition, (why), __FILE__, __LINE__); \
  } while (0)
