// Connection: the client's channel to pba-server and the translation of RPC
// failures into messages and exit codes.
#pragma once

#include <grpcpp/grpcpp.h>

#include <chrono>
#include <memory>
#include <string>

#include "exit_codes.h"
#include "pba/v1/atlas.grpc.pb.h"
#include "pba/v1/job.grpc.pb.h"

namespace pba::cli {

struct GlobalOptions {
  std::string server = "127.0.0.1:50051";  // --server, or PBA_SERVER
  bool json = false;                       // --json: machine-readable output
  double timeout_s = 30;                   // deadline of each unary call
  // Access token sent as `authorization: Bearer <token>`; by default the
  // one `pba login` stored for the server, or PBA_TOKEN (credentials.h).
  std::string token;
  // TLS: the PEM certificate of the authority that signed the server's (or
  // the server's own, self-signed); `tls` alone uses the system's roots.
  // Default from PBA_TLS_CA.
  std::string tls_ca;
  bool tls = false;
};

class Connection {
 public:
  explicit Connection(const GlobalOptions& options);

  v1::JobService::Stub& jobs() { return *jobs_; }
  v1::AtlasService::Stub& atlas() { return *atlas_; }
  const GlobalOptions& options() const { return options_; }
  // Contexts carry the access token, if there is one.
  // A context with the unary deadline set.
  std::unique_ptr<grpc::ClientContext> UnaryContext() const;
  // A context for a stream: no deadline, but fails fast if the server is absent.
  std::unique_ptr<grpc::ClientContext> StreamContext() const;

  // Prints "pba: <what>: <reason>" to stderr and returns the exit code for
  // `status`; an unreachable server is named by its address. A failed
  // precondition means "no result yet" for jobs (kExitNotReady) and a lock
  // problem for the atlas (kExitConflict): the caller says which.
  int Fail(const std::string& what, const grpc::Status& status,
           int failed_precondition = kExitNotReady) const;

 private:
  GlobalOptions options_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::JobService::Stub> jobs_;
  std::unique_ptr<v1::AtlasService::Stub> atlas_;
};

}  // namespace pba::cli
