// Who makes a call: the metadata `authorization: Bearer <token>` checked
// against the users of the atlas store. Every service of pba-server
// authenticates its calls through here.
#pragma once

#include <grpcpp/server_context.h>

#include <string>

#include "pba/status.h"
#include "store/atlas_store.h"

namespace pba {

// *user is the token's user; kUnauthenticated without the metadata, with
// another scheme than Bearer, or with a token no user has. The messages
// never contain the token.
Status CallUser(AtlasStore& users, const grpc::ServerContext& context, std::string* user);

}  // namespace pba
