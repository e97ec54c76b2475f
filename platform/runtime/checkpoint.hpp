#pragma once
// A daemon's state across restarts (kill -9, a crash, a reboot): taken up at
// start from a file, written atomically every period and on stop. The state
// itself is the component's (to bytes and back); this is only the file's life.
#include <functional>
#include <string>

namespace pex::runtime {

class Node;

struct CheckpointFile {
  std::string path;       // "" = no checkpoint
  double period_s = 2.0;  // node clock (the simulator's with clock = "sim")
  std::string what;       // for messages: "mission", "map", "filter"
  // The file's bytes in; "" when taken up, else why not (nothing changed then).
  std::function<std::string(const std::string& bytes)> restore;
  // The state now, as bytes to write.
  std::function<std::string()> save;
};

// Restores now (a missing file is a first start; a file that is refused is an
// error, moved aside to `path`.refused so the next write does not destroy
// what someone may want to look at), then saves every period_s and on
// shutdown (counter `checkpoints_written`, errors under key "checkpoint").
// Returns true if a checkpoint was taken up.
bool keep_checkpoint(Node& node, CheckpointFile file);

}  // namespace pex::runtime
