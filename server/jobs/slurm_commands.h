// Slurm's command language as PBA speaks it: the options of a
// Slurm-backed server, the sbatch line and the batch scripts of a job or a
// job array, squeue's and sacct's answers parsed, Slurm's states as PBA
// takes them, and how long a round of submits is gathered. Pure functions:
// the executor (slurm_executor.h) runs the commands.
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <istream>
#include <string>
#include <vector>

namespace pba {

// With ExecutorOptions::jobs_dir a directory every compute node sees at
// the same path (the job folders, and the atlas mesh cache).
struct SlurmOptions {
  std::string partition;  // empty: Slurm's default partition
  std::string account;    // empty: the user's default account
  // CPUs of each rank (--cpus-per-task), pba-solve's --threads.
  int cpus_per_task = 1;
  // The most jobs in Slurm's hands (pending or running) at once; the rest
  // wait in PBA's queue.
  int max_submitted = 1000;
  // Jobs with the same limits handed to Slurm in one round go as one job
  // array (up to kSlurmArrayMax tasks each) when there are at least this
  // many, as Slurm users submit a sweep; 0: each its own Slurm job.
  int array_min = 10;
  // How often squeue is asked.
  std::chrono::milliseconds poll{2000};
  // After a submit wakes the executor, queued jobs go to Slurm once no new
  // one has come for `gather` (or `gather` × kSlurmGatherCap after the
  // first): a sweep a client submits job by job is one round, so one array.
  // 0: at once.
  std::chrono::milliseconds gather{1000};
  // A job Slurm completed whose exit code or result is not whole here yet
  // (a shared filesystem may show a node's last writes late: NFS caches
  // directory entries up to a minute) is looked at again at each poll for
  // up to `settle` before it is judged on what is there.
  std::chrono::milliseconds settle{60000};
  // Where sbatch, squeue and scancel are (empty: on PATH), and the
  // environment they get (e.g. SLURM_CONF=...).
  std::filesystem::path bin_dir;
  std::vector<std::string> env;
  // Time limit of each Slurm command.
  std::chrono::milliseconds command_timeout{60000};
};

// The most tasks in one job array (Slurm's default MaxArraySize allows
// task ids up to 1000).
inline constexpr int kSlurmArrayMax = 1000;

// The longest a stream of submits holds the jobs back, in `gather`s.
inline constexpr int kSlurmGatherCap = 10;

// A Slurm job as squeue shows it (a task of a job array: id
// "<array job id>_<task id>").
struct SlurmJobState {
  std::string id, name, state, reason, node;
};

// squeue -h -o '%i|%j|%T|%r|%N' lines, as jobs (a line that does not
// parse is skipped).
std::vector<SlurmJobState> ParseSqueue(const std::string& text);

// sacct --parsable2 lines "JobID|State|ExitCode" of `slurm_id`, in order
// (a job run again has one for each end).
std::vector<SlurmJobState> ParseSacct(const std::string& text, const std::string& slurm_id);

// How PBA takes each Slurm state.
enum class SlurmEnd {
  kNotEnded,  // PENDING, RUNNING, CONFIGURING, COMPLETING, SUSPENDED, ...
  kCompleted,
  kFailed,       // FAILED, DEADLINE, SPECIAL_EXIT, and states PBA does not know
  kTimeout,      // TIMEOUT
  kOutOfMemory,  // OUT_OF_MEMORY
  kCancelled,    // CANCELLED (by PBA or by someone with scancel)
  kRequeue,      // NODE_FAIL, PREEMPTED, BOOT_FAIL: the job is run again
};
SlurmEnd ClassifySlurmState(const std::string& state);
bool SlurmRunning(const std::string& state);  // RUNNING or COMPLETING

// The sbatch command line (without the program) of one job: its folder,
// name, limits and script; or of a job array of `array_tasks` tasks, each
// running in entry <task id> of `dir`, a link to its job's folder.
struct SlurmSubmission {
  std::string job_id;  // PBA's; of an array, its name in the jobs folder's arrays/
  std::filesystem::path dir, script;
  int array_tasks = 0;  // 0: one job
  int ranks = 1;
  int cpus_per_task = 1;
  int64_t time_limit_s = 0;  // 0: the partition's
  int64_t memory_bytes = 0;  // 0: the partition's default
};
std::vector<std::string> SbatchArguments(const SlurmOptions& options, const SlurmSubmission& s);

// The batch script: runs `command` (the program first; an argument
// "@PBA_RUN_RESULT@" becomes result-<run>) in the job's folder, under an
// address-space limit when `memory_bytes` > 0, and writes its exit code to
// exit_code-<run> (through a temporary file: the file is there whole or not
// at all), where <run> is $PBA_RUN_ID, or $SLURM_JOB_ID without it. Each
// argument single-quoted for the shell.
std::string SlurmBatchScript(const std::vector<std::string>& command, int64_t memory_bytes);

// A job array's script: task N goes into the array folder's entry N (its
// job's folder) and runs that job's batch script (`job_script`, its name)
// with PBA_RUN_ID=<array job id>_<N>.
std::string SlurmArrayScript(const std::string& job_script);

// The Slurm job name of PBA job `id` (pba-<id>), of the job array named
// `name` (pba-array-<name>), and the prefix of the latter.
inline constexpr char kSlurmArrayPrefix[] = "pba-array-";
std::string SlurmJobName(const std::string& id);

// The file a run's progress lines go to: progress-<run>.jsonl, <run> its
// Slurm job id (of an array task, <array job id>_<task id>).
std::string SlurmProgressFile(const std::string& run);

// In a command line given to SlurmBatchScript: the run's result folder.
inline constexpr char kSlurmRunResult[] = "@PBA_RUN_RESULT@";

// Whether `id` looks like a Slurm job id (digits, '_' for an array task).
bool IsSlurmJobId(const std::string& id);

// `s` without leading and trailing white space.
std::string SlurmTrim(std::string s);

// How much longer the executor waits for more submits before it hands the
// queue to Slurm (SlurmOptions::gather): `first` and `last` are the first
// and the last submit since the last round (the epoch: none since). Zero:
// hand them over now. At most `gather` after the last submit, and at most
// kSlurmGatherCap × `gather` after the first.
std::chrono::steady_clock::duration GatherLeft(std::chrono::steady_clock::time_point first,
                                               std::chrono::steady_clock::time_point last,
                                               std::chrono::steady_clock::time_point now,
                                               std::chrono::milliseconds gather);

// The next line of `in` without its newline, false at the end. A line of
// more than `max` characters (a list file of the shared folder someone
// wrote over) is read past whole and given as "", so that no file makes
// the server hold an unbounded line.
bool ReadBoundedLine(std::istream& in, std::size_t max, std::string* line);

}  // namespace pba
