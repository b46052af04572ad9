#include "service/call_auth.h"

#include <string_view>

namespace pba {
namespace {

constexpr std::string_view kBearer = "bearer ";

// The auth scheme is case-insensitive (RFC 7235 section 2.1).
bool StartsWithBearer(std::string_view value) {
  if (value.size() < kBearer.size()) return false;
  for (size_t i = 0; i < kBearer.size(); ++i) {
    const char c = value[i];
    if ((c >= 'A' && c <= 'Z' ? static_cast<char>(c - 'A' + 'a') : c) != kBearer[i]) return false;
  }
  return true;
}

}  // namespace

Status CallUser(AtlasStore& users, const grpc::ServerContext& context, Caller* caller) {
  const auto& metadata = context.client_metadata();
  const auto it = metadata.find("authorization");
  if (it == metadata.end()) {
    return Status::Unauthenticated(
        "no credentials: send the metadata 'authorization: Bearer <token>'");
  }
  const std::string_view value(it->second.data(), it->second.size());
  if (!StartsWithBearer(value)) {
    return Status::Unauthenticated("the authorization metadata must be 'Bearer <token>'");
  }
  return users.Authenticate(std::string(value.substr(kBearer.size())), &caller->user,
                            &caller->server_admin);
}

}  // namespace pba
