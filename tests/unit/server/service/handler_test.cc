// Handle (server/service/handler.h), the skeleton every RPC handler runs
// through: who may reach the body, the one Status -> gRPC mapping, and the
// log line of a refusal. A ServerContext with injected metadata stands in
// for a call; the users are a real AtlasStore.
#include "service/handler.h"

#include <grpcpp/test/server_context_test_spouse.h>
#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <memory>
#include <sstream>
#include <string>
#include <utility>

#include "unit/server/temp_dir.h"

namespace pba {
namespace {

class RpcHandlerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(AtlasStore::Open(dir_.path(), &users_).ok());
    ASSERT_TRUE(users_->CreateUser("alice", &alice_).ok());
    ASSERT_TRUE(users_->CreateUser("root", &root_, /*server_admin=*/true).ok());
  }

  // Handle() for a call whose authorization metadata is `authorization`
  // (none if empty), with `body`; *ran says whether the body ran.
  template <typename Body>
  grpc::Status Call(const std::string& authorization, Body body, bool* ran) {
    grpc::ServerContext context;
    grpc::testing::ServerContextTestSpouse spouse(&context);
    if (!authorization.empty()) spouse.AddClientMetadata("authorization", authorization);
    *ran = false;
    return Handle(*users_, "TestRpc", context, [&](const Caller& caller) -> RpcStatus {
      *ran = true;
      return body(caller);
    });
  }

  // The body's status as the client gets it, called as alice.
  grpc::Status Returning(RpcStatus status) {
    bool ran = false;
    return Call(
        "Bearer " + alice_, [&](const Caller&) { return status; }, &ran);
  }

  testing::TempDir dir_;
  std::unique_ptr<AtlasStore> users_;
  std::string alice_, root_;
};

TEST_F(RpcHandlerTest, RefusesACallWithoutAValidTokenBeforeTheBody) {
  const std::string unknown(64, 'a');
  for (const std::string& authorization :
       {std::string(), "Basic " + alice_, "Bearer " + unknown, std::string("Bearer short")}) {
    bool ran = true;
    const grpc::Status status = Call(
        authorization, [](const Caller&) { return Status::Ok(); }, &ran);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAUTHENTICATED) << authorization;
    EXPECT_FALSE(ran) << authorization;
    EXPECT_EQ(status.error_message().find(alice_), std::string::npos) << status.error_message();
  }
}

TEST_F(RpcHandlerTest, RefusesADisabledUserBeforeTheBody) {
  ASSERT_TRUE(users_->SetUserDisabled("alice", true).ok());
  bool ran = true;
  const grpc::Status status = Call(
      "Bearer " + alice_, [](const Caller&) { return Status::Ok(); }, &ran);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_NE(status.error_message().find("is disabled"), std::string::npos)
      << status.error_message();
  EXPECT_FALSE(ran);
}

TEST_F(RpcHandlerTest, TheBodyGetsTheCaller) {
  Caller seen;
  bool ran = false;
  const auto keep = [&](const Caller& caller) {
    seen = caller;
    return Status::Ok();
  };
  // The scheme is case-insensitive (RFC 7235).
  EXPECT_TRUE(Call("bearer " + alice_, keep, &ran).ok());
  EXPECT_TRUE(ran);
  EXPECT_EQ(seen.user, "alice");
  EXPECT_FALSE(seen.server_admin);
  EXPECT_TRUE(Call("Bearer " + root_, keep, &ran).ok());
  EXPECT_EQ(seen.user, "root");
  EXPECT_TRUE(seen.server_admin);
}

TEST_F(RpcHandlerTest, EachStatusKindGivesItsGrpcCode) {
  EXPECT_TRUE(Returning(Status::Ok()).ok());
  const std::pair<Status, grpc::StatusCode> cases[] = {
      {Status::InvalidArgument("lease", "must be positive"), grpc::StatusCode::INVALID_ARGUMENT},
      {Status::FailedPrecondition("locked by bob"), grpc::StatusCode::FAILED_PRECONDITION},
      {Status::Cancelled("stop"), grpc::StatusCode::CANCELLED},
      {Status::NotFound("no such structure"), grpc::StatusCode::NOT_FOUND},
      {Status::AlreadyExists("tag exists"), grpc::StatusCode::ALREADY_EXISTS},
      {Status::Aborted("the head is revision 3"), grpc::StatusCode::ABORTED},
      {Status::PermissionDenied("viewer"), grpc::StatusCode::PERMISSION_DENIED},
      {Status::Unauthenticated("unknown token"), grpc::StatusCode::UNAUTHENTICATED},
      {Status::Numerical("diverged"), grpc::StatusCode::INTERNAL},
      {Status::Io("disk full"), grpc::StatusCode::INTERNAL},
      {Status::Internal("bug"), grpc::StatusCode::INTERNAL},
      // A position past what exists, a quota or pool that is full.
      {Status::OutOfRange("offset", "expected 10"), grpc::StatusCode::OUT_OF_RANGE},
      {Status::ResourceExhausted("upload_quota", "1000 open"),
       grpc::StatusCode::RESOURCE_EXHAUSTED},
      // A field alone decides nothing: these keep their own codes.
      {Status::InvalidArgument("offset", "must not be negative"),
       grpc::StatusCode::INVALID_ARGUMENT},
      {Status::FailedPrecondition("upload_quota", "x"), grpc::StatusCode::FAILED_PRECONDITION},
      {Status::InvalidArgument("upload_id", "required"), grpc::StatusCode::INVALID_ARGUMENT},
  };
  for (const auto& [status, code] : cases) {
    const grpc::Status sent = Returning(status);
    EXPECT_EQ(sent.error_code(), code) << status.ToString();
    EXPECT_EQ(sent.error_message(), status.ToString());
    // The same mapping where no call is involved.
    EXPECT_EQ(ToGrpcStatus(status).error_code(), code) << status.ToString();
  }
}

TEST_F(RpcHandlerTest, AGrpcStatusFromTheBodyGoesOutAsItIs) {
  for (const grpc::StatusCode code :
       {grpc::StatusCode::DATA_LOSS, grpc::StatusCode::OUT_OF_RANGE, grpc::StatusCode::UNAVAILABLE,
        grpc::StatusCode::INVALID_ARGUMENT}) {
    const grpc::Status sent = Returning(grpc::Status(code, "offset: as sent"));
    EXPECT_EQ(sent.error_code(), code);
    EXPECT_EQ(sent.error_message(), "offset: as sent");
  }
  const grpc::Status ended =
      Returning(RpcStatus::StreamEnded(grpc::StatusCode::CANCELLED, "the client went away"));
  EXPECT_EQ(ended.error_code(), grpc::StatusCode::CANCELLED);
  EXPECT_EQ(ended.error_message(), "the client went away");
}

// Every refusal is logged once, naming the RPC and the code, without the
// token; a stream its client ended is not a refusal.
TEST_F(RpcHandlerTest, LogsEachRefusalOnce) {
  std::ostringstream log;
  const std::shared_ptr<spdlog::logger> previous = spdlog::default_logger();
  spdlog::set_default_logger(std::make_shared<spdlog::logger>(
      "handler_test", std::make_shared<spdlog::sinks::ostream_sink_mt>(log)));
  bool ran = false;
  Call(
      "Bearer " + std::string(64, 'b'), [](const Caller&) { return Status::Ok(); }, &ran);
  Returning(Status::NotFound("job 42 not found"));
  Returning(Status::Ok());
  Returning(RpcStatus::StreamEnded(grpc::StatusCode::CANCELLED, "watch cancelled"));
  spdlog::set_default_logger(previous);

  const std::string text = log.str();
  EXPECT_NE(text.find("TestRpc: UNAUTHENTICATED unknown access token"), std::string::npos) << text;
  EXPECT_NE(text.find("TestRpc: NOT_FOUND job 42 not found"), std::string::npos) << text;
  EXPECT_EQ(text.find("watch cancelled"), std::string::npos) << text;
  EXPECT_EQ(text.find(std::string(64, 'b')), std::string::npos) << text;
  size_t lines = 0;
  for (char c : text) lines += c == '\n' ? 1 : 0;
  EXPECT_EQ(lines, 2u) << text;
}

}  // namespace
}  // namespace pba
