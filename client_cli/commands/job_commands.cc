#include "commands/job_commands.h"

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <set>

#include "codec/summary_text.h"
#include "codec/yaml_codec.h"
#include "commands/atlas_shared.h"
#include "commands/command_context.h"
#include "exit_codes.h"
#include "files.h"
#include "output.h"
#include "transfer.h"

namespace pba::cli {
namespace fs = std::filesystem;

namespace {

int ExitForState(v1::Job::State state) {
  switch (state) {
    case v1::Job::SUCCEEDED:
      return kExitOk;
    case v1::Job::FAILED:
      return kExitJobFailed;
    case v1::Job::CANCELLED:
      return kExitCancelled;
    default:
      return kExitNotReady;
  }
}

void PrintJobDetails(const v1::Job& job) {
  std::vector<std::vector<std::string>> rows = {
      {"Job", job.id()},
      {"Name", job.name()},
      {"State", StateName(job.state())},
      {"Progress", std::to_string(static_cast<int>(job.progress() * 100 + 0.5)) + " %" +
                       (job.phase().empty() ? "" : " (" + job.phase() + ")")},
      {"Created", FormatTime(job.create_time()) + " UTC"},
      {"Started", FormatTime(job.start_time())},
      {"Ended", FormatTime(job.end_time())},
      {"Run time", FormatDuration(job.start_time(), job.end_time())},
      {"Attempts", std::to_string(job.attempts())},
      {"Owner", job.owner()},
  };
  if (job.priority() != 0) rows.push_back({"Priority", std::to_string(job.priority())});
  if (job.timeout_s() > 0) rows.push_back({"Time limit", std::to_string(job.timeout_s()) + " s"});
  if (job.ranks() > 1) rows.push_back({"MPI ranks", std::to_string(job.ranks())});
  if (job.has_scheduler()) {
    // Where a cluster scheduler has it, in the scheduler's own words.
    const v1::SchedulerJob& s = job.scheduler();
    std::string said = s.state();
    if (!s.reason().empty() && s.reason() != "None") said += ", reason " + s.reason();
    if (!s.node().empty() && s.node() != "(null)") said += ", on " + s.node();
    rows.push_back({s.system() == "slurm" ? "Slurm job" : s.system() + " job",
                    s.job_id() + (said.empty() ? "" : " (" + said + ")")});
  }
  if (job.has_atlas_import()) {
    rows.push_back({"Imports into", job.atlas_import().project()});
  }
  if (!job.snapshot().project().empty()) {
    rows.push_back({job.has_atlas_import() ? "Made snapshot" : "Snapshot",
                    job.snapshot().project() + "/" + job.snapshot().snapshot()});
  }
  if (!job.error().empty()) rows.push_back({"Error", job.error()});
  for (const auto& file : job.result_files()) {
    rows.push_back(
        {"Result file", file.name() + " (" + std::to_string(file.size_bytes()) + " bytes)"});
  }
  PrintTable(rows);
  if (job.has_summary()) std::printf("\n%s", codec::FormatSummary(job.summary()).c_str());
}

bool GetJob(Connection& connection, const std::string& id, v1::Job* job, int* exit_code) {
  v1::GetJobRequest request;
  request.set_id(id);
  auto context = connection.UnaryContext();
  grpc::Status status = connection.jobs().GetJob(context.get(), request, job);
  if (!status.ok()) {
    *exit_code = connection.Fail("job " + id, status);
    return false;
  }
  return true;
}

// Follows the job's events until it ends; returns the final job state.
int Follow(Connection& connection, const std::string& id, v1::Job::State* final_state) {
  const bool interactive = !connection.options().json && ::isatty(STDOUT_FILENO);
  WatchDisplay display(interactive);
  v1::WatchJobRequest request;
  request.set_id(id);
  auto context = connection.StreamContext();
  auto reader = connection.jobs().WatchJob(context.get(), request);
  v1::JobEvent event;
  *final_state = v1::Job::STATE_UNSPECIFIED;
  while (reader->Read(&event)) {
    if (connection.options().json) {
      std::puts(codec::ToJsonLine(event).c_str());
      std::fflush(stdout);
    } else {
      display.Show(event);
    }
    *final_state = event.state();
  }
  display.Finish();
  grpc::Status status = reader->Finish();
  if (!status.ok()) return connection.Fail("watching job " + id, status);
  return kExitOk;
}

// Reports how a job ended (for watch and submit --wait), returns its exit code.
int ReportEnd(Connection& connection, const std::string& id) {
  v1::Job job;
  int code = kExitOk;
  if (!GetJob(connection, id, &job, &code)) return code;
  if (connection.options().json) {
    PrintJson(job);
    return ExitForState(job.state());
  }
  switch (job.state()) {
    case v1::Job::SUCCEEDED:
      std::printf("Job %s succeeded in %s.\n", job.id().c_str(),
                  FormatDuration(job.start_time(), job.end_time()).c_str());
      if (job.has_atlas_import()) {
        // An import's product is in the store, not in files.
        const v1::SnapshotRef& made = job.snapshot();
        std::printf("Imported into %s: snapshot %s (see pba atlas snapshot show -p %s %s)\n",
                    made.project().c_str(), made.snapshot().c_str(), made.project().c_str(),
                    made.snapshot().c_str());
        for (const std::string& note : job.summary().modelled().notes()) {
          std::printf("  %s\n", note.c_str());
        }
        break;
      }
      if (job.has_summary()) std::printf("\n%s", codec::FormatSummary(job.summary()).c_str());
      std::printf("\nFetch the result files with: pba job fetch %s -o DIR\n", job.id().c_str());
      break;
    case v1::Job::FAILED:
      std::fprintf(stderr, "Job %s failed: %s\n", job.id().c_str(), job.error().c_str());
      break;
    case v1::Job::CANCELLED:
      std::fprintf(stderr, "Job %s was cancelled.\n", job.id().c_str());
      break;
    default:
      std::fprintf(stderr, "Job %s is %s.\n", job.id().c_str(), StateName(job.state()).c_str());
  }
  return ExitForState(job.state());
}

// Downloads one result file into dir/name (transfer.h: resumed, checked).
int DownloadFile(Connection& connection, const std::string& id, const v1::ResultFile& file,
                 const fs::path& dir, bool overwrite) {
  return DownloadTo(connection, dir / file.name(), file.size_bytes(), file.sha256(),
                    file.name() + " of job " + id, overwrite,
                    [&](grpc::ClientContext* context, int64_t offset) {
                      v1::DownloadResultRequest request;
                      request.set_job_id(id);
                      request.set_file(file.name());
                      request.set_offset(offset);
                      return connection.jobs().DownloadResult(context, request);
                    });
}

}  // namespace

bool ParseSnapshotRef(const std::string& text, v1::SnapshotRef* ref) {
  const size_t slash = text.find('/');
  if (slash == std::string::npos || slash == 0 || slash + 1 == text.size() ||
      text.find('/', slash + 1) != std::string::npos) {
    std::fprintf(stderr,
                 "pba: --snapshot %s: expected PROJECT/SNAPSHOT (the snapshot's id or tag)\n",
                 text.c_str());
    return false;
  }
  ref->set_project(text.substr(0, slash));
  ref->set_snapshot(text.substr(slash + 1));
  return true;
}

int WaitForJob(Connection& connection, const std::string& id) {
  v1::Job::State state;
  if (int code = Follow(connection, id, &state); code != kExitOk) return code;
  return ReportEnd(connection, id);
}

int SubmitJob(Connection& connection, const SubmitArgs& args) {
  v1::SubmitJobRequest request;
  codec::ParseError error;
  if (!codec::ReadYamlFile(args.file, request.mutable_scene(), &error)) {
    std::fprintf(stderr, "pba: invalid scene: %s\n", error.ToString().c_str());
    return error.unreadable ? kExitError : kExitInvalid;
  }
  if (!args.snapshot.empty() && !ParseSnapshotRef(args.snapshot, request.mutable_snapshot())) {
    return kExitUsage;
  }
  request.set_priority(args.priority);
  request.set_timeout_s(args.timeout_s);
  request.set_ranks(args.ranks);
  request.set_request_id(RequestIdOr(args.request_id));
  v1::Job job;
  auto context = connection.UnaryContext();
  grpc::Status status = connection.jobs().SubmitJob(context.get(), request, &job);
  if (!status.ok()) return connection.Fail("submitting " + args.file, status);
  if (connection.options().json && !args.wait) {
    PrintJson(job);
  } else if (!connection.options().json) {
    std::printf("Submitted job %s (%s)\n", job.id().c_str(), job.name().c_str());
    std::fflush(stdout);
  }
  if (!args.wait) return kExitOk;
  return WaitForJob(connection, job.id());
}

int ListJobs(Connection& connection, const ListArgs& args) {
  v1::ListJobsRequest request;
  request.set_page_size(args.page_size);
  request.set_page_token(args.page_token);
  v1::ListJobsResponse all;
  std::string next;
  do {
    v1::ListJobsResponse page;
    auto context = connection.UnaryContext();
    grpc::Status status = connection.jobs().ListJobs(context.get(), request, &page);
    if (!status.ok()) return connection.Fail("listing jobs", status);
    for (auto& job : *page.mutable_jobs()) *all.add_jobs() = std::move(job);
    next = page.next_page_token();
    request.set_page_token(next);
  } while (args.all && !next.empty());
  all.set_next_page_token(next);

  if (connection.options().json) {
    PrintJson(all);
    return kExitOk;
  }
  if (all.jobs().empty()) {
    std::puts("No jobs.");
    return kExitOk;
  }
  std::vector<std::vector<std::string>> rows = {
      {"ID", "NAME", "STATE", "PROGRESS", "CREATED (UTC)", "RUN TIME"}};
  for (const auto& job : all.jobs()) {
    rows.push_back({job.id(), job.name(), StateName(job.state()),
                    std::to_string(static_cast<int>(job.progress() * 100 + 0.5)) + " %",
                    FormatTime(job.create_time()),
                    FormatDuration(job.start_time(), job.end_time())});
  }
  PrintTable(rows);
  if (!next.empty()) std::printf("More: pba job list --page-token %s\n", next.c_str());
  return kExitOk;
}

int ShowJob(Connection& connection, const std::string& id) {
  v1::Job job;
  int code = kExitOk;
  if (!GetJob(connection, id, &job, &code)) return code;
  if (connection.options().json) {
    PrintJson(job);
  } else {
    PrintJobDetails(job);
  }
  return kExitOk;
}

int WatchJob(Connection& connection, const std::string& id) {
  v1::Job::State state;
  if (int code = Follow(connection, id, &state); code != kExitOk) return code;
  return ReportEnd(connection, id);
}

int CancelJob(Connection& connection, const std::string& id) {
  v1::CancelJobRequest request;
  request.set_id(id);
  v1::Job job;
  auto context = connection.UnaryContext();
  grpc::Status status = connection.jobs().CancelJob(context.get(), request, &job);
  if (!status.ok()) return connection.Fail("cancelling job " + id, status);
  if (connection.options().json) {
    PrintJson(job);
  } else if (IsTerminal(job.state()) && job.state() != v1::Job::CANCELLED) {
    std::printf("Job %s had already ended %s; nothing to cancel.\n", id.c_str(),
                StateName(job.state()).c_str());
  } else if (job.state() == v1::Job::CANCELLED) {
    std::printf("Job %s is cancelled.\n", id.c_str());
  } else {
    std::printf("Cancelling job %s (%s); follow it with: pba job watch %s\n", id.c_str(),
                StateName(job.state()).c_str(), id.c_str());
  }
  return kExitOk;
}

int FetchJob(Connection& connection, const FetchArgs& args) {
  v1::Job job;
  int code = kExitOk;
  if (!GetJob(connection, args.id, &job, &code)) return code;
  if (job.state() != v1::Job::SUCCEEDED) {
    if (job.state() == v1::Job::FAILED) {
      std::fprintf(stderr, "pba: job %s failed, so it has no result: %s\n", args.id.c_str(),
                   job.error().c_str());
    } else if (job.state() == v1::Job::CANCELLED) {
      std::fprintf(stderr, "pba: job %s was cancelled, so it has no result\n", args.id.c_str());
    } else {
      std::fprintf(stderr, "pba: job %s is %s and has no result yet; wait with: pba job watch %s\n",
                   args.id.c_str(), StateName(job.state()).c_str(), args.id.c_str());
    }
    return ExitForState(job.state());
  }
  // The server names the files; every name is checked before anything is
  // written, so a hostile or broken server cannot write outside the
  // directory, nor two files into one.
  std::set<std::string> names;
  for (const auto& file : job.result_files()) {
    if (const std::string why = UnsafeFileNameReason(file.name()); !why.empty()) {
      std::fprintf(stderr,
                   "pba: the server named a result file of job %s %s, which is not a plain file "
                   "name (%s); nothing was written\n",
                   args.id.c_str(), QuotedName(file.name()).c_str(), why.c_str());
      return kExitInvalid;
    }
    if (!names.insert(FoldCase(file.name())).second) {
      std::fprintf(stderr,
                   "pba: the server named two result files of job %s %s (names that differ only "
                   "in case are one file on some systems); nothing was written\n",
                   args.id.c_str(), QuotedName(file.name()).c_str());
      return kExitInvalid;
    }
  }
  const fs::path dir = args.out_dir;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) {
    std::fprintf(stderr, "pba: cannot create %s: %s\n", dir.c_str(), ec.message().c_str());
    return kExitError;
  }
  if (!args.force) {
    // Refused before the first download, not halfway through.
    std::string present;
    for (const auto& file : job.result_files()) {
      if (fs::symlink_status(dir / file.name(), ec).type() != fs::file_type::not_found) {
        present += (present.empty() ? "" : ", ") + file.name();
      }
    }
    if (!present.empty()) {
      std::fprintf(stderr,
                   "pba: %s already holds %s; not overwriting (pass --force to replace them, or "
                   "fetch into another directory)\n",
                   dir.c_str(), present.c_str());
      return kExitConflict;
    }
  }
  for (const auto& file : job.result_files()) {
    if (int result = DownloadFile(connection, args.id, file, dir, args.force); result != kExitOk) {
      return result;
    }
  }
  if (connection.options().json) {
    PrintJson(job);
    return kExitOk;
  }
  std::printf("Downloaded %d file(s) of job %s into %s:", job.result_files_size(), args.id.c_str(),
              dir.c_str());
  for (const auto& file : job.result_files()) std::printf(" %s", file.name().c_str());
  std::printf("\n(the summary is in summary.json, and in `pba job status %s`)\n", args.id.c_str());
  std::printf(
      "\nOpen %s in ParaView (File > Open, pick the XDMF reader) to see the displacement, stress "
      "and von Mises fields.\n",
      (dir / "result.xdmf").c_str());
  return kExitOk;
}

void RegisterJobCommands(CLI::App& app, CommandContext& context) {
  CLI::App* job = AddCommandGroup(app, "job", "Submit, follow, cancel and fetch jobs");

  auto submit = std::make_shared<SubmitArgs>();
  CLI::App* submit_cmd = job->add_subcommand("submit", "Submit a scene file (YAML or JSON)");
  submit_cmd->add_option("file", submit->file, "Scene file")->required()->check(CLI::ExistingFile);
  submit_cmd->add_flag("--wait", submit->wait,
                       "Follow the job until it ends; exit with its outcome");
  submit_cmd->add_option(
      "--request-id", submit->request_id,
      "Idempotency key: a repeated submit with the same key returns the same job");
  submit_cmd->add_option("--snapshot", submit->snapshot,
                         "PROJECT/SNAPSHOT: build the scene's atlas from this snapshot of the "
                         "atlas store (its id or a tag)");
  submit_cmd->add_option("--priority", submit->priority, "Higher runs first (-100..100)")
      ->check(CLI::Range(-100, 100));
  submit_cmd
      ->add_option("--timeout", submit->timeout_s,
                   "Wall-clock limit [s] (at most the server's); 0: the server's")
      ->check(CLI::NonNegativeNumber);
  submit_cmd
      ->add_option("--ranks", submit->ranks,
                   "MPI processes the solve runs on, sharing its linear solves (mpirun on the "
                   "server's machine; at most its --max-ranks); 0 or 1: one")
      ->check(CLI::NonNegativeNumber);
  context.Add(submit_cmd, [submit](Connection& c) { return SubmitJob(c, *submit); });

  auto list = std::make_shared<ListArgs>();
  CLI::App* list_cmd = job->add_subcommand("list", "List jobs, newest first");
  list_cmd->add_option("--page-size", list->page_size, "Jobs per page")->check(CLI::Range(1, 500));
  list_cmd->add_option("--page-token", list->page_token, "Continue from a previous page");
  list_cmd->add_flag("--all", list->all, "Fetch every page");
  context.Add(list_cmd, [list](Connection& c) { return ListJobs(c, *list); });

  // status, watch and cancel: a job id and nothing else.
  const auto add_by_id = [&](const char* name, const char* description,
                             int (*run)(Connection&, const std::string&)) {
    auto id = std::make_shared<std::string>();
    CLI::App* cmd = job->add_subcommand(name, description);
    cmd->add_option("id", *id, "Job id")->required();
    context.Add(cmd, [id, run](Connection& c) { return run(c, *id); });
    return cmd;
  };
  add_by_id("status", "Show one job, with its summary when done (also: show)", ShowJob)
      ->alias("show");
  add_by_id("watch", "Follow a job's progress until it ends", WatchJob);
  add_by_id("cancel", "Cancel a queued or running job", CancelJob);

  auto fetch = std::make_shared<FetchArgs>();
  CLI::App* fetch_cmd = job->add_subcommand("fetch", "Download a finished job's result files");
  fetch_cmd->add_option("id", fetch->id, "Job id")->required();
  fetch_cmd->add_option("-o,--out", fetch->out_dir, "Directory to write into (created)")
      ->required();
  fetch_cmd->add_flag("--force", fetch->force, "Replace files of the same names already there");
  context.Add(fetch_cmd, [fetch](Connection& c) { return FetchJob(c, *fetch); });
}

}  // namespace pba::cli
