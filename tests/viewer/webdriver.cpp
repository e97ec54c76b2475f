#include "webdriver.hpp"

#include <stdexcept>
#include <thread>

#include <httplib.h>

namespace pex::testing {

namespace {

std::string base64_decode(const std::string& in) {
  static const std::string kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  unsigned value = 0;
  int bits = -8;
  for (char c : in) {
    const auto at = kAlphabet.find(c);
    if (at == std::string::npos) continue;  // '=' padding, line breaks
    value = (value << 6) + static_cast<unsigned>(at);
    bits += 6;
    if (bits >= 0) {
      out.push_back(static_cast<char>((value >> bits) & 0xFF));
      bits -= 8;
    }
  }
  return out;
}

}  // namespace

Browser::Browser(const std::string& log_dir, int driver_port) : dir_(log_dir) {
  driver_ = std::make_unique<Process>(
      std::vector<std::string>{"/usr/bin/chromedriver", "--port=" + std::to_string(driver_port),
                               "--allowed-ips=127.0.0.1"},
      log_dir + "/chromedriver.log");
  http_ = std::make_unique<httplib::Client>("127.0.0.1", driver_port);
  http_->set_read_timeout(60, 0);
  // Ready when it answers /status (it starts in well under a second; the budget is for a loaded machine).
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (true) {
    if (auto r = http_->Get("/status"); r && r->status == 200 &&
                                        nlohmann::json::parse(r->body, nullptr, false).value("/value/ready"_json_pointer, false))
      break;
    if (!driver_->running()) throw std::runtime_error("chromedriver exited:\n" + driver_->output());
    if (std::chrono::steady_clock::now() > until) throw std::runtime_error("chromedriver not ready:\n" + driver_->output());
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  const nlohmann::json caps = {
      {"capabilities",
       {{"alwaysMatch",
         {{"browserName", "chrome"},
          {"goog:chromeOptions",
           {{"binary", "/usr/bin/chromium"},
            {"args",
             {"--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--window-size=1400,900",
              "--no-first-run", "--disable-background-networking", "--disable-component-update", "--disable-sync",
              "--disable-extensions", "--user-data-dir=" + log_dir + "/chromium-profile"}}}}}}}}};
  session_ = call("POST", "/session", caps).at("sessionId").get<std::string>();
}

Browser::~Browser() {
  try {
    if (!session_.empty()) call("DELETE", "/session/" + session_);
  } catch (const std::exception&) {
    // chromedriver is stopped below either way
  }
  if (driver_) driver_->stop(std::chrono::seconds(5));
}

nlohmann::json Browser::call(const std::string& method, const std::string& path, const nlohmann::json& body) {
  const std::string text = body.is_null() ? "{}" : body.dump();
  httplib::Result r = method == "GET"      ? http_->Get(path.c_str())
                      : method == "DELETE" ? http_->Delete(path.c_str())
                                           : http_->Post(path.c_str(), text, "application/json");
  if (!r) throw std::runtime_error("WebDriver " + method + " " + path + ": no answer (" + httplib::to_string(r.error()) + ")");
  const auto j = nlohmann::json::parse(r->body, nullptr, false);
  if (r->status != 200 || j.is_discarded())
    throw std::runtime_error("WebDriver " + method + " " + path + ": HTTP " + std::to_string(r->status) + ": " +
                             r->body.substr(0, 2000));
  // New session: {"value": {"sessionId", "capabilities"}}; everything else: {"value": result}.
  return j.at("value");
}

void Browser::open(const std::string& url) { call("POST", "/session/" + session_ + "/url", {{"url", url}}); }

nlohmann::json Browser::run(const std::string& script) {
  return call("POST", "/session/" + session_ + "/execute/sync", {{"script", script}, {"args", nlohmann::json::array()}});
}

void Browser::click(const std::string& css) {
  const auto element = call("POST", "/session/" + session_ + "/element", {{"using", "css selector"}, {"value", css}});
  const std::string id = element.begin().value().get<std::string>();  // {"element-6066-...": id}
  call("POST", "/session/" + session_ + "/element/" + id + "/click", nlohmann::json::object());
}

std::string Browser::screenshot_png() {
  return base64_decode(call("GET", "/session/" + session_ + "/screenshot").get<std::string>());
}

}  // namespace pex::testing
