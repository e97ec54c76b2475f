#pragma once
// The error a replay (Node::replay_logs) throws for a log it cannot trust.
#include <stdexcept>
#include <string>

namespace pex::runtime {

// A replayed LCM log that cannot be opened, or whose bytes are not all LCM
// events (a cut, damaged or foreign file): the replay must not end early as if
// the log had ended. Node::replay_logs throws it naming the file, the byte and
// the events read before it, after its shutdown (what was replayed is kept).
class LogFileError : public std::runtime_error {
 public:
  enum class Kind { kCannotOpen, kNotAllEvents };
  LogFileError(Kind kind, const std::string& what) : std::runtime_error(what), kind_(kind) {}
  Kind kind() const { return kind_; }

 private:
  Kind kind_;
};

}  // namespace pex::runtime
