#pragma once
// A headless Chromium driven through chromedriver (W3C WebDriver over HTTP on
// loopback, with cpp-httplib's client), for the viewer's browser tests: open
// a page, run a script in it, click an element, take a screenshot.
#include <chrono>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "harness.hpp"

namespace httplib {
class Client;
}

namespace pex::testing {

class Browser {
 public:
  // Starts chromedriver on 127.0.0.1:`driver_port` (output to <log_dir>/chromedriver.log)
  // and a headless Chromium session. Throws std::runtime_error if either cannot start.
  Browser(const std::string& log_dir, int driver_port = 9515);
  ~Browser();  // ends the session and chromedriver
  Browser(const Browser&) = delete;
  Browser& operator=(const Browser&) = delete;

  void open(const std::string& url);
  // Runs `script` (a function body: `return ...;`) in the page; its result.
  nlohmann::json run(const std::string& script);
  // Clicks the element `css` selects (the first).
  void click(const std::string& css);
  // The page as PNG bytes.
  std::string screenshot_png();

 private:
  nlohmann::json call(const std::string& method, const std::string& path, const nlohmann::json& body = nullptr);

  std::string dir_;
  std::unique_ptr<Process> driver_;
  std::unique_ptr<httplib::Client> http_;
  std::string session_;
};

}  // namespace pex::testing
