#include "commands/atlas_shared.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <random>

#include "exit_codes.h"
#include "files.h"
#include "transfer.h"

namespace pba::cli {
namespace fs = std::filesystem;
namespace {
constexpr int64_t kUploadChunkBytes = 1 << 20;  // the API's largest chunk
}  // namespace

void DiscardUpload(Connection& connection, const std::string& upload_id) {
  if (upload_id.empty()) return;
  v1::DiscardUploadRequest request;
  request.set_upload_id(upload_id);
  v1::DiscardUploadResponse response;
  auto context = connection.UnaryContext();
  connection.atlas().DiscardUpload(context.get(), request, &response);
}

// Uploads `file` (BeginUpload, then WriteUpload from where the server says
// it is, retried up to three times); *upload_id names the complete upload.
int UploadFile(Connection& connection, const std::string& file, std::string* upload_id) {
  std::error_code ec;
  const auto size = static_cast<int64_t>(fs::file_size(file, ec));
  if (ec) {
    std::fprintf(stderr, "pba: cannot read %s: %s\n", file.c_str(), ec.message().c_str());
    return kExitError;
  }
  v1::BeginUploadRequest begin;
  begin.set_size_bytes(size);
  begin.set_sha256(Sha256File(file));
  v1::Upload upload;
  {
    auto context = connection.UnaryContext();
    grpc::Status status = connection.atlas().BeginUpload(context.get(), begin, &upload);
    if (!status.ok()) return connection.Fail("uploading " + file, status, kExitConflict);
  }
  Progress progress("uploading " + file, size);
  std::ifstream in(file, std::ios::binary);
  std::string buffer(static_cast<size_t>(std::min(kUploadChunkBytes, std::max<int64_t>(size, 1))),
                     '\0');
  grpc::Status last;
  for (int attempt = 0; attempt < 3 && upload.received_bytes() < size; ++attempt) {
    if (attempt > 0) {
      // Where the server is: the next chunk starts there.
      v1::GetUploadRequest get;
      get.set_upload_id(upload.id());
      auto context = connection.UnaryContext();
      grpc::Status status = connection.atlas().GetUpload(context.get(), get, &upload);
      if (!status.ok()) {
        DiscardUpload(connection, upload.id());
        return connection.Fail("resuming the upload of " + file, status);
      }
    }
    in.clear();
    in.seekg(upload.received_bytes());
    auto context = connection.StreamContext();
    v1::Upload result;
    auto writer = connection.atlas().WriteUpload(context.get(), &result);
    int64_t offset = upload.received_bytes();
    while (offset < size) {
      const auto n =
          static_cast<std::streamsize>(std::min<int64_t>(kUploadChunkBytes, size - offset));
      in.read(buffer.data(), n);
      if (in.gcount() != n) {
        std::fprintf(stderr, "pba: %s changed while it was being uploaded\n", file.c_str());
        writer->WritesDone();
        writer->Finish();
        DiscardUpload(connection, upload.id());
        return kExitError;
      }
      v1::UploadChunk chunk;
      chunk.set_upload_id(upload.id());
      chunk.set_offset(offset);
      chunk.set_data(buffer.data(), static_cast<size_t>(n));
      if (!writer->Write(chunk)) break;
      offset += n;
      progress.Update(offset);
    }
    writer->WritesDone();
    last = writer->Finish();
    if (last.ok()) upload = result;
  }
  if (upload.received_bytes() < size) {
    DiscardUpload(connection, upload.id());
    return connection.Fail("uploading " + file,
                           last.ok() ? grpc::Status(grpc::UNKNOWN, "incomplete") : last);
  }
  *upload_id = upload.id();
  return kExitOk;
}

std::string RequestIdOr(const std::string& given) {
  if (!given.empty()) return given;
  std::random_device device;
  std::mt19937_64 engine((static_cast<uint64_t>(device()) << 32) ^ device());
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%016llx%016llx", static_cast<unsigned long long>(engine()),
                static_cast<unsigned long long>(engine()));
  return buffer;
}

std::string RoleText(v1::Role role) {
  switch (role) {
    case v1::VIEWER:
      return "viewer";
    case v1::EDITOR:
      return "editor";
    case v1::ADMIN:
      return "admin";
    default:
      return "-";
  }
}

std::string FormatText(v1::GeometryFormat format) {
  switch (format) {
    case v1::CONTOURS_JSON:
      return "contours_json";
    case v1::NIFTI:
      return "nifti";
    case v1::STL:
      return "stl";
    case v1::OBJ:
      return "obj";
    case v1::VTK:
      return "vtk";
    case v1::DERIVED:
      return "derived";
    default:
      return "-";
  }
}

std::string Extension(v1::GeometryFormat format) {
  switch (format) {
    case v1::CONTOURS_JSON:
      return ".json";
    case v1::NIFTI:
      return ".nii.gz";
    case v1::STL:
      return ".stl";
    case v1::OBJ:
      return ".obj";
    case v1::VTK:
      return ".vtk";
    case v1::DERIVED:
      return ".yaml";
    default:
      return ".bin";
  }
}

std::string ColourText(const v1::Colour& c) {
  return std::to_string(c.r()) + "," + std::to_string(c.g()) + "," + std::to_string(c.b());
}

void MoreHint(const std::string& next, const std::string& command) {
  if (!next.empty()) std::printf("More: %s --page-token %s\n", command.c_str(), next.c_str());
}

// Downloads a revision's geometry into `out` (transfer.h: resumed, checked
// against the revision's SHA-256).
int DownloadRevision(Connection& connection, const v1::Revision& revision, const fs::path& out,
                     bool overwrite) {
  return DownloadTo(connection, out, revision.size_bytes(), revision.content_sha256(),
                    revision.project() + "/" + revision.structure() + " revision " +
                        std::to_string(revision.number()),
                    overwrite, [&](grpc::ClientContext* context, int64_t offset) {
                      v1::DownloadGeometryRequest request;
                      request.set_project(revision.project());
                      request.set_structure(revision.structure());
                      request.set_revision(revision.number());
                      request.set_offset(offset);
                      return connection.atlas().DownloadGeometry(context, request);
                    });
}

int GetHead(Connection& connection, const StructureArgs& target, int64_t number,
            v1::Revision* revision) {
  v1::GetRevisionRequest request;
  request.set_project(target.project);
  request.set_structure(target.structure);
  request.set_revision(number);
  auto context = connection.UnaryContext();
  grpc::Status status = connection.atlas().GetRevision(context.get(), request, revision);
  if (!status.ok()) return connection.Fail(target.project + "/" + target.structure, status);
  return kExitOk;
}

}  // namespace pba::cli
