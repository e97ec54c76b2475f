#pragma once
// Small files a daemon keeps across restarts (checkpoints).
#include <optional>
#include <string>

namespace pex::runtime {

// Writes `text` to `path` so that a reader (or a restart after power loss)
// sees the old file or the new one, never a part: a temporary file beside it,
// flushed to disk, renamed over the old one. "" on success, else why not.
std::string write_file_atomically(const std::string& path, const std::string& text);

// The whole file, or nullopt when it does not exist or cannot be read (why).
std::optional<std::string> read_whole_file(const std::string& path, std::string* why = nullptr);

}  // namespace pex::runtime
