#include "web_server.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <chrono>
#include <set>
#include <stdexcept>
#include <string_view>
#include <utility>

#include <httplib.h>

namespace pex::viewer {

namespace {
const std::set<std::string, std::less<>> kCommands = {"start", "pause", "resume", "home", "stop"};
}  // namespace

WebServer::WebServer(WebServerOptions options, std::string page)
    : options_(std::move(options)), page_(std::move(page)), server_(std::make_unique<httplib::Server>()) {
  if (::pipe2(pipe_, O_NONBLOCK | O_CLOEXEC) != 0) throw std::runtime_error("pex-viewer: pipe2 failed");
  route();
  // A page that stops reading must not hold a thread for long.
  server_->set_write_timeout(2, 0);
  server_->set_keep_alive_timeout(2);
  if (!server_->bind_to_port(options_.bind_address, options_.port))
    throw std::runtime_error("cannot listen on " + options_.bind_address + ":" + std::to_string(options_.port) +
                             " (in use, or not an address of this computer)");
  thread_ = std::thread([this] {
    server_->listen_after_bind();
    loop_ended_ = true;
  });
  // stop() before the loop runs would be lost (httplib stops only a running
  // server) and the destructor would wait for ever: wait until it runs.
  while (!server_->is_running() && !loop_ended_) std::this_thread::sleep_for(std::chrono::milliseconds(1));
}

WebServer::~WebServer() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  server_->stop();
  if (thread_.joinable()) thread_.join();
  for (int fd : pipe_)
    if (fd >= 0) ::close(fd);
}

void WebServer::publish(std::int64_t map_version, std::string map_json, std::string live_json) {
  {
    std::lock_guard lock(mutex_);
    ++snapshot_.seq;
    if (map_version != snapshot_.map_version) {
      snapshot_.map_version = map_version;
      snapshot_.map_json = std::move(map_json);
    }
    snapshot_.live_json = std::move(live_json);
  }
  changed_.notify_all();
}

std::deque<std::string> WebServer::take_commands() {
  char buf[64];
  while (::read(pipe_[0], buf, sizeof buf) > 0) {
  }
  std::lock_guard lock(mutex_);
  return std::exchange(commands_, {});
}

WebCounters WebServer::counters() const {
  std::lock_guard lock(mutex_);
  return counters_;
}

void WebServer::route() {
  auto& s = *server_;
  s.set_pre_routing_handler([this](const httplib::Request&, httplib::Response&) {
    std::lock_guard lock(mutex_);
    ++counters_.requests;
    return httplib::Server::HandlerResponse::Unhandled;
  });
  s.Get("/", [this](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    res.set_content(page_, "text/html; charset=utf-8");
  });
  s.Get("/api/state", [this](const httplib::Request&, httplib::Response& res) {
    std::string body;
    {
      std::lock_guard lock(mutex_);
      // {"map": MAP, ...live}: live is an object ("{...}"), never empty.
      const std::string& live = snapshot_.live_json;
      body.reserve(snapshot_.map_json.size() + live.size() + 8);
      body.append("{\"map\":").append(snapshot_.map_json);
      if (live.size() > 2) body.append(",").append(live, 1, std::string::npos);
      else body.append("}");
    }
    res.set_header("Cache-Control", "no-store");
    res.set_content(body, "application/json");
  });
  s.Get("/events", [this](const httplib::Request&, httplib::Response& res) {
    {
      std::lock_guard lock(mutex_);
      if (counters_.clients >= options_.max_clients) {
        ++counters_.clients_refused;
        res.status = 503;
        res.set_content("too many pages open\n", "text/plain");
        return;
      }
      ++counters_.clients;
    }
    res.set_header("Cache-Control", "no-store");
    // Per stream: what it was last sent.
    auto sent_seq = std::make_shared<std::int64_t>(-1);
    auto sent_map = std::make_shared<std::int64_t>(-1);
    res.set_chunked_content_provider(
        "text/event-stream",
        [this, sent_seq, sent_map](std::size_t, httplib::DataSink& sink) {
          std::string out;
          {
            std::unique_lock lock(mutex_);
            // A comment line every second keeps a quiet stream alive and finds closed pages.
            changed_.wait_for(lock, std::chrono::seconds(1),
                              [&] { return stopping_ || snapshot_.seq != *sent_seq; });
            if (stopping_) return false;
            if (snapshot_.seq == *sent_seq) {
              out = ": idle\n\n";
            } else {
              if (snapshot_.map_version != *sent_map) {
                out += "event: map\ndata: " + snapshot_.map_json + "\n\n";
                *sent_map = snapshot_.map_version;
              }
              out += "event: live\ndata: " + snapshot_.live_json + "\n\n";
              *sent_seq = snapshot_.seq;
              ++counters_.events_sent;
            }
          }
          return sink.write(out.data(), out.size());
        },
        [this](bool) {
          std::lock_guard lock(mutex_);
          --counters_.clients;
        });
  });
  s.Post(R"(/api/mission/([a-z]+))", [this](const httplib::Request& req, httplib::Response& res) {
    const std::string name = req.matches[1];
    if (!kCommands.count(name)) {  // counted by the error handler
      res.status = 404;
      res.set_content("{\"error\":\"unknown command\"}", "application/json");
      return;
    }
    {
      std::lock_guard lock(mutex_);
      commands_.push_back(name);
    }
    const char one = 1;
    [[maybe_unused]] const auto n = ::write(pipe_[1], &one, 1);  // full pipe: a wake-up is pending anyway
    res.status = 202;
    res.set_content("{\"queued\":\"" + name + "\"}", "application/json");
  });
  s.set_error_handler([this](const httplib::Request&, httplib::Response& res) {
    if (res.status >= 400 && res.status != 503) {
      std::lock_guard lock(mutex_);
      ++counters_.bad_requests;
    }
  });
}

}  // namespace pex::viewer
