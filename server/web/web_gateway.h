// The gRPC calls the web API makes (web_server.h), by "Service/Method":
// each parses its JSON request into the call's protobuf message, makes the
// call on the in-process channel with the caller's context (their token),
// and prints the response as JSON with the proto field names. Only the
// calls a page needs are here: reading projects, structures, revisions,
// diffs, snapshots, the audit log and jobs; the small actions (a lock taken
// and released, metadata through its etag, a snapshot tagged, a job
// cancelled). Geometry is edited with the CLI, and nothing else is reachable
// from a browser.
#pragma once

#include <grpcpp/channel.h>
#include <grpcpp/client_context.h>

#include <functional>
#include <map>
#include <memory>
#include <string>

namespace pba {

using GatewayCall = std::function<grpc::Status(
    grpc::ClientContext* context, const std::string& json_request, std::string* json_response)>;

class WebGateway {
 public:
  explicit WebGateway(std::shared_ptr<grpc::Channel> channel);

  // The call named "Service/Method" (e.g. "AtlasService/ListStructures");
  // nullptr when the web may not make it.
  const GatewayCall* Find(const std::string& name) const;
  // The channel the calls are made on (for the streaming ones the routes
  // make themselves).
  const std::shared_ptr<grpc::Channel>& channel() const { return channel_; }

 private:
  std::shared_ptr<grpc::Channel> channel_;
  std::map<std::string, GatewayCall> calls_;
};

}  // namespace pba
