#include "jobs/job_run.h"

#include <google/protobuf/util/json_util.h>
#include <google/protobuf/util/time_util.h>
#include <spdlog/fmt/fmt.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <system_error>

#include "core/atomic_write.h"
#include "core/checksum_file.h"
#include "core/exit_codes.h"
#include "core/sha256.h"
#include "jobs/job_executor.h"

namespace pba {
namespace fs = std::filesystem;
namespace {

using google::protobuf::util::TimeUtil;

// Removes what an earlier attempt left: a complete result of a run whose end
// was never recorded, and pba-solve's hidden staging siblings (.result.*).
// pba-solve's --out is then always new (it replaces an earlier result only
// with --force, which the server never passes).
Status ClearFolder(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return Status::Io("cannot create " + dir.string() + ": " + ec.message());
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name == "result" || name.rfind(".result.", 0) == 0) {
      std::error_code remove_ec;
      fs::remove_all(entry.path(), remove_ec);
      if (remove_ec) {
        return Status::Io("cannot remove " + entry.path().string() + ": " + remove_ec.message());
      }
    }
  }
  if (ec) return Status::Io("cannot list " + dir.string() + ": " + ec.message());
  return Status::Ok();
}

}  // namespace

// The wall clock to the microsecond, as the store stamps the events it makes.
// (TimeUtil::GetCurrentTime() of protobuf 3.21 has whole seconds only, which
// put progress events up to a second before the events stored ahead of them.)
google::protobuf::Timestamp EventTimeNow() {
  return TimeUtil::MicrosecondsToTimestamp(std::chrono::duration_cast<std::chrono::microseconds>(
                                               std::chrono::system_clock::now().time_since_epoch())
                                               .count());
}

void LogStateChange(const v1::JobEvent& event) {
  spdlog::info("job {} {}: {}", event.job_id(), v1::Job::State_Name(event.state()),
               event.message());
}

// pba-solve's hidden staging siblings of result/ (.result.partial-PID,
// .result.old-PID), left when a solve ends without its own cleanup: its
// cancel watchdog exits at once, even while the result is being written
// (pba_solve_main.cc), and a SIGKILL (past the grace, the time limit) or
// the address-space limit leaves no chance either. Called once pba-solve
// has exited.
void RemoveStagingLeftovers(const fs::path& dir) {
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
    if (entry.path().filename().string().rfind(".result.", 0) != 0) continue;
    std::error_code remove_ec;
    fs::remove_all(entry.path(), remove_ec);
    if (remove_ec) {
      spdlog::warn("cannot remove {}: {}", entry.path().string(), remove_ec.message());
    }
  }
}

// The job's folder, ready for pba-solve: inputs staged (by `preparation`,
// when there is one), scene.json written, the attempt noted in solve.log.
// *input: pba-solve's input arguments.
Status PrepareFolder(const v1::Job& job, const fs::path& dir, JobPreparation* preparation,
                     std::vector<std::string>* input) {
  PBA_RETURN_IF_ERROR(ClearFolder(dir));
  v1::Scene scene = job.scene();
  input->clear();
  if (preparation != nullptr) PBA_RETURN_IF_ERROR(preparation->Stage(job, dir, &scene, input));
  if (input->empty()) {
    std::string json;
    google::protobuf::util::JsonPrintOptions options;
    options.preserve_proto_field_names = true;
    options.add_whitespace = true;
    if (!google::protobuf::util::MessageToJsonString(scene, &json, options).ok()) {
      return Status::Internal("cannot write the scene as JSON");
    }
    PBA_RETURN_IF_ERROR(AtomicWriteText(dir / "scene.json", json));
    input->push_back((dir / "scene.json").string());
  }

  std::ofstream log(dir / "solve.log", std::ios::app);
  log << "=== attempt " << job.attempts() << ", " << TimeUtil::ToString(EventTimeNow()) << " ===\n";
  return Status::Ok();
}

// summary.json and every file of a finished result folder, each checked
// against the SHA256SUMS pba-solve wrote last: a file lost, cut short or
// changed since (on the shared filesystem between a Slurm node and the
// server, say) fails the collection naming it.
Status CollectResult(const fs::path& dir, v1::Summary* summary,
                     std::vector<v1::ResultFile>* files) {
  std::vector<ChecksummedFile> checked;
  PBA_RETURN_IF_ERROR(VerifyChecksumFile(dir, &checked));
  std::ifstream in(dir / "summary.json");
  if (!in) return Status::Io("the result has no summary.json");
  std::stringstream json;
  json << in.rdbuf();
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = true;  // a newer pba-solve may say more
  const auto parsed = google::protobuf::util::JsonStringToMessage(json.str(), summary, options);
  if (!parsed.ok()) {
    return Status::Io("summary.json is not a pba.v1.Summary: " + std::string(parsed.message()));
  }
  // The folder's own files are the job's (an import's structures/ are
  // the store's to take); the list goes with them, for `sha256sum -c`.
  ChecksummedFile list;
  list.path = kChecksumFileName;
  PBA_RETURN_IF_ERROR(FileSha256Hex(dir / list.path, &list.sha256, &list.size));
  checked.push_back(list);
  for (const ChecksummedFile& file : checked) {
    if (file.path.find('/') != std::string::npos) continue;
    v1::ResultFile result;
    result.set_name(file.path);
    result.set_sha256(file.sha256);
    result.set_size_bytes(file.size);
    files->push_back(std::move(result));
  }
  std::sort(files->begin(), files->end(),
            [](const v1::ResultFile& a, const v1::ResultFile& b) { return a.name() < b.name(); });
  return Status::Ok();
}

std::string FailureReason(const v1::SolveEvent* error, const ProcessExit& exit) {
  if (error != nullptr && !error->message().empty()) {
    // pba-solve's message is the whole status, its field first already.
    const std::string prefix = error->field() + ": ";
    return error->field().empty() || error->message().rfind(prefix, 0) == 0
               ? error->message()
               : prefix + error->message();
  }
  if (exit.signaled) {
    return "pba-solve was killed by signal " + std::to_string(exit.signal) + " (" +
           SignalName(exit.signal) + ")";
  }
  // Without an ERROR line (a bad command line, the cancel watchdog, a
  // crash) the code is all there is: its meaning from the shared table.
  const ExitCodeInfo* known = FindExitCode(exit.code);
  return "pba-solve exited with code " + std::to_string(exit.code) +
         (known != nullptr ? std::string(" (") + known->meaning + ")" : std::string());
}

ProgressLines::ProgressLines(JobStore& store, JobEventHub& hub, std::string id, int64_t sequence)
    : store_(store), hub_(hub), id_(std::move(id)), sequence_(sequence) {}

void ProgressLines::Skim(const std::string& line) {
  v1::SolveEvent solve_event;
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = true;
  if (google::protobuf::util::JsonStringToMessage(line, &solve_event, options).ok() &&
      solve_event.kind() == v1::SolveEvent::ERROR) {
    have_error_ = true;
    error_ = solve_event;
  }
}

void ProgressLines::Handle(const std::string& line) {
  if (line.empty()) return;
  v1::SolveEvent solve_event;
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = true;  // a newer pba-solve may say more
  if (!google::protobuf::util::JsonStringToMessage(line, &solve_event, options).ok()) {
    spdlog::debug("job {}: ignoring a stdout line that is not a SolveEvent: {}", id_,
                  line.substr(0, 200));
    return;
  }
  if (solve_event.kind() == v1::SolveEvent::ERROR) {
    have_error_ = true;
    error_ = solve_event;
    return;
  }
  if (solve_event.kind() != v1::SolveEvent::PROGRESS) return;
  v1::JobEvent event;
  event.set_job_id(id_);
  event.set_sequence(++sequence_);
  *event.mutable_time() = EventTimeNow();
  event.set_state(v1::Job::RUNNING);
  event.set_phase(solve_event.phase());
  event.set_progress(std::clamp(solve_event.progress(), 0.0, 1.0));
  event.set_message(solve_event.message());
  if (event.phase() != stored_phase_ ||
      event.progress() >= stored_progress_ + kStoredProgressStep) {
    const Status status = store_.RecordProgress(&event);
    if (status.ok()) {
      sequence_ = event.sequence();
      stored_phase_ = event.phase();
      stored_progress_ = event.progress();
    } else {
      spdlog::warn("job {}: cannot store progress: {}", id_, status.ToString());
    }
  }
  hub_.Publish(event);
}

std::vector<std::string> SolverCommandLine(const ExecutorOptions& options, const v1::Job& job,
                                           const std::vector<std::string>& input,
                                           const fs::path& result_dir) {
  const int ranks = std::max(1, job.ranks());
  std::vector<std::string> line;
  if (ranks > 1) {
    // Not bound to cores: jobs running side by side would each bind their
    // ranks to the first cores. Root needs saying so to Open MPI.
    line = {options.mpirun.string(), "-np", std::to_string(ranks), "--bind-to", "none"};
    if (::geteuid() == 0) line.push_back("--allow-run-as-root");
  }
  line.push_back(options.solver.string());
  line.insert(line.end(), input.begin(), input.end());
  line.insert(line.end(), {"--out", result_dir.string(), "--progress=json"});
  if (options.solver_threads > 0) {
    line.push_back("--threads");
    line.push_back(std::to_string(std::max(1, options.solver_threads / ranks)));
  }
  if (!options.atlas_cache_dir.empty()) {
    line.insert(line.end(), {"--atlas-cache", options.atlas_cache_dir.string(),
                             "--atlas-cache-size", fmt::format("{}", options.atlas_cache_gib)});
  }
  return line;
}

int64_t SolverMemoryPerRank(const ExecutorOptions& options, const v1::Job& job) {
  return options.max_solver_memory_bytes / std::max(1, job.ranks());
}

void ExpireResults(JobStore& store, const fs::path& jobs_dir, std::chrono::seconds keep) {
  if (keep.count() <= 0) return;
  const int64_t now_us = std::chrono::duration_cast<std::chrono::microseconds>(
                             std::chrono::system_clock::now().time_since_epoch())
                             .count();
  const int64_t cutoff =
      now_us - std::chrono::duration_cast<std::chrono::microseconds>(keep).count();
  const std::string note =
      fmt::format("result files removed {:.3g} days after the job ended", keep.count() / 86400.0);
  std::vector<std::string> ids;
  const Status status = store.ExpireResults(cutoff, note, &ids);
  if (!status.ok()) {
    spdlog::error("cannot expire old results: {}", status.ToString());
    return;
  }
  for (const std::string& id : ids) {
    std::error_code ec;
    fs::remove_all(jobs_dir / id, ec);
    if (ec) spdlog::warn("cannot remove the folder of job {}: {}", id, ec.message());
  }
  if (!ids.empty()) spdlog::info("removed the result files of {} old job(s)", ids.size());
}

void RecordRunEnd(JobStore& store, JobEventHub& hub, const fs::path& dir, const std::string& id,
                  int64_t sequence, RunOutcome outcome) {
  // Inputs staged for the run (a snapshot's structures, an import's
  // source) are copies of what the store keeps: not kept after it.
  for (const char* staged : {"snapshot", "source"}) {
    std::error_code ec;
    fs::remove_all(dir / staged, ec);
  }
  RemoveStagingLeftovers(dir);
  if (outcome.message.empty()) {
    outcome.message = outcome.state == v1::Job::SUCCEEDED ? "succeeded" : outcome.error;
  }
  v1::JobEvent event;
  const Status status = store.FinishRun(id, sequence + 1, outcome, &event);
  if (!status.ok()) {
    spdlog::error("job {}: cannot record its end: {}", id, status.ToString());
    return;
  }
  hub.Publish(event);
  LogStateChange(event);
}

Status EndQueuedJob(JobStore& store, JobEventHub& hub, const std::string& id, v1::Job::State state,
                    const std::string& message) {
  v1::JobEvent event;
  bool ended = false;
  PBA_RETURN_IF_ERROR(store.EndQueued(id, state, message, &event, &ended));
  if (ended) {
    hub.Publish(event);
    LogStateChange(event);
  }
  return Status::Ok();
}

void RecordRequeue(JobStore& store, JobEventHub& hub, const std::string& id, int64_t sequence,
                   const std::string& message) {
  v1::JobEvent event;
  const Status status = store.RequeueRun(id, sequence + 1, message, &event);
  if (!status.ok()) {
    spdlog::error("job {}: cannot re-queue: {}", id, status.ToString());
    return;
  }
  hub.Publish(event);
  LogStateChange(event);
}

}  // namespace pba
