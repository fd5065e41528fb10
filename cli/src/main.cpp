// octolod: bake PLY meshes into on-disk LOD octrees, inspect, measure and replay them.
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <system_error>

#include <CLI/CLI.hpp>

#include "command.h"
#include "command_line.h"

namespace octolod::cli {

int report(const Status& status) {
  std::fprintf(stderr, "error: %s\n", status.message().c_str());
  return static_cast<int>(status.code());
}

void warn(const std::string& message) { std::fprintf(stderr, "warning: %s\n", message.c_str()); }

void warn_trailing_bytes(const std::string& path, std::uint64_t bytes) {
  if (bytes == 0) return;
  warn(path + ": " + std::to_string(bytes) +
       " bytes after the last element were ignored (padding, or element counts in the header that are too small)");
}

void print_json(const nlohmann::json& document) { std::cout << document.dump(2) << '\n'; }

Result<std::uint64_t> written_file_size(const std::string& path) {
  std::error_code ec;
  const std::uintmax_t bytes = std::filesystem::file_size(path, ec);
  if (ec) return io_error(path + ": cannot stat the written file: " + ec.message());
  return static_cast<std::uint64_t>(bytes);
}

Result<std::uint64_t> parse_byte_size(const std::string& text) {
  std::size_t used = 0;
  double value = 0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    return usage_error("not a byte size: '" + text + "' (expected e.g. 64M, 512K, 2G)");
  }
  std::string suffix = text.substr(used);
  double scale = 1;
  if (suffix == "K" || suffix == "KiB" || suffix == "k") scale = 1024.0;
  else if (suffix == "M" || suffix == "MiB" || suffix == "m") scale = 1024.0 * 1024.0;
  else if (suffix == "G" || suffix == "GiB" || suffix == "g") scale = 1024.0 * 1024.0 * 1024.0;
  else if (!suffix.empty() && suffix != "B")
    return usage_error("unknown size suffix in '" + text + "' (use K, M or G)");
  if (!(value >= 0) || value * scale > 1e18)
    return usage_error("byte size out of range: '" + text + "'");
  return static_cast<std::uint64_t>(value * scale);
}

}  // namespace octolod::cli

int main(int argc, char** argv) {
  using namespace octolod::cli;
  CommandContext context;
  CLI::App app{"octolod: bake meshes larger than memory into an on-disk LOD octree, "
               "and stream it by view"};
  app.set_version_flag("--version", std::string("octolod ") + OCTOLOD_VERSION);
  app.require_subcommand(1);
  app.fallthrough();
  app.add_flag("--json", context.json, "Machine-readable output: one JSON document on stdout");
  app.add_flag("--progress", context.progress,
               "Human progress on stderr (default: only when stderr is a terminal)");
  add_commands(app, context);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    int code = app.exit(e);
    return code == 0 ? 0 : static_cast<int>(octolod::ErrorCode::usage);
  }
  return context.exit_code;
}
