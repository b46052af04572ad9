// Who makes a call: the metadata `authorization: Bearer <token>` checked
// against the users of the atlas store. Every service of pba-server
// authenticates its calls through here.
#pragma once

#include <grpcpp/server_context.h>

#include <string>

#include "pba/status.h"
#include "store/atlas_store.h"

namespace pba {

// Who makes a call, once authenticated.
struct Caller {
  std::string user;
  bool server_admin = false;  // sees and cancels every job (job_service.h)
};

// *caller is the token's user and whether they are a server admin;
// kUnauthenticated without the metadata, with another scheme than Bearer,
// with a token no user has, or for a disabled user. The store is read on
// every call (nothing is cached), so disabling a user takes effect at their
// next call, even in a server that was running. The messages never contain
// the token.
Status CallUser(AtlasStore& users, const grpc::ServerContext& context, Caller* caller);

}  // namespace pba
