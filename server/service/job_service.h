// JobServiceImpl: the pba.v1.JobService handlers. Each one validates its
// request, translates it into a JobStore / JobExecutor call and returns; the
// work itself happens in the executor's workers.
//
// Every call is authenticated (call_auth.h); every user sees every job, and
// only a job's owner (the user who submitted it) may cancel it.
//
// WatchJob sends the stored events after `after_sequence`, then events as they
// are published (including live progress that is not stored: see
// job_event_hub.h for how sequences work), and ends after the event that makes
// the job terminal. It wakes at least every kWatchPoll to notice a cancelled
// call or a server shutting down (then it ends with UNAVAILABLE).
#pragma once

#include <chrono>
#include <filesystem>

#include "jobs/job_event_hub.h"
#include "jobs/job_executor.h"
#include "pba/v1/job.grpc.pb.h"
#include "store/atlas_store.h"
#include "store/job_store.h"

namespace pba {

class JobServiceImpl final : public v1::JobService::Service {
 public:
  static constexpr std::chrono::milliseconds kWatchPoll{250};
  static constexpr size_t kChunkBytes = 1 << 20;
  static constexpr char kDefaultResultFile[] = "result.h5";

  // `users` authenticates every call (call_auth.h).
  JobServiceImpl(JobStore& store, JobExecutor& executor, JobEventHub& hub, AtlasStore& users,
                 std::filesystem::path data_dir);

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

 private:
  // Replaces the stored phase/progress of a running job by the live one.
  void OverlayLive(v1::Job* job) const;
  // The caller, or UNAUTHENTICATED (logged).
  grpc::Status Authenticate(const char* rpc, const grpc::ServerContext& context, std::string* user);

  JobStore& store_;
  JobExecutor& executor_;
  JobEventHub& hub_;
  AtlasStore& users_;
  const std::filesystem::path data_dir_;
};

}  // namespace pba
