#include "commands/atlas_shared.h"

#include <cstdint>
#include <cstdio>
#include <random>

#include "transfer.h"

namespace pba::cli {
namespace fs = std::filesystem;

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
int DownloadRevision(Connection& connection, const v1::Revision& revision, const fs::path& out) {
  return DownloadTo(connection, out, revision.size_bytes(), revision.content_sha256(),
                    revision.project() + "/" + revision.structure() + " revision " +
                        std::to_string(revision.number()),
                    [&](grpc::ClientContext* context, int64_t offset) {
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
