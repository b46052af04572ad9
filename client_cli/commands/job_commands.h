// The `pba job ...` commands. Each returns the process exit code
// (exit_codes.h) and prints human text, or JSON with --json.
#pragma once

#include <string>

#include "connection.h"

namespace pba::cli {

struct SubmitArgs {
  std::string file;
  bool wait = false;
  std::string request_id;  // generated when empty
};

struct ListArgs {
  int page_size = 20;
  std::string page_token;
  bool all = false;
};

struct FetchArgs {
  std::string id;
  std::string out_dir;
};

int SubmitJob(Connection& connection, const SubmitArgs& args);
int ListJobs(Connection& connection, const ListArgs& args);
int ShowJob(Connection& connection, const std::string& id);
int WatchJob(Connection& connection, const std::string& id);
int CancelJob(Connection& connection, const std::string& id);
int FetchJob(Connection& connection, const FetchArgs& args);

}  // namespace pba::cli
