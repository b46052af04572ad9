// What every executor does around one pba-solve run, wherever it runs (a
// child of the server: job_executor.h; a Slurm job: slurm_executor.h): the
// job's folder prepared, pba-solve's --progress=json lines turned into job
// events, the result collected and checked, the end recorded and published.
#pragma once

#include <google/protobuf/timestamp.pb.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "jobs/job_event_hub.h"
#include "jobs/solver_process.h"
#include "pba/status.h"
#include "pba/v1/job.pb.h"
#include "pba/v1/solve_event.pb.h"
#include "store/job_store.h"

namespace pba {

class JobPreparation;
struct ExecutorOptions;

// Progress is stored when the phase changes or it grew by this much.
inline constexpr double kStoredProgressStep = 0.05;

// The wall clock to the microsecond, as the store stamps the events it makes.
google::protobuf::Timestamp EventTimeNow();

void LogStateChange(const v1::JobEvent& event);

// The job's folder `dir`, ready for pba-solve: what an earlier attempt left
// removed, inputs staged (by `preparation`, when there is one), scene.json
// written, the attempt noted in solve.log. *input: pba-solve's input
// arguments.
Status PrepareFolder(const v1::Job& job, const std::filesystem::path& dir,
                     JobPreparation* preparation, std::vector<std::string>* input);

// pba-solve's hidden staging siblings of result/ (.result.partial-PID,
// .result.old-PID) that a solve ended without its own cleanup leaves.
void RemoveStagingLeftovers(const std::filesystem::path& dir);

// summary.json and every file of a finished result folder, with digests,
// once the folder is checked against the SHA256SUMS pba-solve wrote last
// (core/checksum_file.h): kIo naming a file missing, damaged or not
// listed, or the list missing (the result is incomplete).
Status CollectResult(const std::filesystem::path& dir, v1::Summary* summary,
                     std::vector<v1::ResultFile>* files);

// Why a run failed: pba-solve's ERROR event when it wrote one, else how the
// process ended.
std::string FailureReason(const v1::SolveEvent* error, const ProcessExit& exit);

// pba-solve's stdout lines of one run: PROGRESS events published as job
// events (stored when the phase changes or the progress grew by
// kStoredProgressStep), the ERROR event kept for the failure reason.
class ProgressLines {
 public:
  // `sequence`: the job's last event number so far.
  ProgressLines(JobStore& store, JobEventHub& hub, std::string id, int64_t sequence);
  void Handle(const std::string& line);
  // A line of a run followed from the middle (a server re-attached to it):
  // only an ERROR event is kept; progress already told is not told again.
  void Skim(const std::string& line);
  // The job's last event number so far.
  int64_t sequence() const { return sequence_; }
  void set_sequence(int64_t sequence) { sequence_ = sequence; }
  // pba-solve's ERROR event, nullptr when it wrote none.
  const v1::SolveEvent* error() const { return have_error_ ? &error_ : nullptr; }

 private:
  JobStore& store_;
  JobEventHub& hub_;
  std::string id_;
  int64_t sequence_;
  std::string stored_phase_;
  double stored_progress_ = 0;
  bool have_error_ = false;
  v1::SolveEvent error_;
};

// pba-solve's command line for `job` (the program first): `input`, --out
// `result_dir`, --progress=json, --threads (the server's share per rank),
// the atlas cache; a job on several ranks under mpirun.
std::vector<std::string> SolverCommandLine(const ExecutorOptions& options, const v1::Job& job,
                                           const std::vector<std::string>& input,
                                           const std::filesystem::path& result_dir);
// The address-space limit of each of the job's pba-solve processes
// [bytes]: the server's limit shared among its ranks (each inherits it);
// 0: none.
int64_t SolverMemoryPerRank(const ExecutorOptions& options, const v1::Job& job);

// The result files of jobs that ended more than `keep` ago are removed
// (their folders under `jobs_dir`), and each job says so; nothing when
// `keep` is 0.
void ExpireResults(JobStore& store, const std::filesystem::path& jobs_dir,
                   std::chrono::seconds keep);

// Records how a run ended (the staged inputs of the job's folder `dir`
// removed first) and publishes it; `sequence` the job's last event number.
void RecordRunEnd(JobStore& store, JobEventHub& hub, const std::filesystem::path& dir,
                  const std::string& id, int64_t sequence, RunOutcome outcome);

// Ends a QUEUED job (CANCELLED or FAILED) with `message`, and publishes
// it; nothing when it is no longer QUEUED.
Status EndQueuedJob(JobStore& store, JobEventHub& hub, const std::string& id, v1::Job::State state,
                    const std::string& message);

// Puts a RUNNING job back in the queue, saying why, and publishes it.
void RecordRequeue(JobStore& store, JobEventHub& hub, const std::string& id, int64_t sequence,
                   const std::string& message);

}  // namespace pba
