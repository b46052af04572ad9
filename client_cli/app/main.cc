// pba: the command-line client of pba-server.
// Exit codes are listed in exit_codes.h and docs/cli.md.
//
// Each command group registers its own commands (commands/*_commands.cc,
// Register*Commands); here are only the global options, the parse and the
// run of the command parsed.

#include <CLI/CLI.hpp>
#include <cstdlib>

#include "commands/atlas_commands.h"
#include "commands/batch_commands.h"
#include "commands/command_context.h"
#include "commands/job_commands.h"
#include "commands/project_commands.h"
#include "commands/study_commands.h"
#include "connection.h"
#include "credentials.h"
#include "exit_codes.h"

namespace pba::cli {
namespace {

// --server, --json, --tls-ca, --tls, --timeout into *global, with their
// environment defaults.
void AddGlobalOptions(CLI::App& app, GlobalOptions* global) {
  if (const char* env = std::getenv("PBA_SERVER"); env != nullptr && *env != '\0')
    global->server = env;
  app.add_option("--server", global->server, "pba-server address HOST:PORT (env PBA_SERVER)")
      ->capture_default_str();
  app.add_flag("--json", global->json, "Print machine-readable JSON instead of tables");
  if (const char* env = std::getenv("PBA_TLS_CA"); env != nullptr) global->tls_ca = env;
  app.add_option("--tls-ca", global->tls_ca,
                 "Connect with TLS, trusting this PEM certificate (env PBA_TLS_CA)")
      ->check(CLI::ExistingFile);
  app.add_flag("--tls", global->tls, "Connect with TLS, trusting the system's certificates");
  app.add_option("--timeout", global->timeout_s, "Deadline of each request in seconds")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
}

// Builds the command line, parses it and runs the command given; the exit
// code.
int RunPba(int argc, char** argv) {
  CommandContext context;
  CLI::App app{
      "pba: submit brain-biomechanics jobs to pba-server, follow them, fetch results; share and "
      "edit atlas structures"};
  app.set_version_flag("--version", "pba 0.1.0");
  app.require_subcommand(1);
  AddGlobalOptions(app, &context.global);

  // In the order `pba --help` lists them.
  RegisterJobCommands(app, context);
  RegisterLoginCommands(app, context);
  RegisterProjectCommands(app, context);
  RegisterAtlasCommands(app, context);
  RegisterBatchCommands(app, context);
  RegisterStudyCommands(app, context);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitUsage;
  }

  context.global.token = FindToken(context.global.server);
  Connection connection(context.global);
  return context.RunParsed(connection);
}

}  // namespace
}  // namespace pba::cli

int main(int argc, char** argv) { return pba::cli::RunPba(argc, argv); }
