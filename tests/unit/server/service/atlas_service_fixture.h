// The fixture the atlas service tests share: a PbaServer running in-process
// on 127.0.0.1:0 with an admin, bob (editor), carol (viewer) and dave (no
// role) in project "atlas", where "lung" exists at revision 1, and helpers
// that call it through real channels.
#pragma once

#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "app/pba_server.h"
#include "core/sha256.h"
#include "service/atlas_service.h"
#include "unit/server/server_test_support.h"

namespace pba::service_test {

using testing::TempDir;
namespace fs = std::filesystem;

constexpr size_t kMiB = 1 << 20;

inline std::string Hash(const std::string& bytes) { return Sha256Hex(bytes); }

inline bool Contains(const std::string& text, const std::string& fragment) {
  return text.find(fragment) != std::string::npos;
}

// Contours JSON of about `bytes` bytes: one plate with one polygon of many
// points (within the 500 mm the check allows).
inline std::string Contours(size_t bytes, int seed) {
  std::string json = "{\"seed\": " + std::to_string(seed) + ", \"plates\": [{\"z_mm\": 1.5, ";
  json += "\"polygons\": [[";
  for (int i = 0; json.size() < bytes; ++i) {
    if (i > 0) json += ", ";
    json += "[" + std::to_string(i % 397) + "." + std::to_string(seed % 10) + ", " +
            std::to_string((i * i * 31) % 409) + ".25]";
  }
  json += "]]}]}";
  return json;
}

// A square [x0, x1] x [0, 10] mm drawn on plates at z = 0 and 4 mm.
inline std::string Square(double x0, double x1) {
  std::ostringstream out;
  out << R"({"plates": [)";
  for (double z : {0.0, 4.0}) {
    out << (z > 0 ? ", " : "") << R"({"z_mm": )" << z << R"(, "polygons": [[[)" << x0 << ", 0], ["
        << x1 << ", 0], [" << x1 << ", 10], [" << x0 << ", 10]]]}";
  }
  out << "]}";
  return out.str();
}

#define EXPECT_CODE(expr, expected_code, fragment)                               \
  do {                                                                           \
    const ::grpc::Status status_ = (expr);                                       \
    EXPECT_EQ(status_.error_code(), (expected_code)) << status_.error_message(); \
    EXPECT_TRUE(Contains(status_.error_message(), (fragment)))                   \
        << "'" << (fragment) << "' not in: " << status_.error_message();         \
  } while (false)

#define ASSERT_RPC(expr)                                                                 \
  do {                                                                                   \
    const ::grpc::Status status_ = (expr);                                               \
    ASSERT_TRUE(status_.ok()) << status_.error_code() << " " << status_.error_message(); \
  } while (false)

class AtlasServiceTest : public ::testing::Test {
 protected:
  // admin (first start) creates project "atlas"; bob is an editor there,
  // carol a viewer; "lung" exists at revision 1 (created by bob).
  void SetUp() override {
    options_.data_dir = dir_.path() / "data";
    options_.listen = "127.0.0.1:0";
    options_.solver = testing::WriteFakeSolver(dir_.path());
    options_.drain = std::chrono::milliseconds(2000);
    StartServer();
    std::ifstream token_file(options_.data_dir / "admin.token");
    std::getline(token_file, tokens_["admin"]);
    ASSERT_EQ(tokens_["admin"].size(), 64u);
    {
      // Users are made offline (as `pba-server admin create-user` does).
      std::unique_ptr<AtlasStore> store;
      ASSERT_TRUE(AtlasStore::Open(options_.data_dir, &store).ok());
      for (const char* name : {"bob", "carol", "dave"}) {
        ASSERT_TRUE(store->CreateUser(name, &tokens_[name]).ok());
      }
    }
    v1::CreateProjectRequest create;
    create.set_name("atlas");
    v1::Project project;
    ASSERT_RPC(Call("admin", &v1::AtlasService::Stub::CreateProject, create, &project));
    EXPECT_EQ(project.role(), v1::ADMIN);
    EXPECT_EQ(project.created_by(), "admin");
    SetRole("bob", v1::EDITOR);
    SetRole("carol", v1::VIEWER);
    lung_content_ = Contours(2000, 1);
    ASSERT_RPC(Create("bob", "lung", lung_content_));
  }

  void StartServer() {
    const Status status = PbaServer::Start(options_, &server_);
    ASSERT_TRUE(status.ok()) << status.ToString();
    channel_ = grpc::CreateChannel(server_->address(), grpc::InsecureChannelCredentials());
    stub_ = v1::AtlasService::NewStub(channel_);
  }

  void Authorize(grpc::ClientContext* context, const std::string& user) {
    context->AddMetadata("authorization", "Bearer " + tokens_[user]);
    context->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(20));
  }

  template <typename Request, typename Response>
  grpc::Status Call(const std::string& user,
                    grpc::Status (v1::AtlasService::Stub::*method)(grpc::ClientContext*,
                                                                   const Request&, Response*),
                    const Request& request, Response* response) {
    grpc::ClientContext context;
    Authorize(&context, user);
    return ((*stub_).*method)(&context, request, response);
  }

  void SetRole(const std::string& user, v1::Role role) {
    v1::SetRoleRequest request;
    request.set_project("atlas");
    request.set_user(user);
    request.set_role(role);
    v1::Member member;
    ASSERT_RPC(Call("admin", &v1::AtlasService::Stub::SetRole, request, &member));
  }

  grpc::Status Begin(const std::string& user, const std::string& content, v1::Upload* upload,
                     const std::string& announced_hash = "") {
    v1::BeginUploadRequest request;
    request.set_size_bytes(static_cast<int64_t>(content.size()));
    request.set_sha256(announced_hash.empty() ? Hash(content) : announced_hash);
    return Call(user, &v1::AtlasService::Stub::BeginUpload, request, upload);
  }

  // Sends content[from, to) in chunks of `chunk` bytes in one stream.
  grpc::Status Write(const std::string& user, const std::string& id, const std::string& content,
                     size_t from, size_t to, v1::Upload* upload, size_t chunk = kMiB) {
    grpc::ClientContext context;
    Authorize(&context, user);
    auto writer = stub_->WriteUpload(&context, upload);
    for (size_t offset = from; offset < to; offset += chunk) {
      v1::UploadChunk message;
      message.set_upload_id(id);
      message.set_offset(static_cast<int64_t>(offset));
      message.set_data(content.substr(offset, std::min(chunk, to - offset)));
      if (!writer->Write(message)) break;
    }
    writer->WritesDone();
    return writer->Finish();
  }

  // A complete upload of `content`; its id.
  std::string Upload(const std::string& user, const std::string& content) {
    v1::Upload upload;
    EXPECT_TRUE(Begin(user, content, &upload).ok());
    EXPECT_TRUE(Write(user, upload.id(), content, 0, content.size(), &upload).ok());
    EXPECT_EQ(upload.received_bytes(), static_cast<int64_t>(content.size()));
    return upload.id();
  }

  grpc::Status Create(const std::string& user, const std::string& name, const std::string& content,
                      v1::Revision* revision = nullptr,
                      v1::GeometryFormat format = v1::CONTOURS_JSON) {
    v1::CreateStructureRequest request;
    request.set_project("atlas");
    request.set_name(name);
    request.set_format(format);
    request.mutable_metadata()->set_group_path("thorax");
    request.mutable_metadata()->set_material_json("{\"model\": \"neo_hookean\"}");
    request.set_upload_id(Upload(user, content));
    request.set_message("first outline");
    v1::Revision ignored;
    return Call(user, &v1::AtlasService::Stub::CreateStructure, request,
                revision != nullptr ? revision : &ignored);
  }

  grpc::Status Acquire(const std::string& user, v1::Lock* lock,
                       const std::string& structure = "lung") {
    v1::AcquireLockRequest request;
    request.set_project("atlas");
    request.set_structure(structure);
    request.set_lease_seconds(60);
    return Call(user, &v1::AtlasService::Stub::AcquireLock, request, lock);
  }

  grpc::Status Release(const std::string& user, const std::string& lock_id) {
    v1::ReleaseLockRequest request;
    request.set_lock_id(lock_id);
    v1::ReleaseLockResponse response;
    return Call(user, &v1::AtlasService::Stub::ReleaseLock, request, &response);
  }

  grpc::Status Commit(const std::string& user, const std::string& lock_id, int64_t base,
                      const std::string& content, v1::Revision* revision = nullptr,
                      const std::string& structure = "lung",
                      v1::GeometryFormat format = v1::CONTOURS_JSON) {
    v1::CommitStructureRequest request;
    request.set_project("atlas");
    request.set_structure(structure);
    request.set_lock_id(lock_id);
    request.set_base_revision(base);
    request.set_format(format);
    request.set_upload_id(Upload(user, content));
    request.set_message("edit by " + user);
    v1::Revision ignored;
    return Call(user, &v1::AtlasService::Stub::CommitStructure, request,
                revision != nullptr ? revision : &ignored);
  }

  v1::Structure Get(const std::string& structure = "lung") {
    v1::GetStructureRequest request;
    request.set_project("atlas");
    request.set_structure(structure);
    v1::Structure response;
    EXPECT_TRUE(Call("carol", &v1::AtlasService::Stub::GetStructure, request, &response).ok());
    return response;
  }

  // Downloads from `offset`; with `max_chunks` > 0 the stream is cancelled
  // after that many chunks.
  grpc::Status Download(const std::string& user, int64_t revision, int64_t offset,
                        std::string* data, int max_chunks = 0) {
    grpc::ClientContext context;
    Authorize(&context, user);
    v1::DownloadGeometryRequest request;
    request.set_project("atlas");
    request.set_structure("lung");
    request.set_revision(revision);
    request.set_offset(offset);
    auto reader = stub_->DownloadGeometry(&context, request);
    v1::DataChunk chunk;
    int chunks = 0;
    int64_t next = offset;
    while (reader->Read(&chunk)) {
      EXPECT_LE(chunk.data().size(), kMiB);
      EXPECT_EQ(chunk.offset(), next);
      next += static_cast<int64_t>(chunk.data().size());
      data->append(chunk.data());
      if (max_chunks > 0 && ++chunks == max_chunks) {
        context.TryCancel();
        break;
      }
    }
    return reader->Finish();
  }

  std::vector<v1::AuditEntry> Audit() {
    v1::ListAuditRequest request;
    request.set_project("atlas");
    request.set_page_size(1000);
    v1::ListAuditResponse response;
    EXPECT_TRUE(Call("carol", &v1::AtlasService::Stub::ListAudit, request, &response).ok());
    return {response.entries().begin(), response.entries().end()};
  }

  TempDir dir_;
  ServerOptions options_;
  std::unique_ptr<PbaServer> server_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::AtlasService::Stub> stub_;
  std::map<std::string, std::string> tokens_;
  std::string lung_content_;
};

}  // namespace pba::service_test
