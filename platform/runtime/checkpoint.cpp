#include "runtime/checkpoint.hpp"

#include <chrono>
#include <cstdio>
#include <memory>

#include <spdlog/spdlog.h>

#include "runtime/files.hpp"
#include "runtime/node.hpp"

namespace pex::runtime {

bool keep_checkpoint(Node& node, CheckpointFile file) {
  if (file.path.empty()) return false;
  bool restored = false;
  std::string why;
  if (const auto bytes = read_whole_file(file.path, &why)) {
    why = file.restore(*bytes);
    if (why.empty()) {
      spdlog::info("{} restored from {} ({} bytes)", file.what, file.path, bytes->size());
      restored = true;
    } else {
      const std::string aside = file.path + ".refused";
      std::rename(file.path.c_str(), aside.c_str());
      node.error("checkpoint", "cannot restore the " + file.what + " from " + file.path + ": " + why +
                                   "; starting afresh (the file is kept as " + aside + ")");
    }
  } else {
    spdlog::info("no {} checkpoint at {}: starting afresh", file.what, file.path);
  }
  auto save = [&node, path = file.path, state = std::move(file.save)] {
    if (const auto why = write_file_atomically(path, state()); !why.empty())
      node.error("checkpoint", why);
    else
      ++node.counter("checkpoints_written");
  };
  node.every(std::chrono::microseconds(static_cast<std::int64_t>(file.period_s * 1e6)), [save](std::int64_t) { save(); });
  node.on_shutdown(save);
  return restored;
}

}  // namespace pex::runtime
