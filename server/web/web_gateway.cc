#include "web/web_gateway.h"

#include <google/protobuf/util/json_util.h>

#include "pba/v1/atlas.grpc.pb.h"
#include "pba/v1/job.grpc.pb.h"

namespace pba {
namespace {

// A unary call of `stub` as a GatewayCall. The stub is shared by every
// call of its service and outlives them (held by the lambda).
template <class Stub, class Request, class Response>
GatewayCall Unary(std::shared_ptr<Stub> stub,
                  grpc::Status (Stub::*method)(grpc::ClientContext*, const Request&, Response*)) {
  return [stub, method](grpc::ClientContext* context, const std::string& json_request,
                        std::string* json_response) {
    Request request;
    google::protobuf::util::JsonParseOptions parse;
    parse.ignore_unknown_fields = false;
    const auto parsed = google::protobuf::util::JsonStringToMessage(
        json_request.empty() ? "{}" : json_request, &request, parse);
    if (!parsed.ok()) {
      return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                          "the request is not a " + Request::descriptor()->full_name() + ": " +
                              std::string(parsed.message()));
    }
    Response response;
    const grpc::Status status = (stub.get()->*method)(context, request, &response);
    if (!status.ok()) return status;
    google::protobuf::util::JsonPrintOptions print;
    print.preserve_proto_field_names = true;
    // Printing a well-formed message cannot fail.
    (void)google::protobuf::util::MessageToJsonString(response, json_response, print);
    return status;
  };
}

}  // namespace

WebGateway::WebGateway(std::shared_ptr<grpc::Channel> channel) : channel_(std::move(channel)) {
  using Atlas = v1::AtlasService::Stub;
  using Jobs = v1::JobService::Stub;
  auto atlas = std::make_shared<Atlas>(channel_);
  auto jobs = std::make_shared<Jobs>(channel_);
  calls_ = {
      {"AtlasService/WhoAmI", Unary(atlas, &Atlas::WhoAmI)},
      {"AtlasService/ListProjects", Unary(atlas, &Atlas::ListProjects)},
      {"AtlasService/ListStructures", Unary(atlas, &Atlas::ListStructures)},
      {"AtlasService/GetStructure", Unary(atlas, &Atlas::GetStructure)},
      {"AtlasService/ListRevisions", Unary(atlas, &Atlas::ListRevisions)},
      {"AtlasService/GetRevision", Unary(atlas, &Atlas::GetRevision)},
      {"AtlasService/DiffRevisions", Unary(atlas, &Atlas::DiffRevisions)},
      {"AtlasService/ListSnapshots", Unary(atlas, &Atlas::ListSnapshots)},
      {"AtlasService/GetSnapshot", Unary(atlas, &Atlas::GetSnapshot)},
      {"AtlasService/ListAudit", Unary(atlas, &Atlas::ListAudit)},
      {"AtlasService/AcquireLock", Unary(atlas, &Atlas::AcquireLock)},
      {"AtlasService/ReleaseLock", Unary(atlas, &Atlas::ReleaseLock)},
      {"AtlasService/UpdateMetadata", Unary(atlas, &Atlas::UpdateMetadata)},
      {"AtlasService/TagSnapshot", Unary(atlas, &Atlas::TagSnapshot)},
      {"JobService/ListJobs", Unary(jobs, &Jobs::ListJobs)},
      {"JobService/GetJob", Unary(jobs, &Jobs::GetJob)},
      {"JobService/CancelJob", Unary(jobs, &Jobs::CancelJob)},
      {"JobService/GetServerInfo", Unary(jobs, &Jobs::GetServerInfo)},
  };
}

const GatewayCall* WebGateway::Find(const std::string& name) const {
  const auto it = calls_.find(name);
  return it == calls_.end() ? nullptr : &it->second;
}

}  // namespace pba
