#pragma once
// pex-viewer's HTTP side (cpp-httplib, on its own threads):
//   GET  /                  the page (index.html, built in)
//   GET  /api/state         the whole state as JSON (map included)
//   GET  /events            server-sent events: "map" when the map changed, "live" at every update
//   POST /api/mission/NAME  NAME in start|pause|resume|home|stop: queued for the daemon to send
// The daemon's thread hands each update over with publish(); the HTTP threads
// only copy strings out under a lock and queue commands, which the daemon's
// thread takes from command_fd() (a pipe it polls), so every LCM call stays on
// the daemon's thread.
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

namespace httplib {
class Server;
}

namespace pex::viewer {

struct WebServerOptions {
  std::string bind_address = "127.0.0.1";
  int port = 8080;
  int max_clients = 8;  // event streams at once
};

struct WebCounters {
  std::int64_t requests = 0;
  std::int64_t events_sent = 0;
  std::int64_t clients = 0;           // event streams open now
  std::int64_t clients_refused = 0;   // beyond max_clients
  std::int64_t bad_requests = 0;      // unknown command, unknown path

  // By name, for DAEMON_STATUS (runtime::Node::collect_counters).
  template <class Visitor>
  void visit_counters(Visitor& v) const {
    v.total("http_requests", requests);
    v.total("http_bad_requests", bad_requests);
    v.total("pages_open", clients);
    v.total("pages_refused", clients_refused);
    v.total("events_sent", events_sent);
  }
};

class WebServer {
 public:
  // Binds at once: throws std::runtime_error naming the address if it cannot.
  WebServer(WebServerOptions options, std::string page);
  ~WebServer();  // stops the server and joins its threads
  WebServer(const WebServer&) = delete;
  WebServer& operator=(const WebServer&) = delete;

  // A new state for the pages: the map's JSON (sent to a page only when
  // map_version changed since its last) and the rest's.
  void publish(std::int64_t map_version, std::string map_json, std::string live_json);
  // Readable while commands wait; take_commands() empties it.
  int command_fd() const { return pipe_[0]; }
  std::deque<std::string> take_commands();
  WebCounters counters() const;
  int port() const { return options_.port; }

 private:
  struct Snapshot {
    std::int64_t seq = 0;
    std::int64_t map_version = -1;
    std::string map_json = "{}";
    std::string live_json = "{}";
  };
  void route();

  WebServerOptions options_;
  std::string page_;
  std::unique_ptr<httplib::Server> server_;
  std::thread thread_;
  std::atomic<bool> loop_ended_{false};  // the server's loop has returned
  int pipe_[2] = {-1, -1};
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  Snapshot snapshot_;
  std::deque<std::string> commands_;
  WebCounters counters_;
  bool stopping_ = false;
};

}  // namespace pex::viewer
