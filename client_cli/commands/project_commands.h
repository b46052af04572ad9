// The registration of `pba login`, `logout`, `whoami` and `pba project ...`,
// and `pba project remove-member`: the project command added after the
// others, which atlas_commands.h declares (all of them are in
// project_commands.cc).
#pragma once

#include <string>

#include "connection.h"

namespace CLI {
class App;
}

namespace pba::cli {

class CommandContext;

// Adds `pba login`, `pba logout` and `pba whoami` to `app`.
void RegisterLoginCommands(CLI::App& app, CommandContext& context);
// Adds `pba project create|list|role|remove-member` to `app`.
void RegisterProjectCommands(CLI::App& app, CommandContext& context);

// Removes `user` from `project` (project admins only). The locks they held
// there are released; prints which. The last admin cannot be removed
// (exit 9, kExitConflict, as for `pba project role`).
int RemoveMember(Connection& connection, const std::string& project, const std::string& user);

}  // namespace pba::cli
