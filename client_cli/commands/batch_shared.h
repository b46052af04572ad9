// What `pba batch run` and `pba study convergence` share: paths into a scene
// or a summary ("results.reactions[0].force_n[2]"), and running a set of
// member jobs with bounded parallelism, resumable through a state file.
#pragma once

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <string>
#include <vector>

#include "connection.h"
#include "pba/v1/job.pb.h"

namespace pba::cli {

// "a.b[2].c" -> {"a", "b", "[2]", "c"}; false on a malformed path.
bool SplitPath(const std::string& path, std::vector<std::string>* parts);

// Sets `path` in `node` to `value`, creating maps on the way; a list index
// must exist. False with *error naming the part that does not fit.
bool SetPath(YAML::Node node, const std::string& path, const YAML::Node& value, std::string* error);

// The value at `path` in a document (JSON read as YAML); "" when absent.
std::string GetPath(const YAML::Node& root, const std::string& path);

// A YAML value as one line: a scalar as written, anything else in flow style.
std::string Scalar(const YAML::Node& value);

// A CSV cell, quoted when it holds a comma, a quote or a line break.
std::string CsvCell(const std::string& text);

// A summary as a tree for GetPath. With `zeros`, fields at their default
// (0, empty) are present too, so that a zero result reads as 0, not as absent.
YAML::Node SummaryTree(const v1::Summary& summary, bool zeros);

// One job of a batch or a study.
struct RunMember {
  std::string name;  // for messages and the table
  std::string key;   // identifies the member in the state file
  v1::Scene scene;
  std::string request_id;  // the submit's idempotency key
  std::string job_id;      // from the state file or the submit
  v1::Job job;
};

// RunOptions::parallel: every member handed to the server at once (its
// queue, and Slurm behind it, bound how many run; a submit over the
// server's bound of open jobs per user waits for one to end).
inline constexpr int kParallelAll = 0;
// A batch file without `parallel`: all at once to a server whose executor
// is Slurm (a sweep goes as one job array), else kParallelDefault.
inline constexpr int kParallelAuto = -1;
inline constexpr int kParallelDefault = 2;

// `parallel` as given, or for kParallelAuto what the server suits.
int ParallelFor(Connection& connection, int parallel);

struct RunOptions {
  std::filesystem::path state;      // "job-id<TAB>key[<TAB>name]" per line
  bool name_in_state = false;       // write the name as a third column (for reading)
  v1::SnapshotRef snapshot;         // every member's atlas from it, when set
  int parallel = kParallelDefault;  // unfinished jobs at most; kParallelAll
  bool retry_failed = false;        // resubmit a failed or cancelled earlier job
  int ranks = 0;                    // MPI processes per job (SubmitJobRequest.ranks); 0: one
  double poll_s = 0.5;
  bool quiet = false;  // no progress lines (--json)
};

// Looks up the jobs the state file records: a member whose job exists keeps
// it (unless it failed and options.retry_failed), the others are returned
// (their indices) to be submitted. A failed member gets a new request id.
std::vector<size_t> ResumeMembers(Connection& connection, const RunOptions& options,
                                  std::vector<RunMember>* members);

// Submits `to_submit` with at most options.parallel unfinished jobs, writing
// the state file after each submit, and polls every member until all have
// ended. kExitOk, or the exit code of a request that failed (printed).
int SubmitAndPoll(Connection& connection, const RunOptions& options,
                  const std::vector<size_t>& to_submit, std::vector<RunMember>* members);

}  // namespace pba::cli
