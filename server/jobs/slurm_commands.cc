#include "jobs/slurm_commands.h"

#include <spdlog/fmt/fmt.h>

#include <algorithm>
#include <cctype>

namespace pba {
namespace fs = std::filesystem;
namespace {

std::string ShellQuoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// Slurm's time limit in whole minutes, rounded up: Slurm counts no finer
// (a limit of seconds becomes a minute there anyway).
std::string SlurmTime(int64_t seconds) { return std::to_string((seconds + 59) / 60); }

// The lines of `text`, each split at '|' into trimmed fields.
std::vector<std::vector<std::string>> FieldLines(const std::string& text) {
  std::vector<std::vector<std::string>> lines;
  std::size_t start = 0;
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    const std::string line = text.substr(start, end - start);
    start = end + 1;
    std::vector<std::string>& fields = lines.emplace_back();
    std::size_t from = 0;
    for (std::size_t bar; (bar = line.find('|', from)) != std::string::npos; from = bar + 1)
      fields.push_back(SlurmTrim(line.substr(from, bar - from)));
    fields.push_back(SlurmTrim(line.substr(from)));
  }
  return lines;
}

}  // namespace

std::string SlurmJobName(const std::string& id) { return "pba-" + id; }

std::string SlurmProgressFile(const std::string& run) { return "progress-" + run + ".jsonl"; }

std::string SlurmTrim(std::string s) {
  const auto space = [](unsigned char c) { return std::isspace(c) != 0; };
  s.erase(s.begin(), std::find_if_not(s.begin(), s.end(), space));
  s.erase(std::find_if_not(s.rbegin(), s.rend(), space).base(), s.end());
  return s;
}

bool IsSlurmJobId(const std::string& id) {
  return !id.empty() && id.size() <= 32 &&
         std::all_of(id.begin(), id.end(), [](char c) { return std::isdigit(c) || c == '_'; });
}

std::chrono::steady_clock::duration GatherLeft(std::chrono::steady_clock::time_point first,
                                               std::chrono::steady_clock::time_point last,
                                               std::chrono::steady_clock::time_point now,
                                               std::chrono::milliseconds gather) {
  if (first == std::chrono::steady_clock::time_point{}) return {};
  const auto until = std::min(last + gather, first + gather * kSlurmGatherCap);
  return now >= until ? std::chrono::steady_clock::duration{} : until - now;
}

std::vector<SlurmJobState> ParseSacct(const std::string& text, const std::string& slurm_id) {
  std::vector<SlurmJobState> found;
  for (const std::vector<std::string>& f : FieldLines(text)) {
    if (f.size() >= 2 && f[0] == slurm_id && !f[1].empty())
      found.push_back({slurm_id, "", f[1], "", ""});
  }
  return found;
}

std::vector<SlurmJobState> ParseSqueue(const std::string& text) {
  std::vector<SlurmJobState> jobs;
  for (const std::vector<std::string>& f : FieldLines(text)) {
    if (f.size() == 5 && IsSlurmJobId(f[0]) && !f[2].empty())
      jobs.push_back({f[0], f[1], f[2], f[3], f[4]});
  }
  return jobs;
}

SlurmEnd ClassifySlurmState(const std::string& state_text) {
  // squeue may add a flag ("CANCELLED by 0"): the first word is the state.
  const std::string state = state_text.substr(0, state_text.find(' '));
  if (state == "COMPLETED") return SlurmEnd::kCompleted;
  if (state == "TIMEOUT") return SlurmEnd::kTimeout;
  if (state == "OUT_OF_MEMORY") return SlurmEnd::kOutOfMemory;
  if (state == "CANCELLED") return SlurmEnd::kCancelled;
  if (state == "NODE_FAIL" || state == "PREEMPTED" || state == "BOOT_FAIL")
    return SlurmEnd::kRequeue;
  if (state == "FAILED" || state == "DEADLINE" || state == "SPECIAL_EXIT" || state == "REVOKED")
    return SlurmEnd::kFailed;
  return SlurmEnd::kNotEnded;  // PENDING, RUNNING, CONFIGURING, COMPLETING, SUSPENDED, ...
}

bool SlurmRunning(const std::string& state) {
  return state == "RUNNING" || state == "COMPLETING" || state == "CONFIGURING" ||
         state == "SUSPENDED" || state == "STOPPED" || state == "SIGNALING" || state == "STAGE_OUT";
}

std::vector<std::string> SbatchArguments(const SlurmOptions& options, const SlurmSubmission& s) {
  // A task of an array writes through its entry, into its job's folder.
  const bool array = s.array_tasks > 0;
  const fs::path run_dir = array ? s.dir / "%a" : s.dir;
  std::vector<std::string> args = {
      "--parsable",
      "--job-name=" + (array ? kSlurmArrayPrefix + s.job_id : SlurmJobName(s.job_id)),
      "--chdir=" + s.dir.string(),
      "--output=" + (run_dir / SlurmProgressFile(array ? "%A_%a" : "%j")).string(),
      "--error=" + (run_dir / "solve.log").string(),
      "--open-mode=append",
      // PBA runs a job again itself (max_attempts), as a new Slurm job.
      "--no-requeue",
      "--ntasks=" + std::to_string(std::max(1, s.ranks)),
      "--cpus-per-task=" + std::to_string(std::max(1, s.cpus_per_task)),
  };
  if (s.time_limit_s > 0) args.push_back("--time=" + SlurmTime(s.time_limit_s));
  if (s.memory_bytes > 0) {
    const int64_t mib = (s.memory_bytes + (int64_t{1} << 20) - 1) >> 20;
    args.push_back("--mem=" + std::to_string(mib) + "M");
  }
  if (array) args.push_back("--array=0-" + std::to_string(s.array_tasks - 1));
  if (!options.partition.empty()) args.push_back("--partition=" + options.partition);
  if (!options.account.empty()) args.push_back("--account=" + options.account);
  args.push_back(s.script.string());
  return args;
}

std::string SlurmBatchScript(const std::vector<std::string>& command, int64_t memory_bytes) {
  std::string script =
      "#!/bin/sh\n"
      "# A PBA job: pba-solve in this folder, its result to result-<run>, its\n"
      "# exit code to exit_code-<run>; <run> is the Slurm job id, or the array\n"
      "# task's <array job id>_<task id>.\n"
      "run=\"${PBA_RUN_ID:-$SLURM_JOB_ID}\"\n"
      "ulimit -c 0\n";
  if (memory_bytes > 0) script += fmt::format("ulimit -v {}\n", memory_bytes / 1024);
  for (std::size_t i = 0; i < command.size(); ++i) {
    script += i == 0 ? "" : " ";
    script += command[i] == kSlurmRunResult ? "result-\"$run\"" : ShellQuoted(command[i]);
  }
  script += "\ncode=$?\n";
  script +=
      "printf '%s\\n' \"$code\" > exit_code-\"$run\".partial &&\n"
      "  mv -f exit_code-\"$run\".partial exit_code-\"$run\"\n"
      "exit \"$code\"\n";
  return script;
}

std::string SlurmArrayScript(const std::string& job_script) {
  return "#!/bin/sh\n"
         "# A PBA job array: task N runs the job whose folder entry N links to.\n"
         "cd \"$SLURM_ARRAY_TASK_ID\" || exit 1\n"
         "PBA_RUN_ID=\"${SLURM_ARRAY_JOB_ID}_${SLURM_ARRAY_TASK_ID}\" exec /bin/sh " +
         ShellQuoted("./" + job_script) + "\n";
}

bool ReadBoundedLine(std::istream& in, std::size_t max, std::string* line) {
  line->clear();
  bool any = false, over = false;
  for (int c = in.get(); c != std::char_traits<char>::eof(); c = in.get()) {
    any = true;
    if (c == '\n') break;
    if (line->size() < max) {
      line->push_back(static_cast<char>(c));
    } else {
      over = true;
    }
  }
  if (over) line->clear();
  return any;
}

}  // namespace pba
