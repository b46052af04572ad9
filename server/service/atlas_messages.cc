#include "service/atlas_messages.h"

namespace pba {

void SetTime(int64_t us, google::protobuf::Timestamp* time) {
  int64_t seconds = us / 1000000;
  int64_t micros = us % 1000000;
  if (micros < 0) {
    micros += 1000000;
    seconds -= 1;
  }
  time->set_seconds(seconds);
  time->set_nanos(static_cast<int32_t>(micros * 1000));
}

v1::Role RoleToProto(Role role) {
  switch (role) {
    case Role::kViewer:
      return v1::VIEWER;
    case Role::kEditor:
      return v1::EDITOR;
    case Role::kAdmin:
      return v1::ADMIN;
  }
  return v1::ROLE_UNSPECIFIED;
}

Status RoleFromProto(v1::Role role, Role* out) {
  switch (role) {
    case v1::VIEWER:
      *out = Role::kViewer;
      return Status::Ok();
    case v1::EDITOR:
      *out = Role::kEditor;
      return Status::Ok();
    case v1::ADMIN:
      *out = Role::kAdmin;
      return Status::Ok();
    default:
      return Status::InvalidArgument("role", "must be VIEWER, EDITOR or ADMIN");
  }
}

v1::GeometryFormat FormatToProto(StructureFormat format) {
  switch (format) {
    case StructureFormat::kContours:
      return v1::CONTOURS_JSON;
    case StructureFormat::kNifti:
      return v1::NIFTI;
    case StructureFormat::kStl:
      return v1::STL;
    case StructureFormat::kObj:
      return v1::OBJ;
    case StructureFormat::kVtk:
      return v1::VTK;
    case StructureFormat::kDerived:
      return v1::DERIVED;
  }
  return v1::GEOMETRY_FORMAT_UNSPECIFIED;
}

Status FormatFromProto(v1::GeometryFormat format, StructureFormat* out) {
  switch (format) {
    case v1::CONTOURS_JSON:
      *out = StructureFormat::kContours;
      return Status::Ok();
    case v1::NIFTI:
      *out = StructureFormat::kNifti;
      return Status::Ok();
    case v1::STL:
      *out = StructureFormat::kStl;
      return Status::Ok();
    case v1::OBJ:
      *out = StructureFormat::kObj;
      return Status::Ok();
    case v1::VTK:
      *out = StructureFormat::kVtk;
      return Status::Ok();
    case v1::DERIVED:
      *out = StructureFormat::kDerived;
      return Status::Ok();
    default:
      return Status::InvalidArgument("format",
                                     "must be CONTOURS_JSON, NIFTI, STL, OBJ, VTK or DERIVED");
  }
}

void MetadataToProto(const StructureMetadata& metadata, v1::StructureMetadata* out) {
  out->mutable_colour()->set_r(metadata.colour.r);
  out->mutable_colour()->set_g(metadata.colour.g);
  out->mutable_colour()->set_b(metadata.colour.b);
  out->set_group_path(metadata.group_path);
  out->set_material_json(metadata.material_json);
}

StructureMetadata MetadataFromProto(const v1::StructureMetadata& metadata) {
  StructureMetadata out;
  out.colour = {metadata.colour().r(), metadata.colour().g(), metadata.colour().b()};
  out.group_path = metadata.group_path();
  if (!metadata.material_json().empty()) out.material_json = metadata.material_json();
  return out;
}

void RevisionToProto(const Revision& revision, v1::Revision* out) {
  out->set_project(revision.project);
  out->set_structure(revision.structure);
  out->set_number(revision.number);
  out->set_parent(revision.parent);
  out->set_author(revision.author);
  SetTime(revision.time_us, out->mutable_time());
  out->set_kind(revision.kind);
  out->set_message(revision.message);
  out->set_content_sha256(revision.content_sha256);
  out->set_format(FormatToProto(revision.format));
  out->set_size_bytes(revision.size_bytes);
  MetadataToProto(revision.metadata, out->mutable_metadata());
}

void LockToProto(const LockInfo& lock, v1::Lock* out) {
  out->set_project(lock.structure.project);
  out->set_structure(lock.structure.structure);
  out->set_holder(lock.owner);
  out->set_lock_id(lock.lock_id);
  SetTime(lock.acquired_us, out->mutable_acquire_time());
  SetTime(lock.lease_expiry_us, out->mutable_expire_time());
  out->set_took_over_from(lock.took_over_from);
}

void StructureToProto(const StructureInfo& info, v1::Structure* out) {
  out->set_project(info.project);
  out->set_name(info.name);
  out->set_head(info.head);
  out->set_metadata_etag(info.metadata_etag);
  MetadataToProto(info.metadata, out->mutable_metadata());
  SetTime(info.created_us, out->mutable_create_time());
  if (info.lock) {
    LockToProto(*info.lock, out->mutable_lock());
    out->mutable_lock()->clear_lock_id();
  }
}

void UploadToProto(const UploadInfo& upload, v1::Upload* out) {
  out->set_id(upload.id);
  out->set_size_bytes(upload.size_bytes);
  out->set_sha256(upload.sha256);
  out->set_received_bytes(upload.received_bytes);
  SetTime(upload.expire_us, out->mutable_expire_time());
}

void SnapshotToProto(const SnapshotInfo& snapshot, v1::Snapshot* out) {
  out->set_project(snapshot.project);
  out->set_id(snapshot.id);
  out->set_name(snapshot.name);
  out->set_author(snapshot.author);
  SetTime(snapshot.created_us, out->mutable_create_time());
  for (const std::string& tag : snapshot.tags) out->add_tags(tag);
  for (const auto& [structure, revision] : snapshot.revisions) {
    v1::Snapshot::Member* member = out->add_members();
    member->set_structure(structure);
    member->set_revision(revision);
  }
}

}  // namespace pba
