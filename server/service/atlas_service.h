// AtlasServiceImpl: the pba.v1.AtlasService handlers over AtlasStore (the
// repository), UploadStore (resumable uploads) and AtlasEventHub (Watch).
// Each handler runs through Handle (handler.h), which authenticates the
// caller and maps and logs the outcome; the handler validates and
// translates the request and calls the store. Rights, locks and etags are
// the store's (atlas_store.h).
//
// Authentication: every call carries the metadata
// `authorization: Bearer <token>`; a missing, malformed or unknown token is
// UNAUTHENTICATED and the token is never echoed or logged.
//
// Events: every change that succeeds publishes one AtlasEvent for its
// project. Changes and their publication happen under one mutex, so watchers
// see events in the order the store applied them (the store serialises its
// writes anyway, so this costs no concurrency the store had). An open Watch
// re-checks its caller every kWatchRecheck: a user disabled since it opened
// ends it UNAUTHENTICATED, a member removed PERMISSION_DENIED.
//
// Uploads are consumed by CreateStructure and CommitStructure: the complete
// upload file is mapped read-only (never copied onto the heap), checked
// (size, SHA-256, then the format's minimal check of geometry_check.h), and
// moved into the blob store as the new revision's blob (renamed to its
// content-addressed name, BlobStore::PutFile); then the rest of the upload
// is removed. A create or commit refused before the blob is stored (a
// failing check, stale base, lock, rights) keeps the upload whole, so the
// client can retry with it. One that fails after (a database error) has
// consumed it: begin again. A replayed create or commit (same request_id)
// needs no upload: one named is removed unused. The caller's role in the
// project is checked before an upload is read or parsed.
#pragma once

#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>
#include <string>

#include "pba/v1/atlas.grpc.pb.h"
#include "service/atlas_event_hub.h"
#include "service/diff_slots.h"
#include "service/stream_slots.h"
#include "store/atlas_store.h"
#include "store/upload_store.h"

namespace pba {

class SurfaceViews;

class AtlasServiceImpl final : public v1::AtlasService::Service {
 public:
  static constexpr std::chrono::milliseconds kWatchPoll{250};
  // How often an open Watch stream checks again that its caller is still
  // enabled and still a member of the project (as WatchJob does).
  static constexpr std::chrono::milliseconds kWatchRecheck{2000};
  // Watch streams one user may hold open at once (stream_slots.h).
  static constexpr int kMaxWatchesPerUser = 64;
  static constexpr size_t kChunkBytes = 1 << 20;
  static constexpr int64_t kDefaultLeaseSeconds = 300;
  static constexpr int64_t kMaxLeaseSeconds = 3600;

  // Shape comparisons (DiffRevisions) run at once; more wait their turn
  // up to kDiffPatience, then are RESOURCE_EXHAUSTED.
  static constexpr int kMaxConcurrentDiffs = 2;
  static constexpr std::chrono::milliseconds kDiffPatience{30000};

  AtlasServiceImpl(AtlasStore& store, UploadStore& uploads, AtlasEventHub& hub);

  // The server is stopping: waiting and not yet started shape comparisons
  // give up (UNAVAILABLE), so that shutdown waits for none but those
  // already voxelising (seconds, by the voxel budget). Called before the
  // gRPC server's Shutdown().
  void Stop() { stopping_.store(true); }

  // What DownloadSurfaces builds and caches the surfaces with (owned by
  // the caller, outliving the service); without it, DownloadSurfaces is
  // UNIMPLEMENTED.
  void set_surface_views(SurfaceViews* views) { surface_views_ = views; }

  grpc::Status WhoAmI(grpc::ServerContext* context, const v1::WhoAmIRequest* request,
                      v1::User* response) override;
  grpc::Status CreateProject(grpc::ServerContext* context, const v1::CreateProjectRequest* request,
                             v1::Project* response) override;
  grpc::Status ListProjects(grpc::ServerContext* context, const v1::ListProjectsRequest* request,
                            v1::ListProjectsResponse* response) override;
  grpc::Status SetRole(grpc::ServerContext* context, const v1::SetRoleRequest* request,
                       v1::Member* response) override;
  grpc::Status RemoveMember(grpc::ServerContext* context, const v1::RemoveMemberRequest* request,
                            v1::RemoveMemberResponse* response) override;

  grpc::Status BeginUpload(grpc::ServerContext* context, const v1::BeginUploadRequest* request,
                           v1::Upload* response) override;
  grpc::Status WriteUpload(grpc::ServerContext* context,
                           grpc::ServerReader<v1::UploadChunk>* reader,
                           v1::Upload* response) override;
  grpc::Status GetUpload(grpc::ServerContext* context, const v1::GetUploadRequest* request,
                         v1::Upload* response) override;
  grpc::Status DiscardUpload(grpc::ServerContext* context, const v1::DiscardUploadRequest* request,
                             v1::DiscardUploadResponse* response) override;

  grpc::Status CreateStructure(grpc::ServerContext* context,
                               const v1::CreateStructureRequest* request,
                               v1::Revision* response) override;
  grpc::Status GetStructure(grpc::ServerContext* context, const v1::GetStructureRequest* request,
                            v1::Structure* response) override;
  grpc::Status ListStructures(grpc::ServerContext* context,
                              const v1::ListStructuresRequest* request,
                              v1::ListStructuresResponse* response) override;

  grpc::Status AcquireLock(grpc::ServerContext* context, const v1::AcquireLockRequest* request,
                           v1::Lock* response) override;
  grpc::Status RenewLock(grpc::ServerContext* context, const v1::RenewLockRequest* request,
                         v1::Lock* response) override;
  grpc::Status ReleaseLock(grpc::ServerContext* context, const v1::ReleaseLockRequest* request,
                           v1::ReleaseLockResponse* response) override;
  grpc::Status BreakLock(grpc::ServerContext* context, const v1::BreakLockRequest* request,
                         v1::BreakLockResponse* response) override;

  grpc::Status CommitStructure(grpc::ServerContext* context,
                               const v1::CommitStructureRequest* request,
                               v1::Revision* response) override;
  grpc::Status UpdateMetadata(grpc::ServerContext* context,
                              const v1::UpdateMetadataRequest* request,
                              v1::UpdateMetadataResponse* response) override;
  grpc::Status RevertStructure(grpc::ServerContext* context,
                               const v1::RevertStructureRequest* request,
                               v1::Revision* response) override;
  grpc::Status ListRevisions(grpc::ServerContext* context, const v1::ListRevisionsRequest* request,
                             v1::ListRevisionsResponse* response) override;
  grpc::Status GetRevision(grpc::ServerContext* context, const v1::GetRevisionRequest* request,
                           v1::Revision* response) override;
  grpc::Status DownloadGeometry(grpc::ServerContext* context,
                                const v1::DownloadGeometryRequest* request,
                                grpc::ServerWriter<v1::DataChunk>* writer) override;
  grpc::Status DiffRevisions(grpc::ServerContext* context, const v1::DiffRevisionsRequest* request,
                             v1::RevisionDiff* response) override;
  grpc::Status DownloadSurfaces(grpc::ServerContext* context,
                                const v1::DownloadSurfacesRequest* request,
                                grpc::ServerWriter<v1::DataChunk>* writer) override;

  grpc::Status CreateSnapshot(grpc::ServerContext* context,
                              const v1::CreateSnapshotRequest* request,
                              v1::Snapshot* response) override;
  grpc::Status TagSnapshot(grpc::ServerContext* context, const v1::TagSnapshotRequest* request,
                           v1::Snapshot* response) override;
  grpc::Status GetSnapshot(grpc::ServerContext* context, const v1::GetSnapshotRequest* request,
                           v1::Snapshot* response) override;
  grpc::Status ListSnapshots(grpc::ServerContext* context, const v1::ListSnapshotsRequest* request,
                             v1::ListSnapshotsResponse* response) override;

  grpc::Status ListAudit(grpc::ServerContext* context, const v1::ListAuditRequest* request,
                         v1::ListAuditResponse* response) override;

  grpc::Status Watch(grpc::ServerContext* context, const v1::WatchRequest* request,
                     grpc::ServerWriter<v1::AtlasEvent>* writer) override;

 private:
  // Whether `user` may watch `project` (a member of it): checked when a
  // Watch opens and every kWatchRecheck while it is open.
  Status MayWatch(const std::string& project, const std::string& user);
  // The verified, format-checked content of `user`'s complete upload.
  Status TakeUpload(const std::string& user, const std::string& upload_id, StructureFormat format,
                    std::unique_ptr<MappedFile>* content);
  // Removes an upload a create or commit has consumed (or found consumed by
  // the call it replays); a failure is only logged: the upload lapses.
  void ForgetUpload(const char* rpc, const std::string& user, const std::string& upload_id);
  void Publish(v1::AtlasEvent::Kind kind, const std::string& project, const std::string& structure,
               int64_t revision, int64_t snapshot, const std::string& user,
               const std::string& detail);

  AtlasStore& store_;
  UploadStore& uploads_;
  AtlasEventHub& hub_;
  // Held from a change in the store until its event is published.
  std::mutex change_mutex_;
  std::atomic<bool> stopping_{false};
  DiffSlots diff_slots_{kMaxConcurrentDiffs};
  SurfaceViews* surface_views_ = nullptr;
  StreamSlots watch_slots_{kMaxWatchesPerUser};
};

}  // namespace pba
