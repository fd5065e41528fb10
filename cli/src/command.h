// The frame every subcommand plugs into. A subcommand file defines one
//   void add_<name>_command(CLI::App& app, CommandContext& context);
// that adds a CLI11 subcommand whose callback stores its exit code in context.exit_code.
#pragma once

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

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
// Prints `document` (pretty) on stdout.
void print_json(const nlohmann::json& document);
// Parses "64M", "512K", "2G", "1048576" (binary units) into bytes.
Result<std::uint64_t> parse_byte_size(const std::string& text);
// Size in bytes of a file a command has just written (for its summary); io error naming it.
Result<std::uint64_t> written_file_size(const std::string& path);

void add_sample_command(CLI::App& app, CommandContext& context);
void add_walk_command(CLI::App& app, CommandContext& context);
void add_export_command(CLI::App& app, CommandContext& context);
void add_bake_command(CLI::App& app, CommandContext& context);
void add_info_command(CLI::App& app, CommandContext& context);
void add_extract_command(CLI::App& app, CommandContext& context);
void add_eval_command(CLI::App& app, CommandContext& context);
void add_reference_command(CLI::App& app, CommandContext& context);
void add_compare_command(CLI::App& app, CommandContext& context);
void add_render_command(CLI::App& app, CommandContext& context);



}  // namespace octolod::cli
