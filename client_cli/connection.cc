#include "connection.h"

#include <cstdio>
#include <fstream>
#include <sstream>

#include "exit_codes.h"

namespace pba::cli {

Connection::Connection(const GlobalOptions& options) : options_(options) {
  grpc::ChannelArguments args;
  // Fail quickly, not after the default 20 s of reconnect back-off.
  args.SetInt(GRPC_ARG_INITIAL_RECONNECT_BACKOFF_MS, 500);
  args.SetInt(GRPC_ARG_MAX_RECONNECT_BACKOFF_MS, 2000);
  std::shared_ptr<grpc::ChannelCredentials> credentials = grpc::InsecureChannelCredentials();
  if (options_.tls || !options_.tls_ca.empty()) {
    grpc::SslCredentialsOptions ssl;
    if (!options_.tls_ca.empty()) {
      std::ifstream in(options_.tls_ca);
      std::stringstream pem;
      pem << in.rdbuf();
      ssl.pem_root_certs = pem.str();
    }
    credentials = grpc::SslCredentials(ssl);
  }
  channel_ = grpc::CreateCustomChannel(options_.server, credentials, args);
  jobs_ = v1::JobService::NewStub(channel_);
  atlas_ = v1::AtlasService::NewStub(channel_);
}

std::unique_ptr<grpc::ClientContext> Connection::UnaryContext() const {
  auto context = std::make_unique<grpc::ClientContext>();
  if (!options_.token.empty()) context->AddMetadata("authorization", "Bearer " + options_.token);
  context->set_deadline(std::chrono::system_clock::now() +
                        std::chrono::milliseconds(static_cast<int64_t>(options_.timeout_s * 1000)));
  return context;
}

std::unique_ptr<grpc::ClientContext> Connection::StreamContext() const {
  auto context = std::make_unique<grpc::ClientContext>();
  if (!options_.token.empty()) context->AddMetadata("authorization", "Bearer " + options_.token);
  context->set_wait_for_ready(false);
  return context;
}

int Connection::Fail(const std::string& what, const grpc::Status& status,
                     int failed_precondition) const {
  switch (status.error_code()) {
    case grpc::StatusCode::UNAVAILABLE:
      std::fprintf(stderr,
                   "pba: cannot reach pba-server at %s (%s). Is it running? Start one with "
                   "`pba-server --data DIR`, or point --server (or PBA_SERVER) at it.\n",
                   options_.server.c_str(), status.error_message().c_str());
      return kExitUnavailable;
    case grpc::StatusCode::DEADLINE_EXCEEDED:
      std::fprintf(stderr, "pba: %s: pba-server at %s did not answer within %.0f s\n", what.c_str(),
                   options_.server.c_str(), options_.timeout_s);
      return kExitUnavailable;
    case grpc::StatusCode::NOT_FOUND:
      std::fprintf(stderr, "pba: %s: %s\n", what.c_str(), status.error_message().c_str());
      return kExitNotFound;
    case grpc::StatusCode::INVALID_ARGUMENT:
    case grpc::StatusCode::OUT_OF_RANGE:
      std::fprintf(stderr, "pba: %s: %s\n", what.c_str(), status.error_message().c_str());
      return kExitInvalid;
    case grpc::StatusCode::FAILED_PRECONDITION:
      std::fprintf(stderr, "pba: %s: %s\n", what.c_str(), status.error_message().c_str());
      return failed_precondition;
    case grpc::StatusCode::ABORTED:
    case grpc::StatusCode::ALREADY_EXISTS:
      std::fprintf(stderr, "pba: %s: %s\n", what.c_str(), status.error_message().c_str());
      return kExitConflict;
    case grpc::StatusCode::UNAUTHENTICATED:
      std::fprintf(stderr,
                   "pba: %s: %s. Log in with `pba login --token TOKEN` (an admin creates "
                   "users with `pba-server admin create-user`), or set PBA_TOKEN.\n",
                   what.c_str(), status.error_message().c_str());
      return kExitDenied;
    case grpc::StatusCode::PERMISSION_DENIED:
      std::fprintf(stderr, "pba: %s: %s\n", what.c_str(), status.error_message().c_str());
      return kExitDenied;
    default:
      std::fprintf(stderr, "pba: %s: %s (%d)\n", what.c_str(), status.error_message().c_str(),
                   static_cast<int>(status.error_code()));
      return kExitError;
  }
}

}  // namespace pba::cli
