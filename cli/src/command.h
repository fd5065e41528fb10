// What every subcommand shares: the global flags and the helpers that report results and errors
// (commands.h lists the subcommands, command_line.cpp declares their options).
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>

#include "octolod/formats/status.h"

namespace octolod::cli {

struct CommandContext {
  bool json = false;      // --json: one JSON document on stdout, nothing else on stdout
  bool progress = false;  // --progress, or stderr is a terminal: human progress on stderr
  int exit_code = 0;
};

// Prints "error: <message>" on stderr and returns the Status's exit code.
int report(const Status& status);
// Prints "warning: <message>" on stderr (the command goes on).
void warn(const std::string& message);
// warn()s that `bytes` (> 0) after the last element of the PLY at `path` were ignored
// (PlyInfo::trailing_bytes); nothing when `bytes` is 0.
void warn_trailing_bytes(const std::string& path, std::uint64_t bytes);
// Prints `document` (pretty) on stdout.
void print_json(const nlohmann::json& document);
// Parses "64M", "512K", "2G", "1048576" (binary units) into bytes.
Result<std::uint64_t> parse_byte_size(const std::string& text);
// Size in bytes of a file a command has just written (for its summary); io error naming it.
Result<std::uint64_t> written_file_size(const std::string& path);

}  // namespace octolod::cli
