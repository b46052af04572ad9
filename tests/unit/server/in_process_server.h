// A real PbaServer on 127.0.0.1:0 in the test process, with the fake
// pba-solve (server_test_support.h), a channel to it, both services' stubs
// and the first start's admin token; calls with a token, uploads. The
// fixtures that test jobs and rights through the wire derive from it.
#pragma once

#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <memory>
#include <string>

#include "app/pba_server.h"
#include "core/sha256.h"
#include "pba/v1/atlas.grpc.pb.h"
#include "pba/v1/job.grpc.pb.h"
#include "unit/server/server_test_support.h"

namespace pba::testing {

class InProcessServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    options_.data_dir = dir_.path() / "data";
    options_.listen = "127.0.0.1:0";
    options_.solver = WriteFakeSolver(dir_.path());
    options_.kill_grace = std::chrono::milliseconds(1000);
    options_.drain = std::chrono::milliseconds(2000);
    const Status status = PbaServer::Start(options_, &server_);
    ASSERT_TRUE(status.ok()) << status.ToString();
    channel_ = grpc::CreateChannel(server_->address(), grpc::InsecureChannelCredentials());
    jobs_ = v1::JobService::NewStub(channel_);
    atlas_ = v1::AtlasService::NewStub(channel_);
    std::ifstream(options_.data_dir / "admin.token") >> admin_;
  }

  // f(context) with `token` in the call's metadata.
  template <typename F>
  grpc::Status Call(const std::string& token, F f) {
    grpc::ClientContext context;
    context.AddMetadata("authorization", "Bearer " + token);
    return f(&context);
  }

  // `bytes` uploaded as `token` in one chunk; the upload id.
  std::string Upload(const std::string& token, const std::string& bytes) {
    v1::BeginUploadRequest begin;
    begin.set_size_bytes(static_cast<int64_t>(bytes.size()));
    begin.set_sha256(Sha256Hex(bytes));
    v1::Upload upload;
    EXPECT_TRUE(Call(token, [&](grpc::ClientContext* c) {
                  return atlas_->BeginUpload(c, begin, &upload);
                }).ok());
    grpc::ClientContext context;
    context.AddMetadata("authorization", "Bearer " + token);
    v1::Upload done;
    auto writer = atlas_->WriteUpload(&context, &done);
    v1::UploadChunk chunk;
    chunk.set_upload_id(upload.id());
    chunk.set_data(bytes);
    writer->Write(chunk);
    writer->WritesDone();
    EXPECT_TRUE(writer->Finish().ok());
    return upload.id();
  }

  TempDir dir_;
  ServerOptions options_;
  std::unique_ptr<PbaServer> server_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::JobService::Stub> jobs_;
  std::unique_ptr<v1::AtlasService::Stub> atlas_;
  std::string admin_;  // the first start's admin (a server admin)
};

}  // namespace pba::testing
