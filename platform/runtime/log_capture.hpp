#pragma once
// For tests: while a LogCapture lives, spdlog's default logger writes the
// bare messages ("%v") into a string, and the logger before it comes back
// when it goes, also when a failed ASSERT leaves the test early (set by
// hand, a test that stopped half-way left the next tests logging into a
// dead stream). Read text() once the code that logs has stopped.
#include <memory>
#include <sstream>
#include <string>
#include <string_view>

#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

namespace pex::runtime {

class LogCapture {
 public:
  LogCapture() : previous_(spdlog::default_logger()) {
    auto logger = std::make_shared<spdlog::logger>("capture", std::make_shared<spdlog::sinks::ostream_sink_mt>(text_));
    logger->set_pattern("%v");
    spdlog::set_default_logger(std::move(logger));
  }
  ~LogCapture() { spdlog::set_default_logger(previous_); }
  LogCapture(const LogCapture&) = delete;
  LogCapture& operator=(const LogCapture&) = delete;

  std::string text() const { return text_.str(); }
  int lines() const { return lines_with(""); }
  int lines_with(std::string_view what) const {
    std::istringstream in(text_.str());
    int n = 0;
    for (std::string line; std::getline(in, line);) n += line.find(what) != std::string::npos;
    return n;
  }

 private:
  std::ostringstream text_;
  std::shared_ptr<spdlog::logger> previous_;
};

}  // namespace pex::runtime
