// pba: the command-line client of pba-server.
// Exit codes are listed in exit_codes.h and docs/cli.md.

#include <CLI/CLI.hpp>
#include <cstdlib>
#include <string>

#include "commands/job_commands.h"
#include "connection.h"
#include "exit_codes.h"

int main(int argc, char** argv) {
  using namespace pba::cli;
  CLI::App app{"pba: submit brain-biomechanics jobs to pba-server, follow them, fetch results"};
  app.set_version_flag("--version", "pba 0.1.0");
  app.require_subcommand(1);

  GlobalOptions global;
  if (const char* env = std::getenv("PBA_SERVER"); env != nullptr && *env != '\0')
    global.server = env;
  app.add_option("--server", global.server, "pba-server address HOST:PORT (env PBA_SERVER)")
      ->capture_default_str();
  app.add_flag("--json", global.json, "Print machine-readable JSON instead of tables");
  app.add_option("--timeout", global.timeout_s, "Deadline of each request in seconds")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();

  CLI::App* job = app.add_subcommand("job", "Submit, follow, cancel and fetch jobs");
  job->require_subcommand(1);

  SubmitArgs submit;
  CLI::App* submit_cmd = job->add_subcommand("submit", "Submit a scene file (YAML or JSON)");
  submit_cmd->add_option("file", submit.file, "Scene file")->required()->check(CLI::ExistingFile);
  submit_cmd->add_flag("--wait", submit.wait,
                       "Follow the job until it ends; exit with its outcome");
  submit_cmd->add_option(
      "--request-id", submit.request_id,
      "Idempotency key: a repeated submit with the same key returns the same job");

  ListArgs list;
  CLI::App* list_cmd = job->add_subcommand("list", "List jobs, newest first");
  list_cmd->add_option("--page-size", list.page_size, "Jobs per page")->check(CLI::Range(1, 500));
  list_cmd->add_option("--page-token", list.page_token, "Continue from a previous page");
  list_cmd->add_flag("--all", list.all, "Fetch every page");

  std::string id;
  CLI::App* status_cmd = job->add_subcommand("status", "Show one job, with its summary when done");
  status_cmd->add_option("id", id, "Job id")->required();
  CLI::App* watch_cmd = job->add_subcommand("watch", "Follow a job's progress until it ends");
  watch_cmd->add_option("id", id, "Job id")->required();
  CLI::App* cancel_cmd = job->add_subcommand("cancel", "Cancel a queued or running job");
  cancel_cmd->add_option("id", id, "Job id")->required();

  FetchArgs fetch;
  CLI::App* fetch_cmd = job->add_subcommand("fetch", "Download a finished job's result files");
  fetch_cmd->add_option("id", fetch.id, "Job id")->required();
  fetch_cmd->add_option("-o,--out", fetch.out_dir, "Directory to write into (created)")->required();

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitUsage;
  }

  Connection connection(global);
  if (*submit_cmd) return SubmitJob(connection, submit);
  if (*list_cmd) return ListJobs(connection, list);
  if (*status_cmd) return ShowJob(connection, id);
  if (*watch_cmd) return WatchJob(connection, id);
  if (*cancel_cmd) return CancelJob(connection, id);
  if (*fetch_cmd) return FetchJob(connection, fetch);
  return kExitUsage;
}
