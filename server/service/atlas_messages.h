// Conversions between the pba.v1 atlas messages and the atlas store's types
// (store/atlas_types.h, store/upload_store.h), for AtlasServiceImpl. Times
// are microseconds since the Unix epoch in the store, Timestamps here.
#pragma once

#include <google/protobuf/timestamp.pb.h>

#include <cstdint>

#include "pba/status.h"
#include "pba/v1/atlas.pb.h"
#include "store/atlas_types.h"
#include "store/upload_store.h"

namespace pba {

void SetTime(int64_t us, google::protobuf::Timestamp* time);

v1::Role RoleToProto(Role role);
// kInvalidArgument (field "role") for ROLE_UNSPECIFIED or an unknown value.
Status RoleFromProto(v1::Role role, Role* out);

v1::GeometryFormat FormatToProto(StructureFormat format);
// kInvalidArgument (field "format") for GEOMETRY_FORMAT_UNSPECIFIED or an
// unknown value.
Status FormatFromProto(v1::GeometryFormat format, StructureFormat* out);

void MetadataToProto(const StructureMetadata& metadata, v1::StructureMetadata* out);
// An empty material_json becomes "{}" (no parameters).
StructureMetadata MetadataFromProto(const v1::StructureMetadata& metadata);

void RevisionToProto(const Revision& revision, v1::Revision* out);
// lock_id is copied as given: callers clear it unless the caller acquired it.
void LockToProto(const LockInfo& lock, v1::Lock* out);
// The lock, if any, without its id.
void StructureToProto(const StructureInfo& info, v1::Structure* out);
void UploadToProto(const UploadInfo& upload, v1::Upload* out);
void SnapshotToProto(const SnapshotInfo& snapshot, v1::Snapshot* out);

}  // namespace pba
