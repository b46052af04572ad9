// What every `pba` command's registration shares: the global options, the
// PBA_PROJECT default, and the action of each leaf command, run after
// parsing with a connection made from the global options.
//
// A command group registers its commands next to their implementation
// (RegisterJobCommands in job_commands.cc, and so on): it adds its
// subcommands and options to the CLI11 app, keeps the parsed values in
// arguments its action owns, and gives the action to Add(). main() builds
// the app, the global options and the connection, and runs the one action
// whose command was parsed.
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "commands/atlas_commands.h"
#include "connection.h"

namespace CLI {
class App;
}

namespace pba::cli {

class CommandContext {
 public:
  // Reads PBA_PROJECT (the default of every -p,--project).
  CommandContext();

  // --server, --json, --tls-ca, --tls, --timeout: filled in by parsing.
  GlobalOptions global;

  // Runs `action` when `command` is the subcommand parsed.
  void Add(CLI::App* command, std::function<int(Connection&)> action);
  // The exit code of the parsed command's action; kExitUsage when no action's
  // command was parsed.
  int RunParsed(Connection& connection) const;

  // -p,--project into *project, PBA_PROJECT by default; required when that
  // is unset.
  void AddProjectOption(CLI::App* command, std::string* project) const;

 private:
  std::string project_env_;
  std::vector<std::pair<CLI::App*, std::function<int(Connection&)>>> actions_;
};

// A command group ("job", "atlas", ...) that needs one of its subcommands.
CLI::App* AddCommandGroup(CLI::App& parent, const std::string& name,
                          const std::string& description);

// --page-size, --page-token and --all of a list command.
void AddPagingOptions(CLI::App* command, PageArgs* page);

// --request-id of a create: `what` names what a rerun returns.
void AddRequestIdOption(CLI::App* command, std::string* request_id, const char* what);

}  // namespace pba::cli
