// The `pba job ...` commands. Each returns the process exit code
// (exit_codes.h) and prints human text, or JSON with --json.
#pragma once

#include <string>

#include "connection.h"
#include "pba/v1/job.pb.h"

namespace CLI {
class App;
}

namespace pba::cli {

class CommandContext;

// Adds `pba job submit|list|status|watch|cancel|fetch` to `app`.
void RegisterJobCommands(CLI::App& app, CommandContext& context);

struct SubmitArgs {
  std::string file;
  bool wait = false;
  std::string request_id;  // generated when empty
  std::string snapshot;    // PROJECT/SNAPSHOT (id or tag); empty: none
  int priority = 0;
  int timeout_s = 0;
  int ranks = 0;  // MPI processes; 0 or 1: one
};

// "PROJECT/SNAPSHOT" into a SnapshotRef; false (with a message on stderr)
// when it is not of that form.
bool ParseSnapshotRef(const std::string& text, v1::SnapshotRef* ref);

// Follows a job until it ends and reports how (as `pba job submit --wait`),
// returning the exit code for its outcome.
int WaitForJob(Connection& connection, const std::string& id);

struct ListArgs {
  int page_size = 20;
  std::string page_token;
  bool all = false;
};

struct FetchArgs {
  std::string id;
  std::string out_dir;
  bool force = false;  // replace files already in out_dir
};

int SubmitJob(Connection& connection, const SubmitArgs& args);
int ListJobs(Connection& connection, const ListArgs& args);
int ShowJob(Connection& connection, const std::string& id);
int WatchJob(Connection& connection, const std::string& id);
int CancelJob(Connection& connection, const std::string& id);
int FetchJob(Connection& connection, const FetchArgs& args);

}  // namespace pba::cli
