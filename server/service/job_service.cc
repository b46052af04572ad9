#include "service/job_service.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <system_error>
#include <vector>

#include "convert/convert.h"
#include "core/atomic_write.h"
#include "service/atlas_jobs.h"
#include "service/handler.h"
#include "store/job_id.h"

namespace pba {
namespace fs = std::filesystem;
namespace {

// request_id is a client key (a UUID is 36 characters); bound it so the
// UNIQUE index stays small.
constexpr size_t kMaxRequestIdLength = 200;

bool IsTerminal(v1::Job::State state) {
  return state == v1::Job::SUCCEEDED || state == v1::Job::FAILED || state == v1::Job::CANCELLED;
}

// The same words for a job that does not exist and one the caller may not
// see, so that ids cannot be probed.
Status JobNotFound(const std::string& id) { return Status::NotFound("job " + id + " not found"); }

}  // namespace

JobServiceImpl::JobServiceImpl(JobStore& store, Executor& executor, JobEventHub& hub,
                               AtlasStore& users, UploadStore& uploads, fs::path jobs_dir)
    : store_(store),
      executor_(executor),
      hub_(hub),
      users_(users),
      uploads_(uploads),
      jobs_dir_(std::move(jobs_dir)) {}

Status JobServiceImpl::CheckSubmit(const std::string& user, const v1::SubmitJobRequest& request,
                                   NewJob* job) {
  if (request.priority() < -kMaxPriority || request.priority() > kMaxPriority) {
    return Status::InvalidArgument("priority", "must be within -100..100");
  }
  if (request.timeout_s() < 0) {
    return Status::InvalidArgument("timeout_s", "must not be negative");
  }
  const int max_ranks = std::max(1, info_.max_ranks());
  if (request.ranks() < 0 || request.ranks() > max_ranks) {
    return Status::InvalidArgument("ranks", "must be within 0.." + std::to_string(max_ranks) +
                                                " on this server (pba-server --max-ranks), got " +
                                                std::to_string(request.ranks()));
  }
  job->owner = user;
  job->max_open = info_.max_open_jobs();
  job->request_id = request.request_id();
  job->priority = request.priority();
  job->timeout_s = request.timeout_s();
  job->ranks = request.ranks();
  if (request.has_atlas_import()) {
    if (request.ranks() > 1) {
      return Status::InvalidArgument("ranks", "an import runs as one process");
    }
    if (request.has_scene() || request.has_snapshot()) {
      return Status::InvalidArgument("atlas_import",
                                     "an import is a job of its own: send no scene or snapshot");
    }
    PBA_RETURN_IF_ERROR(CheckAtlasImport(request.atlas_import()));
    Role role = Role::kViewer;
    bool member = false;
    PBA_RETURN_IF_ERROR(users_.RoleOf(request.atlas_import().project(), user, &role, &member));
    if (!member || role < Role::kEditor) {
      return Status::PermissionDenied("importing into project '" +
                                      request.atlas_import().project() + "' needs the editor role");
    }
    job->atlas_import = &request.atlas_import();
    return Status::Ok();
  }
  if (!request.has_scene()) return Status::InvalidArgument("scene", "required");
  const int ranks = std::max(1, request.ranks());
  if (!request.has_snapshot()) {
    PBA_RETURN_IF_ERROR(ValidateSceneProto(request.scene(), ranks));
    job->scene = request.scene();
    // A job's atlas is one a result can be reproduced from: the built-in one
    // (versioned with the software) or a snapshot, never a file on the
    // server that may change or vanish.
    const std::string& source = request.scene().geometry().atlas().source();
    if (request.scene().geometry().has_atlas() && !source.empty() && source != "synthetic") {
      return Status::InvalidArgument(
          "scene.geometry.atlas.source",
          "names a file on the server; a job's atlas is the built-in one (\"synthetic\") or a "
          "snapshot of the atlas store: import it (pba atlas import) and submit with --snapshot");
    }
    return Status::Ok();
  }
  const v1::SnapshotRef& ref = request.snapshot();
  if (!request.scene().geometry().has_atlas()) {
    return Status::InvalidArgument("snapshot",
                                   "only an atlas scene (geometry.atlas) is built from a snapshot");
  }
  const std::string& source = request.scene().geometry().atlas().source();
  if (!source.empty()) {
    return Status::InvalidArgument("scene.geometry.atlas.source",
                                   "a job against a snapshot is built from the snapshot's "
                                   "structures: leave the source empty");
  }
  if (ref.project().empty()) return Status::InvalidArgument("snapshot.project", "required");
  if (ref.snapshot().empty()) return Status::InvalidArgument("snapshot.snapshot", "required");
  SnapshotInfo snapshot;
  PBA_RETURN_IF_ERROR(users_.ResolveSnapshot(user, ref.project(), ref.snapshot(), &snapshot));
  if (snapshot.revisions.empty()) {
    return Status::FailedPrecondition("snapshot " + ref.snapshot() + " of project '" +
                                      ref.project() + "' has no structures");
  }
  // The scene names the snapshot's structures, not the synthetic atlas's
  // (the rights to the snapshot checked first, by ResolveSnapshot).
  std::vector<std::string> names;
  for (const auto& [name, revision] : snapshot.revisions) names.push_back(name);
  PBA_RETURN_IF_ERROR(ValidateSceneProto(request.scene(), ranks, names));
  job->scene = request.scene();
  job->snapshot.set_project(ref.project());
  job->snapshot.set_snapshot(std::to_string(snapshot.id));
  return Status::Ok();
}

Status JobServiceImpl::MaySee(const Caller& caller, const v1::Job& job, bool* visible) {
  *visible = true;
  if (caller.server_admin || job.owner() == caller.user) return Status::Ok();
  // The project a job belongs to: its snapshot's, or the one it imports into.
  const std::string& project =
      !job.snapshot().project().empty() ? job.snapshot().project() : job.atlas_import().project();
  if (project.empty()) return Status::Ok();
  Role role = Role::kViewer;
  bool member = false;
  const Status status = users_.RoleOf(project, caller.user, &role, &member);
  // Projects are never deleted; a job naming none that exists is no one's.
  if (status.code() == Status::Code::kNotFound) {
    *visible = false;
    return Status::Ok();
  }
  PBA_RETURN_IF_ERROR(status);
  *visible = member;
  return Status::Ok();
}

Status JobServiceImpl::LoadVisibleJob(const char* rpc, const Caller& caller, const std::string& id,
                                      JobView view, v1::Job* job) {
  bool found = false;
  PBA_RETURN_IF_ERROR(store_.GetJob(id, view, job, &found));
  if (!found) return JobNotFound(id);
  bool visible = false;
  PBA_RETURN_IF_ERROR(MaySee(caller, *job, &visible));
  if (!visible) {
    // Logged as any NOT_FOUND, with who asked, for the operator only.
    spdlog::info("{}: job {} is hidden from {}", rpc, id, caller.user);
    return JobNotFound(id);
  }
  return Status::Ok();
}

void JobServiceImpl::OverlayLive(v1::Job* job) const {
  if (job->state() != v1::Job::RUNNING) return;
  std::string phase;
  double progress = 0;
  if (hub_.Live(job->id(), &phase, &progress)) {
    job->set_phase(phase);
    job->set_progress(progress);
  }
}

grpc::Status JobServiceImpl::SubmitJob(grpc::ServerContext* context,
                                       const v1::SubmitJobRequest* request, v1::Job* response) {
  return Handle(users_, "SubmitJob", *context, [&](const Caller& caller) -> RpcStatus {
    const std::string& user = caller.user;
    if (request->request_id().size() > kMaxRequestIdLength) {
      return Status::InvalidArgument(
          "request_id", "at most " + std::to_string(kMaxRequestIdLength) + " characters");
    }
    NewJob job;
    PBA_RETURN_IF_ERROR(CheckSubmit(user, *request, &job));

    // A repeated import returns its job before its uploads (taken the first
    // time) are looked for.
    if (job.atlas_import != nullptr && !job.request_id.empty()) {
      bool found = false;
      PBA_RETURN_IF_ERROR(store_.FindByRequestId(job.request_id, user, response, &found));
      if (found) {
        OverlayLive(response);
        return Status::Ok();
      }
    }
    // An import's files are taken in before the job exists (a staging
    // directory renamed to the job's once it has an id): a job that is
    // queued always has its source.
    fs::path staged;
    if (job.atlas_import != nullptr) {
      staged = jobs_dir_ / (".import-" + NewJobId());
      PBA_RETURN_IF_ERROR(StageImportSource(uploads_, user, *job.atlas_import, staged));
    }
    if (!staged.empty()) {
      job.before_commit = [&](const std::string& id) {
        std::error_code ec;
        const fs::path dir = jobs_dir_ / id;
        fs::create_directories(dir, ec);
        if (!ec) fs::rename(staged, dir / "source", ec);
        if (ec) return Status::Io("cannot move the import's files into place: " + ec.message());
        // Durable before the job is stored (the source's entries are).
        SyncDirectory(dir);
        SyncDirectory(dir.parent_path());
        return Status::Ok();
      };
    }
    bool created = false;
    const Status stored = store_.CreateJob(job, response, &created);
    if (!staged.empty()) {
      std::error_code ec;
      fs::remove_all(staged, ec);  // left only when the submit failed or was a repeat
    }
    PBA_RETURN_IF_ERROR(stored);
    if (created && job.atlas_import != nullptr) {
      RemoveImportUploads(uploads_, user, *job.atlas_import);
    }
    if (created) {
      spdlog::info("job {} QUEUED: {} submitted by {}", response->id(), response->name(), user);
      v1::JobEvent queued;
      queued.set_job_id(response->id());
      queued.set_sequence(1);
      *queued.mutable_time() = response->create_time();
      queued.set_state(v1::Job::QUEUED);
      queued.set_message("queued");
      hub_.Publish(queued);
      executor_.Wake();
    }
    OverlayLive(response);
    return Status::Ok();
  });
}

grpc::Status JobServiceImpl::GetJob(grpc::ServerContext* context, const v1::GetJobRequest* request,
                                    v1::Job* response) {
  constexpr char kRpc[] = "GetJob";
  return Handle(users_, kRpc, *context, [&](const Caller& caller) -> RpcStatus {
    if (request->id().empty()) return Status::InvalidArgument("id", "required");
    PBA_RETURN_IF_ERROR(LoadVisibleJob(kRpc, caller, request->id(), JobView::kFull, response));
    OverlayLive(response);
    return Status::Ok();
  });
}

grpc::Status JobServiceImpl::ListJobs(grpc::ServerContext* context,
                                      const v1::ListJobsRequest* request,
                                      v1::ListJobsResponse* response) {
  return Handle(users_, "ListJobs", *context, [&](const Caller& caller) -> RpcStatus {
    std::vector<v1::Job> jobs;
    std::string next_page_token;
    JobReader reader;
    reader.user = caller.user;
    reader.all = caller.server_admin;
    PBA_RETURN_IF_ERROR(store_.ListJobs(reader, request->page_size(), request->page_token(), &jobs,
                                        &next_page_token));
    for (v1::Job& job : jobs) {
      OverlayLive(&job);
      *response->add_jobs() = std::move(job);
    }
    response->set_next_page_token(next_page_token);
    return Status::Ok();
  });
}

grpc::Status JobServiceImpl::CancelJob(grpc::ServerContext* context,
                                       const v1::CancelJobRequest* request, v1::Job* response) {
  constexpr char kRpc[] = "CancelJob";
  return Handle(users_, kRpc, *context, [&](const Caller& caller) -> RpcStatus {
    if (request->id().empty()) return Status::InvalidArgument("id", "required");
    {
      // The owner or a server admin cancels (jobs stored before owners were
      // kept have none: anyone who sees them may).
      v1::Job job;
      PBA_RETURN_IF_ERROR(LoadVisibleJob(kRpc, caller, request->id(), JobView::kBasic, &job));
      if (!caller.server_admin && !job.owner().empty() && job.owner() != caller.user) {
        return Status::PermissionDenied("job " + request->id() + " was submitted by " +
                                        job.owner() +
                                        "; only they or a server admin can cancel it");
      }
    }
    bool found = false;
    PBA_RETURN_IF_ERROR(executor_.Cancel(request->id(), response, &found));
    if (!found) return JobNotFound(request->id());
    OverlayLive(response);
    return Status::Ok();
  });
}

grpc::Status JobServiceImpl::WatchJob(grpc::ServerContext* context,
                                      const v1::WatchJobRequest* request,
                                      grpc::ServerWriter<v1::JobEvent>* writer) {
  constexpr char kRpc[] = "WatchJob";
  return Handle(users_, kRpc, *context, [&](const Caller& caller) -> RpcStatus {
    const std::string& id = request->id();
    if (id.empty()) return Status::InvalidArgument("id", "required");
    if (request->after_sequence() < 0) {
      return Status::InvalidArgument("after_sequence", "must not be negative");
    }
    v1::Job job;
    PBA_RETURN_IF_ERROR(LoadVisibleJob(kRpc, caller, id, JobView::kBasic, &job));
    const StreamSlots::Ticket slot = watch_slots_.TryAcquire(caller.user);
    if (!slot.held()) {
      return Status::ResourceExhausted("", "user '" + caller.user + "' already has " +
                                               std::to_string(kMaxWatchesPerUser) +
                                               " WatchJob streams open; close one first");
    }
    auto checked = std::chrono::steady_clock::now();
    // All events of a job that was already terminal are stored: once those
    // are sent there is nothing left to wait for, even if the terminal one
    // was before after_sequence.
    const bool terminal_at_start = IsTerminal(job.state());

    int64_t last = request->after_sequence();
    while (true) {
      if (context->IsCancelled()) {
        return RpcStatus::StreamEnded(grpc::StatusCode::CANCELLED, "watch cancelled");
      }
      if (hub_.shutting_down()) {
        return RpcStatus::StreamEnded(grpc::StatusCode::UNAVAILABLE, "the server is shutting down");
      }
      if (std::chrono::steady_clock::now() - checked >= kWatchRecheck) {
        // A long watch must not outlive the caller's rights: a user disabled
        // or a member removed since the stream opened loses it.
        checked = std::chrono::steady_clock::now();
        Caller again;
        PBA_RETURN_IF_ERROR(CallUser(users_, *context, &again));
        PBA_RETURN_IF_ERROR(LoadVisibleJob(kRpc, again, id, JobView::kBasic, &job));
      }
      const uint64_t version = hub_.version();
      std::vector<v1::JobEvent> stored;
      PBA_RETURN_IF_ERROR(store_.ListEvents(id, last, &stored));
      // Stored and live events overlap; the sequence number identifies an event.
      std::map<int64_t, v1::JobEvent> pending;
      for (v1::JobEvent& event : hub_.Recent(id, last))
        pending[event.sequence()] = std::move(event);
      for (v1::JobEvent& event : stored) pending[event.sequence()] = std::move(event);
      for (const auto& [sequence, event] : pending) {
        if (!writer->Write(event)) {
          return RpcStatus::StreamEnded(grpc::StatusCode::CANCELLED, "the client went away");
        }
        last = sequence;
        if (IsTerminal(event.state())) return Status::Ok();
      }
      if (terminal_at_start) return Status::Ok();
      hub_.WaitForChange(version, kWatchPoll);
    }
  });
}

grpc::Status JobServiceImpl::DownloadResult(grpc::ServerContext* context,
                                            const v1::DownloadResultRequest* request,
                                            grpc::ServerWriter<v1::DataChunk>* writer) {
  constexpr char kRpc[] = "DownloadResult";
  return Handle(users_, kRpc, *context, [&](const Caller& caller) -> RpcStatus {
    const std::string& id = request->job_id();
    if (id.empty()) return Status::InvalidArgument("job_id", "required");
    if (request->offset() < 0) return Status::InvalidArgument("offset", "must not be negative");
    // The id becomes part of a path below; only ids we could have made pass.
    if (!IsWellFormedJobId(id)) return JobNotFound(id);
    v1::Job job;
    PBA_RETURN_IF_ERROR(LoadVisibleJob(kRpc, caller, id, JobView::kBasic, &job));
    if (job.state() != v1::Job::SUCCEEDED) {
      std::string message =
          "job " + id + " is " + v1::Job::State_Name(job.state()) + ", not SUCCEEDED";
      if (!job.error().empty()) message += ": " + job.error();
      return Status::FailedPrecondition(message);
    }
    const std::string name = request->file().empty() ? kDefaultResultFile : request->file();
    // Only names recorded in result_files are served; those come from a
    // directory listing, so they are plain file names, never paths.
    v1::ResultFile file;
    bool found = false;
    PBA_RETURN_IF_ERROR(store_.GetResultFile(id, name, &file, &found));
    if (!found || name.find('/') != std::string::npos || name == "." || name == "..") {
      return Status::NotFound("job " + id + " has no result file " + name);
    }
    const int64_t size = file.size_bytes();
    if (request->offset() > size) {
      return Status::OutOfRange("offset", std::to_string(request->offset()) +
                                              " is past the end of " + name + " (" +
                                              std::to_string(size) + " bytes)");
    }
    const fs::path path = jobs_dir_ / id / "result" / name;
    std::error_code ec;
    const auto disk_size = fs::file_size(path, ec);
    if (ec || static_cast<int64_t>(disk_size) != size) {
      return grpc::Status(
          grpc::StatusCode::DATA_LOSS,
          "result file " + path.string() + " is missing or changed since the job ended");
    }
    std::ifstream in(path, std::ios::binary);
    if (!in || !in.seekg(request->offset()))
      return Status::Internal("cannot read " + path.string());

    int64_t offset = request->offset();
    v1::DataChunk chunk;
    chunk.set_total_size(size);
    std::string buffer(kChunkBytes, '\0');
    // One chunk even at the end of the file, so the client learns total_size.
    do {
      if (context->IsCancelled()) {
        return RpcStatus::StreamEnded(grpc::StatusCode::CANCELLED, "cancelled");
      }
      const int64_t want = std::min<int64_t>(kChunkBytes, size - offset);
      in.read(buffer.data(), want);
      if (in.gcount() != want) return Status::Internal("cannot read " + path.string());
      chunk.set_offset(offset);
      chunk.set_data(buffer.data(), static_cast<size_t>(want));
      if (!writer->Write(chunk)) {
        return RpcStatus::StreamEnded(grpc::StatusCode::CANCELLED, "the client went away");
      }
      offset += want;
    } while (offset < size);
    return Status::Ok();
  });
}

grpc::Status JobServiceImpl::GetServerInfo(grpc::ServerContext* context,
                                           const v1::GetServerInfoRequest* /*request*/,
                                           v1::ServerInfo* response) {
  return Handle(users_, "GetServerInfo", *context, [&](const Caller&) -> RpcStatus {
    *response = info_;
    return Status::Ok();
  });
}

}  // namespace pba
