// An LCM log file as a replay reads it (pex-slam --log, pex-polygon-mapper
// --log, ...): Node::replay_logs -> LCM's log reader, checked for a log that
// is cut, damaged or no log at all -> each event dispatched to the channel's
// bounded decoder.
//
// Input: the file's bytes.
// Invariants: nothing crashes; the replay either ends at the log's last byte
// or says the log is damaged (runtime::LogFileError); every event reached a
// handler, was rejected, or was on a channel nobody reads; no handler failed.
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <string>

#include <spdlog/spdlog.h>

#include "lcm_channels.hpp"
#include "runtime/log_file_error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  spdlog::set_level(spdlog::level::err);  // rejections are warnings; a handler's failure shows
  // The log as a file that lives in memory only.
  const int fd = ::memfd_create("pex-fuzz-log", 0);
  PEX_FUZZ_CHECK(fd >= 0, "memfd_create");
  for (std::size_t done = 0; done < size;) {
    const ssize_t n = ::write(fd, data + done, size - done);
    PEX_FUZZ_CHECK(n > 0, "write");
    done += static_cast<std::size_t>(n);
  }
  const std::string path = "/proc/self/fd/" + std::to_string(fd);
  {
    pex::runtime::NodeOptions options;
    options.name = "fuzz";
    options.offline = true;
    pex::runtime::Node node(options);
    std::int64_t decoded = 0;
    const int max_size = static_cast<int>(size);
    pex::fuzz::subscribe_every_channel(node, decoded, max_size);
    try {
      const std::int64_t events = node.replay_log(path);
      PEX_FUZZ_CHECK(decoded + node.msgs_rejected() <= events, "more outcomes than events");
    } catch (const pex::runtime::LogFileError&) {
      // a clean refusal, naming the file and the byte
    }
    PEX_FUZZ_CHECK(node.errors() == node.msgs_rejected(), "a handler failed");  // errors() counts rejections too
  }
  ::close(fd);
  return 0;
}
