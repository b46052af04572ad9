// `pba project remove-member`: the project command added after the others,
// which atlas_commands.h declares (all of them are in project_commands.cc).
#pragma once

#include <string>

#include "connection.h"

namespace pba::cli {

// Removes `user` from `project` (project admins only). The locks they held
// there are released; prints which. The last admin cannot be removed
// (exit 9, kExitConflict, as for `pba project role`).
int RemoveMember(Connection& connection, const std::string& project, const std::string& user);

}  // namespace pba::cli
