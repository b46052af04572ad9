// BenchServer: a PbaServer in-process on 127.0.0.1:0 with a fresh data
// directory, for server_bench: the admin token of its first start, stubs on
// one channel, and the calls the benchmarks share (a project, uploads,
// structures). Every call carries the admin token, the job service's too.
#pragma once

#include <grpcpp/grpcpp.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "app/pba_server.h"
#include "core/sha256.h"
#include "pba/v1/atlas.grpc.pb.h"
#include "pba/v1/job.grpc.pb.h"
#include "unit/server/temp_dir.h"

namespace pba::testing {

constexpr char kProject[] = "bench";
constexpr size_t kMiB = 1 << 20;

// "what: CODE message", for SkipWithError.
inline std::string ErrorText(const char* what, const grpc::Status& status) {
  return std::string(what) + ": " + std::to_string(status.error_code()) + " " +
         status.error_message();
}

// A PbaServer in-process on 127.0.0.1:0 with a fresh data directory, the
// admin token of its first start, and stubs on one channel.
class BenchServer {
 public:
  // `solver` is the pba-solve the jobs run; error() is empty when the
  // server is up.
  BenchServer(const std::filesystem::path& solver, int max_running) {
    // The server's per-job and first-start lines would bury the tables.
    spdlog::set_level(spdlog::level::warn);
    ServerOptions options;
    options.data_dir = dir_.path() / "data";
    options.listen = "127.0.0.1:0";
    options.solver = solver;
    options.max_running = max_running;
    options.solver_threads = 1;
    options.drain = std::chrono::milliseconds(2000);
    const Status status = PbaServer::Start(options, &server_);
    if (!status.ok()) {
      error_ = status.ToString();
      return;
    }
    std::ifstream token_file(options.data_dir / PbaServer::kAdminTokenFile);
    std::getline(token_file, token_);
    if (token_.size() != 64) {
      error_ = "no 64-character admin token in " + (options.data_dir / "admin.token").string();
      return;
    }
    channel_ = NewChannel();
    atlas_ = v1::AtlasService::NewStub(channel_);
    jobs_ = v1::JobService::NewStub(channel_);
  }

  const std::string& error() const { return error_; }
  const std::filesystem::path& dir() const { return dir_.path(); }
  const std::shared_ptr<grpc::Channel>& channel() const { return channel_; }
  v1::AtlasService::Stub& atlas() { return *atlas_; }
  v1::JobService::Stub& jobs() { return *jobs_; }

  // A channel with its own connection (a local subchannel pool), as a
  // separate client would have.
  std::shared_ptr<grpc::Channel> NewChannel() const {
    grpc::ChannelArguments args;
    args.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
    args.SetMaxReceiveMessageSize(8 * static_cast<int>(kMiB));
    return grpc::CreateCustomChannel(server_->address(), grpc::InsecureChannelCredentials(), args);
  }

  // The admin's credentials and a deadline.
  void Prepare(grpc::ClientContext* context,
               std::chrono::seconds deadline = std::chrono::seconds(60)) const {
    context->AddMetadata("authorization", "Bearer " + token_);
    context->set_deadline(std::chrono::system_clock::now() + deadline);
  }

  template <typename Stub, typename Request, typename Response>
  grpc::Status Call(Stub& stub,
                    grpc::Status (Stub::*method)(grpc::ClientContext*, const Request&, Response*),
                    const Request& request, Response* response) const {
    grpc::ClientContext context;
    Prepare(&context);
    return (stub.*method)(&context, request, response);
  }

  grpc::Status CreateProject() {
    v1::CreateProjectRequest request;
    request.set_name(kProject);
    v1::Project project;
    return Call(*atlas_, &v1::AtlasService::Stub::CreateProject, request, &project);
  }

  // BeginUpload and WriteUpload of `content` in 1 MiB chunks; the upload id.
  grpc::Status Upload(const std::string& content, const std::string& sha256,
                      std::string* upload_id) {
    v1::BeginUploadRequest begin;
    begin.set_size_bytes(static_cast<int64_t>(content.size()));
    begin.set_sha256(sha256);
    v1::Upload upload;
    grpc::Status status = Call(*atlas_, &v1::AtlasService::Stub::BeginUpload, begin, &upload);
    if (!status.ok()) return status;
    grpc::ClientContext context;
    Prepare(&context);
    auto writer = atlas_->WriteUpload(&context, &upload);
    v1::UploadChunk chunk;
    for (size_t offset = 0; offset < content.size(); offset += kMiB) {
      chunk.set_upload_id(upload.id());
      chunk.set_offset(static_cast<int64_t>(offset));
      chunk.set_data(content.data() + offset, std::min(kMiB, content.size() - offset));
      if (!writer->Write(chunk)) break;
    }
    writer->WritesDone();
    status = writer->Finish();
    if (status.ok() && upload.received_bytes() != static_cast<int64_t>(content.size())) {
      return grpc::Status(grpc::StatusCode::INTERNAL, "the upload is short");
    }
    *upload_id = upload.id();
    return status;
  }

  grpc::Status CreateStructure(const std::string& name, v1::GeometryFormat format,
                               const std::string& content) {
    const std::string hash = Sha256Hex(content);
    v1::CreateStructureRequest request;
    grpc::Status status = Upload(content, hash, request.mutable_upload_id());
    if (!status.ok()) return status;
    request.set_project(kProject);
    request.set_name(name);
    request.set_format(format);
    request.mutable_metadata()->set_group_path("cerebrum");
    request.set_message("benchmark structure");
    v1::Revision revision;
    return Call(*atlas_, &v1::AtlasService::Stub::CreateStructure, request, &revision);
  }

  grpc::Status GetStructure(const std::string& name, v1::Structure* structure) {
    v1::GetStructureRequest request;
    request.set_project(kProject);
    request.set_structure(name);
    return Call(*atlas_, &v1::AtlasService::Stub::GetStructure, request, structure);
  }

 private:
  TempDir dir_;
  std::unique_ptr<PbaServer> server_;
  std::string token_;
  std::string error_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::AtlasService::Stub> atlas_;
  std::unique_ptr<v1::JobService::Stub> jobs_;
};

}  // namespace pba::testing
