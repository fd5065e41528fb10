// Declares octolod's subcommands on the top-level CLI11 app (main.cpp). Each subcommand's
// callback runs it and stores its exit code in context.exit_code; `context` must outlive the parse.
#pragma once

#include "command.h"

namespace CLI {
class App;
}

namespace octolod::cli {

void add_commands(CLI::App& app, CommandContext& context);

}  // namespace octolod::cli
