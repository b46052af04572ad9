#include "service/atlas_service.h"

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <map>
#include <string_view>
#include <vector>

#include "service/atlas_messages.h"
#include "service/derived_check.h"
#include "service/geometry_check.h"
#include "service/geometry_diff.h"
#include "service/handler.h"
#include "service/overlap_check.h"
#include "service/surface_views.h"
#include "store/page_token.h"

namespace pba {
namespace {

int64_t NowMicros() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

Status LeaseMicros(int64_t lease_seconds, int64_t* micros) {
  if (lease_seconds == 0) lease_seconds = AtlasServiceImpl::kDefaultLeaseSeconds;
  if (lease_seconds < 1 || lease_seconds > AtlasServiceImpl::kMaxLeaseSeconds) {
    return Status::InvalidArgument(
        "lease_seconds", "must be 1 to " + std::to_string(AtlasServiceImpl::kMaxLeaseSeconds) +
                             " (0: " + std::to_string(AtlasServiceImpl::kDefaultLeaseSeconds) +
                             "), not " + std::to_string(lease_seconds));
  }
  *micros = lease_seconds * 1000 * 1000;
  return Status::Ok();
}

}  // namespace

AtlasServiceImpl::AtlasServiceImpl(AtlasStore& store, UploadStore& uploads, AtlasEventHub& hub)
    : store_(store), uploads_(uploads), hub_(hub) {}

void AtlasServiceImpl::Publish(v1::AtlasEvent::Kind kind, const std::string& project,
                               const std::string& structure, int64_t revision, int64_t snapshot,
                               const std::string& user, const std::string& detail) {
  v1::AtlasEvent event;
  event.set_kind(kind);
  event.set_project(project);
  event.set_structure(structure);
  event.set_revision(revision);
  event.set_snapshot(snapshot);
  event.set_user(user);
  SetTime(NowMicros(), event.mutable_time());
  event.set_detail(detail);
  hub_.Publish(event);
}

void AtlasServiceImpl::ForgetUpload(const char* rpc, const std::string& user,
                                    const std::string& upload_id) {
  if (upload_id.empty()) return;
  const Status removed = uploads_.Remove(user, upload_id);
  if (!removed.ok()) spdlog::warn("{}: {}", rpc, removed.ToString());
}

Status AtlasServiceImpl::TakeUpload(const std::string& user, const std::string& upload_id,
                                    StructureFormat format, std::unique_ptr<MappedFile>* content) {
  if (upload_id.empty()) return Status::InvalidArgument("upload_id", "required");
  PBA_RETURN_IF_ERROR(uploads_.Take(user, upload_id, content));
  return CheckGeometryContent("upload_id", format, (*content)->bytes());
}

// --- users and projects ----------------------------------------------------

grpc::Status AtlasServiceImpl::WhoAmI(grpc::ServerContext* context, const v1::WhoAmIRequest*,
                                      v1::User* response) {
  return Handle(store_, "WhoAmI", *context, [&](const Caller& caller) -> RpcStatus {
    response->set_name(caller.user);
    return Status::Ok();
  });
}

grpc::Status AtlasServiceImpl::CreateProject(grpc::ServerContext* context,
                                             const v1::CreateProjectRequest* request,
                                             v1::Project* response) {
  return Handle(store_, "CreateProject", *context, [&](const Caller& caller) -> RpcStatus {
    // A replayed create (same request_id) answers as the first one did.
    PBA_RETURN_IF_ERROR(store_.CreateProject(caller.user, request->name(), request->request_id()));
    // The project as the caller's listing shows it (creation time included).
    std::vector<ProjectInfo> projects;
    std::string token;
    do {
      PBA_RETURN_IF_ERROR(store_.ListProjects(caller.user, kMaxPageSize, token, &projects, &token));
      for (const ProjectInfo& project : projects) {
        if (project.name != request->name()) continue;
        response->set_name(project.name);
        SetTime(project.created_us, response->mutable_create_time());
        response->set_created_by(project.created_by);
        response->set_role(RoleToProto(project.role));
        return Status::Ok();
      }
    } while (!token.empty());
    return Status::Internal("the project just created cannot be listed");
  });
}

grpc::Status AtlasServiceImpl::ListProjects(grpc::ServerContext* context,
                                            const v1::ListProjectsRequest* request,
                                            v1::ListProjectsResponse* response) {
  return Handle(store_, "ListProjects", *context, [&](const Caller& caller) -> RpcStatus {
    std::vector<ProjectInfo> projects;
    std::string next;
    PBA_RETURN_IF_ERROR(store_.ListProjects(caller.user, request->page_size(),
                                            request->page_token(), &projects, &next));
    for (const ProjectInfo& project : projects) {
      v1::Project* out = response->add_projects();
      out->set_name(project.name);
      SetTime(project.created_us, out->mutable_create_time());
      out->set_created_by(project.created_by);
      out->set_role(RoleToProto(project.role));
    }
    response->set_next_page_token(next);
    return Status::Ok();
  });
}

grpc::Status AtlasServiceImpl::SetRole(grpc::ServerContext* context,
                                       const v1::SetRoleRequest* request, v1::Member* response) {
  return Handle(store_, "SetRole", *context, [&](const Caller& caller) -> RpcStatus {
    Role role = Role::kViewer;
    PBA_RETURN_IF_ERROR(RoleFromProto(request->role(), &role));
    PBA_RETURN_IF_ERROR(store_.SetRole(caller.user, request->project(), request->user(), role));
    response->set_project(request->project());
    response->set_user(request->user());
    response->set_role(request->role());
    return Status::Ok();
  });
}

grpc::Status AtlasServiceImpl::RemoveMember(grpc::ServerContext* context,
                                            const v1::RemoveMemberRequest* request,
                                            v1::RemoveMemberResponse* response) {
  return Handle(store_, "RemoveMember", *context, [&](const Caller& caller) -> RpcStatus {
    std::vector<std::string> released;
    std::lock_guard lock(change_mutex_);
    PBA_RETURN_IF_ERROR(
        store_.RemoveMember(caller.user, request->project(), request->user(), &released));
    // Watchers learn the locks are gone as they would from BreakLock.
    for (const std::string& structure : released) {
      Publish(v1::AtlasEvent::LOCK_BROKEN, request->project(), structure, 0, 0, caller.user,
              "lock of " + request->user() + " released: they were removed from the project");
      response->add_released_locks(structure);
    }
    return Status::Ok();
  });
}

// --- uploads ---------------------------------------------------------------

grpc::Status AtlasServiceImpl::BeginUpload(grpc::ServerContext* context,
                                           const v1::BeginUploadRequest* request,
                                           v1::Upload* response) {
  return Handle(store_, "BeginUpload", *context, [&](const Caller& caller) -> RpcStatus {
    UploadInfo info;
    PBA_RETURN_IF_ERROR(
        uploads_.Begin(caller.user, request->size_bytes(), request->sha256(), &info));
    UploadToProto(info, response);
    return Status::Ok();
  });
}

grpc::Status AtlasServiceImpl::WriteUpload(grpc::ServerContext* context,
                                           grpc::ServerReader<v1::UploadChunk>* reader,
                                           v1::Upload* response) {
  return Handle(store_, "WriteUpload", *context, [&](const Caller& caller) -> RpcStatus {
    v1::UploadChunk chunk;
    std::string upload_id;
    UploadInfo info;
    bool any = false;
    while (reader->Read(&chunk)) {
      if (!any) {
        upload_id = chunk.upload_id();
        any = true;
      } else if (chunk.upload_id() != upload_id) {
        return Status::InvalidArgument("upload_id",
                                       "every chunk of a stream must name the same upload");
      }
      PBA_RETURN_IF_ERROR(
          uploads_.Write(caller.user, upload_id, chunk.offset(), chunk.data(), &info));
    }
    if (!any) return Status::InvalidArgument("upload_id", "the stream held no chunk");
    UploadToProto(info, response);
    return Status::Ok();
  });
}

grpc::Status AtlasServiceImpl::GetUpload(grpc::ServerContext* context,
                                         const v1::GetUploadRequest* request,
                                         v1::Upload* response) {
  return Handle(store_, "GetUpload", *context, [&](const Caller& caller) -> RpcStatus {
    UploadInfo info;
    PBA_RETURN_IF_ERROR(uploads_.Get(caller.user, request->upload_id(), &info));
    UploadToProto(info, response);
    return Status::Ok();
  });
}

grpc::Status AtlasServiceImpl::DiscardUpload(grpc::ServerContext* context,
                                             const v1::DiscardUploadRequest* request,
                                             v1::DiscardUploadResponse*) {
  return Handle(store_, "DiscardUpload", *context, [&](const Caller& caller) -> RpcStatus {
    if (request->upload_id().empty()) {
      return Status::InvalidArgument("upload_id", "must not be empty");
    }
    if (!UploadStore::IsWellFormedId(request->upload_id())) {
      return Status::InvalidArgument("upload_id", "is not an upload id (32 characters 0-9 a-f)");
    }
    // Another user's upload is left alone and, like one already gone, not an
    // error (existence is not revealed).
    return uploads_.Remove(caller.user, request->upload_id());
  });
}

// --- structures ------------------------------------------------------------

grpc::Status AtlasServiceImpl::CreateStructure(grpc::ServerContext* context,
                                               const v1::CreateStructureRequest* request,
                                               v1::Revision* response) {
  constexpr char kRpc[] = "CreateStructure";
  return Handle(store_, kRpc, *context, [&](const Caller& caller) -> RpcStatus {
    const std::string& user = caller.user;
    const StructureRef ref{request->project(), request->name()};
    // Cheap checks before the upload is read.
    StructureFormat format = StructureFormat::kContours;
    PBA_RETURN_IF_ERROR(CheckName("project", ref.project));
    PBA_RETURN_IF_ERROR(CheckName("name", ref.structure));
    PBA_RETURN_IF_ERROR(FormatFromProto(request->format(), &format));
    const StructureMetadata metadata = MetadataFromProto(request->metadata());
    PBA_RETURN_IF_ERROR(CheckMetadata(metadata));
    PBA_RETURN_IF_ERROR(CheckMessage("message", request->message()));
    NewStructure create;
    create.structure = ref;
    create.metadata = metadata;
    create.format = format;
    create.message = request->message();
    create.request_id = request->request_id();
    // Rights before the upload is read: a caller who may not create here
    // must not get the server to parse what they uploaded.
    PBA_RETURN_IF_ERROR(store_.CheckRole(user, ref.project, Role::kEditor));
    // A retry of a create that landed is answered before its upload is
    // looked at: the first create consumed it.
    Revision revision;
    bool replayed = false;
    PBA_RETURN_IF_ERROR(store_.FindCreatedStructure(user, create, &revision, &replayed));
    std::unique_ptr<MappedFile> content;
    if (!replayed) {
      PBA_RETURN_IF_ERROR(TakeUpload(user, request->upload_id(), format, &content));
      PBA_RETURN_IF_ERROR(
          CheckDerivedStructure(store_, user, ref, format, content->bytes(), "upload_id"));
      PBA_RETURN_IF_ERROR(CheckLockedNeighbours(store_, user, ref, format, content->path()));
      create.geometry = content->bytes();
      create.geometry_file = content.get();
      std::lock_guard lock(change_mutex_);
      PBA_RETURN_IF_ERROR(store_.CreateStructure(user, create, &revision, &replayed));
      if (!replayed) {
        Publish(v1::AtlasEvent::STRUCTURE_CREATED, ref.project, ref.structure, revision.number, 0,
                user, request->message());
      }
    }
    content.reset();
    ForgetUpload(kRpc, user, request->upload_id());
    RevisionToProto(revision, response);
    return Status::Ok();
  });
}

grpc::Status AtlasServiceImpl::GetStructure(grpc::ServerContext* context,
                                            const v1::GetStructureRequest* request,
                                            v1::Structure* response) {
  return Handle(store_, "GetStructure", *context, [&](const Caller& caller) -> RpcStatus {
    StructureInfo info;
    PBA_RETURN_IF_ERROR(
        store_.GetStructure(caller.user, {request->project(), request->structure()}, &info));
    StructureToProto(info, response);
    return Status::Ok();
  });
}

grpc::Status AtlasServiceImpl::ListStructures(grpc::ServerContext* context,
                                              const v1::ListStructuresRequest* request,
                                              v1::ListStructuresResponse* response) {
  return Handle(store_, "ListStructures", *context, [&](const Caller& caller) -> RpcStatus {
    std::vector<StructureInfo> structures;
    std::string next;
    PBA_RETURN_IF_ERROR(store_.ListStructures(caller.user, request->project(), request->page_size(),
                                              request->page_token(), &structures, &next));
    for (const StructureInfo& info : structures) StructureToProto(info, response->add_structures());
    response->set_next_page_token(next);
    return Status::Ok();
  });
}

// --- locks -----------------------------------------------------------------

grpc::Status AtlasServiceImpl::AcquireLock(grpc::ServerContext* context,
                                           const v1::AcquireLockRequest* request,
                                           v1::Lock* response) {
  return Handle(store_, "AcquireLock", *context, [&](const Caller& caller) -> RpcStatus {
    int64_t lease_us = 0;
    PBA_RETURN_IF_ERROR(LeaseMicros(request->lease_seconds(), &lease_us));
    LockInfo info;
    {
      std::lock_guard lock(change_mutex_);
      PBA_RETURN_IF_ERROR(store_.AcquireLock(
          caller.user, {request->project(), request->structure()}, lease_us, &info));
      Publish(v1::AtlasEvent::LOCK_ACQUIRED, request->project(), request->structure(), 0, 0,
              caller.user,
              info.took_over_from.empty() ? "" : "took over from " + info.took_over_from);
    }
    LockToProto(info, response);  // the one response that carries lock_id
    return Status::Ok();
  });
}

grpc::Status AtlasServiceImpl::RenewLock(grpc::ServerContext* context,
                                         const v1::RenewLockRequest* request, v1::Lock* response) {
  return Handle(store_, "RenewLock", *context, [&](const Caller& caller) -> RpcStatus {
    int64_t lease_us = 0;
    PBA_RETURN_IF_ERROR(LeaseMicros(request->lease_seconds(), &lease_us));
    LockInfo info;
    {
      std::lock_guard lock(change_mutex_);
      PBA_RETURN_IF_ERROR(store_.RenewLock(caller.user, request->lock_id(), lease_us, &info));
      Publish(v1::AtlasEvent::LOCK_RENEWED, info.structure.project, info.structure.structure, 0, 0,
              caller.user, "");
    }
    LockToProto(info, response);
    response->clear_lock_id();
    return Status::Ok();
  });
}

grpc::Status AtlasServiceImpl::ReleaseLock(grpc::ServerContext* context,
                                           const v1::ReleaseLockRequest* request,
                                           v1::ReleaseLockResponse*) {
  return Handle(store_, "ReleaseLock", *context, [&](const Caller& caller) -> RpcStatus {
    std::lock_guard lock(change_mutex_);
    StructureRef released;
    PBA_RETURN_IF_ERROR(store_.ReleaseLock(caller.user, request->lock_id(), &released));
    Publish(v1::AtlasEvent::LOCK_RELEASED, released.project, released.structure, 0, 0, caller.user,
            "");
    return Status::Ok();
  });
}

grpc::Status AtlasServiceImpl::BreakLock(grpc::ServerContext* context,
                                         const v1::BreakLockRequest* request,
                                         v1::BreakLockResponse* response) {
  return Handle(store_, "BreakLock", *context, [&](const Caller& caller) -> RpcStatus {
    std::lock_guard lock(change_mutex_);
    std::string holder;
    PBA_RETURN_IF_ERROR(store_.BreakLock(caller.user, {request->project(), request->structure()},
                                         request->reason(), &holder));
    Publish(v1::AtlasEvent::LOCK_BROKEN, request->project(), request->structure(), 0, 0,
            caller.user, "lock of " + holder + " broken: " + request->reason());
    response->set_holder(holder);
    return Status::Ok();
  });
}

// --- revisions -------------------------------------------------------------

grpc::Status AtlasServiceImpl::CommitStructure(grpc::ServerContext* context,
                                               const v1::CommitStructureRequest* request,
                                               v1::Revision* response) {
  constexpr char kRpc[] = "CommitStructure";
  return Handle(store_, kRpc, *context, [&](const Caller& caller) -> RpcStatus {
    const std::string& user = caller.user;
    CommitRequest commit;
    commit.structure = {request->project(), request->structure()};
    commit.lock_id = request->lock_id();
    commit.base_revision = request->base_revision();
    if (request->has_material_json()) commit.material_json = request->material_json();
    commit.message = request->message();
    commit.request_id = request->request_id();
    PBA_RETURN_IF_ERROR(CheckName("project", commit.structure.project));
    PBA_RETURN_IF_ERROR(CheckName("structure", commit.structure.structure));
    PBA_RETURN_IF_ERROR(FormatFromProto(request->format(), &commit.format));
    PBA_RETURN_IF_ERROR(CheckMessage("message", commit.message));
    if (commit.lock_id.empty()) {
      return Status::InvalidArgument("lock_id", "required: acquire the structure's lock first");
    }
    // Rights before the upload is read (see CreateStructure); then a retry
    // of a commit that landed is answered without its upload, which the
    // first commit consumed (atlas.proto promises so).
    PBA_RETURN_IF_ERROR(store_.CheckRole(user, commit.structure.project, Role::kEditor));
    Revision revision;
    bool replayed = false;
    PBA_RETURN_IF_ERROR(
        store_.FindCommit(user, commit.structure, commit.request_id, &revision, &replayed));
    std::unique_ptr<MappedFile> content;
    if (!replayed) {
      PBA_RETURN_IF_ERROR(TakeUpload(user, request->upload_id(), commit.format, &content));
      PBA_RETURN_IF_ERROR(CheckDerivedStructure(store_, user, commit.structure, commit.format,
                                                content->bytes(), "upload_id"));
      PBA_RETURN_IF_ERROR(
          CheckLockedNeighbours(store_, user, commit.structure, commit.format, content->path()));
      commit.geometry = content->bytes();
      commit.geometry_file = content.get();
      std::lock_guard lock(change_mutex_);
      PBA_RETURN_IF_ERROR(store_.Commit(user, commit, &revision, &replayed));
      if (!replayed) {
        Publish(v1::AtlasEvent::COMMITTED, commit.structure.project, commit.structure.structure,
                revision.number, 0, user, commit.message);
      }
    }
    content.reset();
    ForgetUpload(kRpc, user, request->upload_id());
    RevisionToProto(revision, response);
    return Status::Ok();
  });
}

grpc::Status AtlasServiceImpl::UpdateMetadata(grpc::ServerContext* context,
                                              const v1::UpdateMetadataRequest* request,
                                              v1::UpdateMetadataResponse* response) {
  return Handle(store_, "UpdateMetadata", *context, [&](const Caller& caller) -> RpcStatus {
    MetadataUpdate update;
    if (request->has_colour()) {
      update.colour = Colour{request->colour().r(), request->colour().g(), request->colour().b()};
    }
    if (request->has_group_path()) update.group_path = request->group_path();
    if (request->has_material_json()) update.material_json = request->material_json();
    Revision revision;
    std::string etag;
    std::lock_guard lock(change_mutex_);
    PBA_RETURN_IF_ERROR(
        store_.UpdateMetadata(caller.user, {request->project(), request->structure()},
                              request->etag(), update, request->message(), &revision, &etag));
    // An update that changes nothing records nothing (the etag stays).
    if (etag != request->etag()) {
      Publish(v1::AtlasEvent::METADATA_UPDATED, request->project(), request->structure(),
              revision.number, 0, caller.user, revision.message);
    }
    RevisionToProto(revision, response->mutable_revision());
    response->set_etag(etag);
    return Status::Ok();
  });
}

grpc::Status AtlasServiceImpl::RevertStructure(grpc::ServerContext* context,
                                               const v1::RevertStructureRequest* request,
                                               v1::Revision* response) {
  return Handle(store_, "RevertStructure", *context, [&](const Caller& caller) -> RpcStatus {
    Revision revision;
    std::lock_guard lock(change_mutex_);
    PBA_RETURN_IF_ERROR(store_.Revert(caller.user, {request->project(), request->structure()},
                                      request->lock_id(), request->base_revision(),
                                      request->to_revision(), request->message(), &revision));
    Publish(v1::AtlasEvent::REVERTED, request->project(), request->structure(), revision.number, 0,
            caller.user, revision.message);
    RevisionToProto(revision, response);
    return Status::Ok();
  });
}

grpc::Status AtlasServiceImpl::ListRevisions(grpc::ServerContext* context,
                                             const v1::ListRevisionsRequest* request,
                                             v1::ListRevisionsResponse* response) {
  return Handle(store_, "ListRevisions", *context, [&](const Caller& caller) -> RpcStatus {
    std::vector<Revision> revisions;
    std::string next;
    PBA_RETURN_IF_ERROR(store_.History(caller.user, {request->project(), request->structure()},
                                       request->page_size(), request->page_token(), &revisions,
                                       &next));
    for (const Revision& revision : revisions) {
      RevisionToProto(revision, response->add_revisions());
    }
    response->set_next_page_token(next);
    return Status::Ok();
  });
}

grpc::Status AtlasServiceImpl::GetRevision(grpc::ServerContext* context,
                                           const v1::GetRevisionRequest* request,
                                           v1::Revision* response) {
  return Handle(store_, "GetRevision", *context, [&](const Caller& caller) -> RpcStatus {
    const StructureRef ref{request->project(), request->structure()};
    int64_t number = request->revision();
    if (number < 0) return Status::InvalidArgument("revision", "must be 0 (the head) or more");
    if (number == 0) {
      StructureInfo info;
      PBA_RETURN_IF_ERROR(store_.GetStructure(caller.user, ref, &info));
      number = info.head;
    }
    Revision revision;
    PBA_RETURN_IF_ERROR(store_.GetRevision(caller.user, ref, number, &revision, nullptr));
    RevisionToProto(revision, response);
    return Status::Ok();
  });
}

namespace {

// `bytes` from `offset` as DataChunks of at most `chunk_bytes`, with the
// total size in each; one chunk even at the end, so the client learns
// total_size. `what` names the bytes in an offset past the end.
RpcStatus StreamChunks(grpc::ServerContext& context, grpc::ServerWriter<v1::DataChunk>* writer,
                       const std::string& bytes, int64_t offset, size_t chunk_bytes,
                       const std::string& what) {
  const int64_t size = static_cast<int64_t>(bytes.size());
  if (offset < 0) return Status::InvalidArgument("offset", "must not be negative");
  if (offset > size) {
    return Status::OutOfRange("offset", std::to_string(offset) + " is past the end of " + what +
                                            " (" + std::to_string(size) + " bytes)");
  }
  v1::DataChunk chunk;
  chunk.set_total_size(size);
  do {
    if (context.IsCancelled()) {
      return RpcStatus::StreamEnded(grpc::StatusCode::CANCELLED, "cancelled");
    }
    const int64_t want = std::min<int64_t>(static_cast<int64_t>(chunk_bytes), size - offset);
    chunk.set_offset(offset);
    chunk.set_data(bytes.data() + offset, static_cast<size_t>(want));
    if (!writer->Write(chunk)) {
      return RpcStatus::StreamEnded(grpc::StatusCode::CANCELLED, "the client went away");
    }
    offset += want;
  } while (offset < size);
  return Status::Ok();
}

// The top-level parameters of two material JSON objects that differ.
void DiffMaterials(const std::string& from, const std::string& to, v1::RevisionDiff* diff) {
  google::protobuf::Struct a, b;
  // Stored material is a JSON object (atlas_types.h checks it on the way in).
  (void)google::protobuf::util::JsonStringToMessage(from, &a);
  (void)google::protobuf::util::JsonStringToMessage(to, &b);
  const auto text = [](const google::protobuf::Value& v) {
    std::string out;
    (void)google::protobuf::util::MessageToJsonString(v, &out);
    return out;
  };
  std::map<std::string, std::pair<std::string, std::string>> changes;
  for (const auto& [key, value] : a.fields()) changes[key].first = text(value);
  for (const auto& [key, value] : b.fields()) changes[key].second = text(value);
  for (const auto& [key, values] : changes) {
    if (values.first == values.second) continue;
    auto* change = diff->add_material_changes();
    change->set_parameter(key);
    change->set_from(values.first);
    change->set_to(values.second);
  }
}

}  // namespace

// The voxels revisions are compared on [mm]: fine enough for the brain's
// nuclei (a few mm across), coarse enough for a whole cortex in a second.
constexpr double kDiffVoxelMm = 1.0;

grpc::Status AtlasServiceImpl::DiffRevisions(grpc::ServerContext* context,
                                             const v1::DiffRevisionsRequest* request,
                                             v1::RevisionDiff* response) {
  return Handle(store_, "DiffRevisions", *context, [&](const Caller& caller) -> RpcStatus {
    const StructureRef ref{request->project(), request->structure()};
    int64_t to = request->to_revision(), from = request->from_revision();
    if (to < 0 || from < 0) {
      return Status::InvalidArgument(to < 0 ? "to_revision" : "from_revision",
                                     "must be 0 (the default) or more");
    }
    if (to == 0 || from == 0) {
      StructureInfo info;
      PBA_RETURN_IF_ERROR(store_.GetStructure(caller.user, ref, &info));
      if (to == 0) to = info.head;
      if (from == 0) from = std::max<int64_t>(1, to - 1);
    }
    Revision a, b;
    std::string geometry_a, geometry_b;
    PBA_RETURN_IF_ERROR(store_.GetRevision(caller.user, ref, from, &a, &geometry_a));
    PBA_RETURN_IF_ERROR(store_.GetRevision(caller.user, ref, to, &b, &geometry_b));
    response->set_project(ref.project);
    response->set_structure(ref.structure);
    response->set_from_revision(from);
    response->set_to_revision(to);
    DiffMaterials(a.metadata.material_json, b.metadata.material_json, response);
    const auto colour = [](const Colour& c, v1::Colour* out) {
      out->set_r(c.r);
      out->set_g(c.g);
      out->set_b(c.b);
    };
    colour(a.metadata.colour, response->mutable_from_colour());
    colour(b.metadata.colour, response->mutable_to_colour());
    response->set_from_group(a.metadata.group_path);
    response->set_to_group(b.metadata.group_path);
    response->set_geometry_changed(a.content_sha256 != b.content_sha256);
    if (a.format == StructureFormat::kContours && b.format == StructureFormat::kContours) {
      Contours plates_a, plates_b;
      PBA_RETURN_IF_ERROR(ParseContoursJson(geometry_a, "from", &plates_a));
      PBA_RETURN_IF_ERROR(ParseContoursJson(geometry_b, "to", &plates_b));
      v1::ContoursDiff* contours = response->mutable_contours();
      contours->set_from_volume_mm3(ContoursVolume(plates_a));
      contours->set_to_volume_mm3(ContoursVolume(plates_b));
      const ContoursDistance distance = DistanceBetween(plates_a, plates_b);
      contours->set_hausdorff_mm(distance.hausdorff_mm);
      contours->set_mean_distance_mm(distance.mean_mm);
      contours->set_plates_compared(distance.plates_compared);
      for (double z : distance.only_in_a_z_mm) contours->add_only_in_from_z_mm(z);
      for (double z : distance.only_in_b_z_mm) contours->add_only_in_to_z_mm(z);
    }
    if (a.content_sha256 == b.content_sha256) return Status::Ok();
    // A derived revision has no shape of its own, only a recipe.
    if (a.format == StructureFormat::kDerived || b.format == StructureFormat::kDerived) {
      return Status::Ok();
    }
    // The caller gone or the server stopping ends the wait for a slot and
    // the comparison between its phases.
    const auto cancelled = [&] { return context->IsCancelled() || stopping_.load(); };
    const auto give_up = [&](const Status& why) -> RpcStatus {
      if (stopping_.load()) {
        return grpc::Status(grpc::StatusCode::UNAVAILABLE,
                            "the server is shutting down; compare again once it is back");
      }
      return why;
    };
    ShapeComparison shapes;
    Status status = diff_slots_.Acquire(cancelled, kDiffPatience);
    if (!status.ok()) return give_up(status);
    status = CompareRevisionShapes(a.format, geometry_a, b.format, geometry_b, kDiffVoxelMm,
                                   kMaxDiffVoxels, cancelled, &shapes);
    diff_slots_.Release();
    if (!status.ok()) return give_up(status);
    v1::ShapeDiff* shape = response->mutable_shape();
    // Coarser than kDiffVoxelMm when the shapes' box would pass the budget.
    shape->set_voxel_mm(shapes.overlap.voxel_mm);
    shape->set_from_volume_mm3(shapes.overlap.a_mm3);
    shape->set_to_volume_mm3(shapes.overlap.b_mm3);
    shape->set_shared_volume_mm3(shapes.overlap.overlap_mm3);
    shape->set_dice(shapes.dice);
    shape->set_hausdorff_mm(shapes.hausdorff_mm);
    shape->set_mean_surface_distance_mm(shapes.mean_surface_distance_mm);
    return Status::Ok();
  });
}

grpc::Status AtlasServiceImpl::DownloadGeometry(grpc::ServerContext* context,
                                                const v1::DownloadGeometryRequest* request,
                                                grpc::ServerWriter<v1::DataChunk>* writer) {
  return Handle(store_, "DownloadGeometry", *context, [&](const Caller& caller) -> RpcStatus {
    const StructureRef ref{request->project(), request->structure()};
    int64_t number = request->revision();
    Status status;
    if (number < 0) status = Status::InvalidArgument("revision", "must be 0 (the head) or more");
    if (status.ok() && request->offset() < 0) {
      status = Status::InvalidArgument("offset", "must not be negative");
    }
    if (status.ok() && number == 0) {
      StructureInfo info;
      status = store_.GetStructure(caller.user, ref, &info);
      number = info.head;
    }
    // The whole blob, verified against its hash, before the first byte is sent.
    Revision revision;
    std::string geometry;
    if (status.ok()) status = store_.GetRevision(caller.user, ref, number, &revision, &geometry);
    // A blob that no longer matches its hash is lost data, not a bug.
    if (status.code() == Status::Code::kIo) {
      return grpc::Status(grpc::StatusCode::DATA_LOSS, status.ToString());
    }
    PBA_RETURN_IF_ERROR(status);
    return StreamChunks(
        *context, writer, geometry, request->offset(), kChunkBytes,
        "revision " + std::to_string(number) + " of structure '" + ref.structure + "'");
  });
}

// --- snapshots and audit ---------------------------------------------------

grpc::Status AtlasServiceImpl::DownloadSurfaces(grpc::ServerContext* context,
                                                const v1::DownloadSurfacesRequest* request,
                                                grpc::ServerWriter<v1::DataChunk>* writer) {
  return Handle(store_, "DownloadSurfaces", *context, [&](const Caller& caller) -> RpcStatus {
    if (surface_views_ == nullptr) {
      return grpc::Status(grpc::StatusCode::UNIMPLEMENTED, "this server draws no surfaces");
    }
    const std::string& project = request->project();
    const std::string& structure = request->structure();
    if (request->revision() < 0) {
      return Status::InvalidArgument("revision", "must be 0 (the head) or more");
    }
    if (request->offset() < 0) return Status::InvalidArgument("offset", "must not be negative");
    if (request->revision() > 0 && structure.empty()) {
      return Status::InvalidArgument("revision", "names a revision of `structure`, which is empty");
    }
    if (!structure.empty() && !request->snapshot().empty()) {
      return Status::InvalidArgument("structure",
                                     "draws one structure's revision: give it "
                                     "without a snapshot");
    }
    // Rights first (each store call checks the caller's role), then work.
    std::vector<SnapshotFile> files;
    int64_t snapshot = 0;
    if (!structure.empty()) {
      const StructureRef ref{project, structure};
      int64_t number = request->revision();
      if (number == 0) {
        StructureInfo info;
        PBA_RETURN_IF_ERROR(store_.GetStructure(caller.user, ref, &info));
        number = info.head;
      }
      files.emplace_back();
      PBA_RETURN_IF_ERROR(store_.RevisionFile(caller.user, ref, number, &files.back()));
      if (files.back().revision.format == StructureFormat::kDerived) {
        return Status::FailedPrecondition(
            "structure", "'" + structure +
                             "' is derived from other structures and has no shape "
                             "of its own: draw the project's structures or a snapshot instead");
      }
    } else if (!request->snapshot().empty()) {
      SnapshotInfo info;
      PBA_RETURN_IF_ERROR(store_.ResolveSnapshot(caller.user, project, request->snapshot(), &info));
      snapshot = info.id;
      PBA_RETURN_IF_ERROR(store_.SnapshotFiles(caller.user, project, snapshot, &files));
    } else {
      PBA_RETURN_IF_ERROR(store_.Heads(caller.user, project, &files));
    }
    if (files.empty()) {
      return Status::FailedPrecondition("project", "'" + project + "' has no structures to draw");
    }
    const auto cancelled = [&] { return context->IsCancelled() || stopping_.load(); };
    SurfaceView view;
    const Status status = surface_views_->Get(project, snapshot, files, cancelled, &view);
    if (!status.ok() && stopping_.load()) {
      return grpc::Status(grpc::StatusCode::UNAVAILABLE,
                          "the server is shutting down; ask again once it is back");
    }
    PBA_RETURN_IF_ERROR(status);
    spdlog::info("DownloadSurfaces {} ({} structures): {}", project, files.size(),
                 view.cached ? std::string("from the cache")
                             : "built in " + std::to_string(view.build_s) + " s");
    return StreamChunks(*context, writer, view.bytes, request->offset(), kChunkBytes,
                        "the surfaces");
  });
}

grpc::Status AtlasServiceImpl::CreateSnapshot(grpc::ServerContext* context,
                                              const v1::CreateSnapshotRequest* request,
                                              v1::Snapshot* response) {
  return Handle(store_, "CreateSnapshot", *context, [&](const Caller& caller) -> RpcStatus {
    SnapshotInfo snapshot;
    std::lock_guard lock(change_mutex_);
    bool replayed = false;
    PBA_RETURN_IF_ERROR(store_.CreateSnapshot(caller.user, request->project(), request->name(),
                                              &snapshot, request->request_id(), &replayed));
    if (!replayed) {
      Publish(v1::AtlasEvent::SNAPSHOT_CREATED, request->project(), "", 0, snapshot.id, caller.user,
              snapshot.name);
    }
    SnapshotToProto(snapshot, response);
    return Status::Ok();
  });
}

grpc::Status AtlasServiceImpl::TagSnapshot(grpc::ServerContext* context,
                                           const v1::TagSnapshotRequest* request,
                                           v1::Snapshot* response) {
  return Handle(store_, "TagSnapshot", *context, [&](const Caller& caller) -> RpcStatus {
    {
      std::lock_guard lock(change_mutex_);
      PBA_RETURN_IF_ERROR(
          store_.Tag(caller.user, request->project(), request->snapshot_id(), request->tag()));
      Publish(v1::AtlasEvent::SNAPSHOT_TAGGED, request->project(), "", 0, request->snapshot_id(),
              caller.user, request->tag());
    }
    SnapshotInfo snapshot;
    PBA_RETURN_IF_ERROR(store_.ResolveSnapshot(caller.user, request->project(),
                                               std::to_string(request->snapshot_id()), &snapshot));
    SnapshotToProto(snapshot, response);
    return Status::Ok();
  });
}

grpc::Status AtlasServiceImpl::GetSnapshot(grpc::ServerContext* context,
                                           const v1::GetSnapshotRequest* request,
                                           v1::Snapshot* response) {
  return Handle(store_, "GetSnapshot", *context, [&](const Caller& caller) -> RpcStatus {
    SnapshotInfo snapshot;
    PBA_RETURN_IF_ERROR(
        store_.ResolveSnapshot(caller.user, request->project(), request->snapshot(), &snapshot));
    SnapshotToProto(snapshot, response);
    return Status::Ok();
  });
}

grpc::Status AtlasServiceImpl::ListSnapshots(grpc::ServerContext* context,
                                             const v1::ListSnapshotsRequest* request,
                                             v1::ListSnapshotsResponse* response) {
  return Handle(store_, "ListSnapshots", *context, [&](const Caller& caller) -> RpcStatus {
    std::vector<SnapshotInfo> snapshots;
    std::string next;
    PBA_RETURN_IF_ERROR(store_.ListSnapshots(caller.user, request->project(), request->page_size(),
                                             request->page_token(), &snapshots, &next));
    for (const SnapshotInfo& snapshot : snapshots) {
      SnapshotToProto(snapshot, response->add_snapshots());
    }
    response->set_next_page_token(next);
    return Status::Ok();
  });
}

grpc::Status AtlasServiceImpl::ListAudit(grpc::ServerContext* context,
                                         const v1::ListAuditRequest* request,
                                         v1::ListAuditResponse* response) {
  return Handle(store_, "ListAudit", *context, [&](const Caller& caller) -> RpcStatus {
    std::vector<AuditEntry> entries;
    std::string next;
    PBA_RETURN_IF_ERROR(store_.ListAudit(caller.user, request->project(), request->page_size(),
                                         request->page_token(), &entries, &next));
    for (const AuditEntry& entry : entries) {
      v1::AuditEntry* out = response->add_entries();
      out->set_sequence(entry.seq);
      SetTime(entry.time_us, out->mutable_time());
      out->set_user(entry.user);
      out->set_action(entry.action);
      out->set_target(entry.target);
      out->set_revision(entry.revision);
      out->set_detail(entry.detail);
    }
    response->set_next_page_token(next);
    return Status::Ok();
  });
}

// --- watch -----------------------------------------------------------------

Status AtlasServiceImpl::MayWatch(const std::string& project, const std::string& user) {
  Role role = Role::kViewer;
  bool member = false;
  PBA_RETURN_IF_ERROR(store_.RoleOf(project, user, &role, &member));
  if (!member) {
    return Status::PermissionDenied("user '" + user + "' is not a member of project '" + project +
                                    "'; watching needs viewer");
  }
  return Status::Ok();
}

grpc::Status AtlasServiceImpl::Watch(grpc::ServerContext* context, const v1::WatchRequest* request,
                                     grpc::ServerWriter<v1::AtlasEvent>* writer) {
  return Handle(store_, "Watch", *context, [&](const Caller& caller) -> RpcStatus {
    const std::string& project = request->project();
    PBA_RETURN_IF_ERROR(MayWatch(project, caller.user));
    const StreamSlots::Ticket slot = watch_slots_.TryAcquire(caller.user);
    if (!slot.held()) {
      return Status::ResourceExhausted("", "user '" + caller.user + "' already has " +
                                               std::to_string(kMaxWatchesPerUser) +
                                               " Watch streams open; close one first");
    }
    auto checked = std::chrono::steady_clock::now();
    // Subscribed before READY goes out: nothing published after READY is missed.
    const std::unique_ptr<AtlasEventHub::Subscription> subscription = hub_.Subscribe(project);
    v1::AtlasEvent ready;
    ready.set_kind(v1::AtlasEvent::READY);
    ready.set_project(project);
    ready.set_user(caller.user);
    SetTime(NowMicros(), ready.mutable_time());
    if (!writer->Write(ready)) {
      return RpcStatus::StreamEnded(grpc::StatusCode::CANCELLED, "the client went away");
    }
    std::vector<v1::AtlasEvent> events;
    while (true) {
      if (context->IsCancelled()) {
        return RpcStatus::StreamEnded(grpc::StatusCode::CANCELLED, "watch cancelled");
      }
      if (std::chrono::steady_clock::now() - checked >= kWatchRecheck) {
        // A long watch must not outlive the caller's rights (a user disabled
        // or a member removed since it opened loses it, as in WatchJob).
        checked = std::chrono::steady_clock::now();
        Caller again;
        PBA_RETURN_IF_ERROR(CallUser(store_, *context, &again));
        PBA_RETURN_IF_ERROR(MayWatch(project, again.user));
      }
      bool overrun = false;
      if (!subscription->Next(kWatchPoll, &events, &overrun)) {
        if (overrun) {
          return Status::ResourceExhausted(
              "", "the watcher fell more than " + std::to_string(AtlasEventHub::kMaxQueued) +
                      " events behind; watch again and read the audit log for the gap");
        }
        return RpcStatus::StreamEnded(grpc::StatusCode::UNAVAILABLE, "the server is shutting down");
      }
      for (const v1::AtlasEvent& event : events) {
        if (!writer->Write(event)) {
          return RpcStatus::StreamEnded(grpc::StatusCode::CANCELLED, "the client went away");
        }
      }
    }
  });
}

}  // namespace pba
