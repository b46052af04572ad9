// JobServiceImpl: the pba.v1.JobService handlers. Each one runs through
// Handle (handler.h: authentication, the status mapping, the log line),
// validates its request, translates it into a JobStore / JobExecutor call
// and returns; the work itself happens in the executor's workers.
//
// Every call is authenticated (call_auth.h). Who sees a job (job.proto):
// a job on a project of the atlas store (against one of its snapshots, or
// importing into it) is seen by the project's members, its owner and
// server admins; a job on no project by every user. A job the caller may
// not see is NOT_FOUND in every handler, word for word as an unknown id, so
// that ids cannot be probed; ListJobs filters in the store's query, so its
// pages stay full. A job's owner or a server admin may cancel it. Rights
// are read from the store on every call (a member removed, or a user
// disabled, loses access at their next call; a WatchJob stream re-checks
// every kWatchRecheck).
//
// A submit carries a scene, optionally against a snapshot of the atlas
// store (viewer role on its project), or an atlas import (editor role; its
// uploads are taken into the job's folder at once, so they cannot expire
// while it waits in the queue). See atlas_jobs.h for how they run.
//
// WatchJob sends the stored events after `after_sequence`, then events as they
// are published (including live progress that is not stored: see
// job_event_hub.h for how sequences work), and ends after the event that makes
// the job terminal. It wakes at least every kWatchPoll to notice a cancelled
// call or a server shutting down (then it ends with UNAVAILABLE).
#pragma once

#include <chrono>
#include <filesystem>
#include <string>

#include "jobs/job_event_hub.h"
#include "jobs/job_executor.h"
#include "pba/v1/job.grpc.pb.h"
#include "service/call_auth.h"
#include "service/stream_slots.h"
#include "store/atlas_store.h"
#include "store/job_store.h"
#include "store/upload_store.h"

namespace pba {

class JobServiceImpl final : public v1::JobService::Service {
 public:
  static constexpr std::chrono::milliseconds kWatchPoll{250};
  // How often an open WatchJob stream checks again that its caller is still
  // enabled and may still see the job.
  static constexpr std::chrono::milliseconds kWatchRecheck{2000};
  // WatchJob streams one user may hold open at once (stream_slots.h).
  static constexpr int kMaxWatchesPerUser = 64;
  static constexpr size_t kChunkBytes = 1 << 20;
  static constexpr char kDefaultResultFile[] = "result.h5";

  // `users` authenticates every call (call_auth.h).
  // Priorities a submit may ask for.
  static constexpr int kMaxPriority = 100;

  JobServiceImpl(JobStore& store, Executor& executor, JobEventHub& hub, AtlasStore& users,
                 UploadStore& uploads, std::filesystem::path jobs_dir);

  // What GetServerInfo answers, and the bounds a submit meets: the most
  // MPI ranks a job may ask for (max_ranks, pba-server --max-ranks; 1, the
  // default, runs every job as one process) and the most jobs one user may
  // have queued or running (max_open_jobs; 0: no bound).
  void set_info(const v1::ServerInfo& info) { info_ = info; }

  grpc::Status SubmitJob(grpc::ServerContext* context, const v1::SubmitJobRequest* request,
                         v1::Job* response) override;
  grpc::Status GetJob(grpc::ServerContext* context, const v1::GetJobRequest* request,
                      v1::Job* response) override;
  grpc::Status ListJobs(grpc::ServerContext* context, const v1::ListJobsRequest* request,
                        v1::ListJobsResponse* response) override;
  grpc::Status CancelJob(grpc::ServerContext* context, const v1::CancelJobRequest* request,
                         v1::Job* response) override;
  grpc::Status WatchJob(grpc::ServerContext* context, const v1::WatchJobRequest* request,
                        grpc::ServerWriter<v1::JobEvent>* writer) override;
  grpc::Status DownloadResult(grpc::ServerContext* context,
                              const v1::DownloadResultRequest* request,
                              grpc::ServerWriter<v1::DataChunk>* writer) override;
  grpc::Status GetServerInfo(grpc::ServerContext* context, const v1::GetServerInfoRequest* request,
                             v1::ServerInfo* response) override;

 private:
  v1::ServerInfo info_ = [] {
    v1::ServerInfo info;
    info.set_executor("local");
    info.set_max_ranks(1);
    return info;
  }();
  // Replaces the stored phase/progress of a running job by the live one.
  void OverlayLive(v1::Job* job) const;
  // Whether `caller` may see `job` (loaded with at least JobView::kBasic).
  Status MaySee(const Caller& caller, const v1::Job& job, bool* visible);
  // Loads job `id` if `caller` may see it; kNotFound otherwise, the same
  // for a job that does not exist (a hidden one is logged for `rpc`).
  Status LoadVisibleJob(const char* rpc, const Caller& caller, const std::string& id, JobView view,
                        v1::Job* job);

  // The submit's checks beyond the scene: snapshot, import, priority, time
  // limit; *job gets what they resolve to.
  Status CheckSubmit(const std::string& user, const v1::SubmitJobRequest& request, NewJob* job);

  JobStore& store_;
  Executor& executor_;
  JobEventHub& hub_;
  AtlasStore& users_;
  UploadStore& uploads_;
  const std::filesystem::path jobs_dir_;  // the job folders, jobs_dir_/<id>/
  StreamSlots watch_slots_{kMaxWatchesPerUser};
};

}  // namespace pba
