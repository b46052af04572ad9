#include "commands/command_context.h"

#include <CLI/CLI.hpp>
#include <cstdlib>

#include "exit_codes.h"

namespace pba::cli {

CommandContext::CommandContext() {
  if (const char* env = std::getenv("PBA_PROJECT"); env != nullptr) project_env_ = env;
}

void CommandContext::Add(CLI::App* command, std::function<int(Connection&)> action) {
  actions_.emplace_back(command, std::move(action));
}

int CommandContext::RunParsed(Connection& connection) const {
  for (const auto& [command, action] : actions_) {
    if (command->parsed()) return action(connection);
  }
  return kExitUsage;
}

void CommandContext::AddProjectOption(CLI::App* command, std::string* project) const {
  *project = project_env_;
  CLI::Option* option = command->add_option("-p,--project", *project, "Project (env PBA_PROJECT)");
  if (project_env_.empty()) option->required();
}

CLI::App* AddCommandGroup(CLI::App& parent, const std::string& name,
                          const std::string& description) {
  CLI::App* group = parent.add_subcommand(name, description);
  group->require_subcommand(1);
  return group;
}

void AddPagingOptions(CLI::App* command, PageArgs* page) {
  command->add_option("--page-size", page->page_size, "Entries per page")
      ->check(CLI::Range(1, 1000));
  command->add_option("--page-token", page->page_token, "Continue from a previous page");
  command->add_flag("--all", page->all, "Fetch every page");
}

void AddRequestIdOption(CLI::App* command, std::string* request_id, const char* what) {
  command->add_option("--request-id", *request_id,
                      std::string("Idempotency key: a rerun with the same key returns the ") +
                          what + " the first run created (default: a fresh random key)");
}

}  // namespace pba::cli
