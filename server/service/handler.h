// The skeleton every pba-server RPC handler shares, written once: who calls
// (call_auth.h), the handler's own work, and the status that goes back,
// with one log line for each refusal. A handler is then
//
//   grpc::Status AtlasServiceImpl::GetStructure(grpc::ServerContext* context,
//                                               const v1::GetStructureRequest* request,
//                                               v1::Structure* response) {
//     return Handle(store_, "GetStructure", *context, [&](const Caller& caller) -> RpcStatus {
//       StructureInfo info;
//       PBA_RETURN_IF_ERROR(store_.GetStructure(caller.user, {...}, &info));
//       StructureToProto(info, response);
//       return Status::Ok();
//     });
//   }
//
// Rights are not checked here: they are the store's (atlas_store.h) or the
// handler's (JobServiceImpl::LoadVisibleJob), since they depend on what the
// request names. Streaming handlers run their loops inside the body too.
#pragma once

#include <grpcpp/server_context.h>
#include <grpcpp/support/status.h>

#include <string>
#include <utility>

#include "pba/status.h"
#include "service/call_auth.h"
#include "store/atlas_store.h"

namespace pba {

// The one translation of a Status into the gRPC status a client gets
// (google.rpc codes; the message is Status::ToString(), "field: message"):
// every code to the gRPC code of the same name (kOutOfRange OUT_OF_RANGE,
// kResourceExhausted RESOURCE_EXHAUSTED, ...) but kNumerical, kIo and
// kInternal, which are INTERNAL.
grpc::Status ToGrpcStatus(const Status& status);

// The code's name as gRPC spells it ("PERMISSION_DENIED"; "ERROR" for
// codes PBA never answers).
const char* GrpcCodeName(grpc::StatusCode code);

// What a handler's body returns: a Status (sent as ToGrpcStatus makes it),
// or, for a code Status lacks (DATA_LOSS, UNAVAILABLE) or a message that
// must not name a field, a grpc::Status as it is. Both convert implicitly, so a body may `return
// status;`, `return grpc::Status(code, message);` and use PBA_RETURN_IF_ERROR.
class RpcStatus {
 public:
  RpcStatus() = default;
  RpcStatus(const Status& status) : status_(ToGrpcStatus(status)) {}  // NOLINT(runtime/explicit)
  RpcStatus(grpc::Status status) : status_(std::move(status)) {}      // NOLINT(runtime/explicit)

  // A stream that ends because its client went away or cancelled, or the
  // server is stopping: no refusal, so not logged.
  static RpcStatus StreamEnded(grpc::StatusCode code, std::string message) {
    RpcStatus ended(grpc::Status(code, std::move(message)));
    ended.logged_ = false;
    return ended;
  }

  bool ok() const { return status_.ok(); }
  const grpc::Status& status() const { return status_; }
  // Whether a failure is logged (all but StreamEnded ones).
  bool logged() const { return logged_; }

 private:
  grpc::Status status_;
  bool logged_ = true;
};

// The status a call ends with; a failure but a StreamEnded one is logged as
// "<rpc>: <CODE> <message>" (no message carries a token).
grpc::Status FinishCall(const char* rpc, const RpcStatus& status);

// The handler skeleton: authenticates the call against `users`
// (UNAUTHENTICATED without a valid token or for a disabled user, and then
// `body` does not run), runs body(caller) and ends the call with what it
// returned (FinishCall).
template <typename Body>
grpc::Status Handle(AtlasStore& users, const char* rpc, const grpc::ServerContext& context,
                    Body&& body) {
  Caller caller;
  const Status authenticated = CallUser(users, context, &caller);
  if (!authenticated.ok()) return FinishCall(rpc, authenticated);
  const Caller& who = caller;
  return FinishCall(rpc, std::forward<Body>(body)(who));
}

}  // namespace pba
