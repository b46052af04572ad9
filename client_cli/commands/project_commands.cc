// `pba login`, `logout`, `whoami` and `pba project ...` (atlas_commands.h,
// project_commands.h).
#include "commands/project_commands.h"

#include <CLI/CLI.hpp>
#include <cstdio>
#include <fstream>
#include <memory>

#include "commands/atlas_commands.h"
#include "commands/atlas_shared.h"
#include "commands/command_context.h"
#include "credentials.h"
#include "exit_codes.h"
#include "output.h"

namespace pba::cli {
namespace {

bool ParseRoleText(const std::string& text, v1::Role* role) {
  if (text == "viewer")
    *role = v1::VIEWER;
  else if (text == "editor")
    *role = v1::EDITOR;
  else if (text == "admin")
    *role = v1::ADMIN;
  else
    return false;
  return true;
}

}  // namespace

int Login(Connection& connection, const LoginArgs& args) {
  std::string token = args.token;
  if (!args.token_file.empty()) {
    std::ifstream in(args.token_file);
    if (!(in >> token)) {
      std::fprintf(stderr, "pba: cannot read a token from %s\n", args.token_file.c_str());
      return kExitError;
    }
  }
  if (token.empty()) {
    std::fprintf(stderr, "pba: login needs --token TOKEN or --token-file FILE\n");
    return kExitUsage;
  }
  GlobalOptions options = connection.options();
  options.token = token;
  Connection with_token(options);
  v1::User user;
  auto context = with_token.UnaryContext();
  grpc::Status status = with_token.atlas().WhoAmI(context.get(), v1::WhoAmIRequest(), &user);
  if (!status.ok()) return with_token.Fail("logging in to " + options.server, status);
  std::string error;
  if (!StoreToken(options.server, token, &error)) {
    std::fprintf(stderr, "pba: %s\n", error.c_str());
    return kExitError;
  }
  if (connection.options().json) {
    PrintJson(user);
  } else {
    std::printf("Logged in to %s as %s (token kept in %s)\n", options.server.c_str(),
                user.name().c_str(), CredentialsPath().c_str());
  }
  return kExitOk;
}

int Logout(Connection& connection) {
  std::string error;
  const bool had = ForgetToken(connection.options().server, &error);
  if (!error.empty()) {
    std::fprintf(stderr, "pba: %s\n", error.c_str());
    return kExitError;
  }
  std::printf(had ? "Logged out of %s\n" : "No token was kept for %s\n",
              connection.options().server.c_str());
  return kExitOk;
}

int WhoAmI(Connection& connection) {
  v1::User user;
  auto context = connection.UnaryContext();
  grpc::Status status = connection.atlas().WhoAmI(context.get(), v1::WhoAmIRequest(), &user);
  if (!status.ok()) return connection.Fail("who am I", status);
  if (connection.options().json) {
    PrintJson(user);
  } else {
    std::printf("%s on %s\n", user.name().c_str(), connection.options().server.c_str());
  }
  return kExitOk;
}

int ServerInfo(Connection& connection) {
  v1::ServerInfo info;
  auto context = connection.UnaryContext();
  grpc::Status status =
      connection.jobs().GetServerInfo(context.get(), v1::GetServerInfoRequest(), &info);
  if (!status.ok()) return connection.Fail("server info", status);
  if (connection.options().json) {
    PrintJson(info);
    return kExitOk;
  }
  const bool slurm = info.executor() == "slurm";
  std::printf("server %s\n", connection.options().server.c_str());
  if (slurm) {
    std::printf("executor: slurm (%s)\n",
                info.array_min() > 0 ? ("jobs handed over together go as one job array from " +
                                        std::to_string(info.array_min()))
                                           .c_str()
                                     : "each job its own Slurm job");
    std::printf("jobs in Slurm's hands at once: %d\n", info.max_running());
  } else {
    std::printf("executor: local (child processes of the server)\n");
    std::printf("jobs running at once: %d\n", info.max_running());
  }
  std::printf("jobs queued or running per user: %s\n",
              info.max_open_jobs() > 0 ? std::to_string(info.max_open_jobs()).c_str() : "no bound");
  std::printf("MPI ranks per job: at most %d\n", info.max_ranks());
  std::printf("time per job: %s\n",
              info.max_job_time_s() > 0
                  ? ("at most " + std::to_string(info.max_job_time_s()) + " s").c_str()
                  : "no limit");
  return kExitOk;
}

int CreateProject(Connection& connection, const std::string& name, const std::string& request_id) {
  v1::CreateProjectRequest request;
  request.set_name(name);
  request.set_request_id(RequestIdOr(request_id));
  v1::Project project;
  auto context = connection.UnaryContext();
  grpc::Status status = connection.atlas().CreateProject(context.get(), request, &project);
  if (!status.ok()) return connection.Fail("creating project " + name, status);
  if (connection.options().json) {
    PrintJson(project);
  } else {
    std::printf("Created project %s; you are its admin\n", project.name().c_str());
  }
  return kExitOk;
}

int ListProjects(Connection& connection, const PageArgs& page) {
  v1::ListProjectsResponse all;
  v1::ListProjectsRequest request;
  int code = FetchPages(connection, page, request, &v1::AtlasService::Stub::ListProjects,
                        &v1::ListProjectsResponse::mutable_projects, "listing projects", &all);
  if (code != kExitOk) return code;
  if (connection.options().json) {
    PrintJson(all);
    return kExitOk;
  }
  if (all.projects().empty()) {
    std::puts("No projects. Create one with: pba project create NAME");
    return kExitOk;
  }
  std::vector<std::vector<std::string>> rows = {{"PROJECT", "YOUR ROLE", "CREATED (UTC)", "BY"}};
  for (const auto& p : all.projects()) {
    rows.push_back({p.name(), RoleText(p.role()), FormatTime(p.create_time()), p.created_by()});
  }
  PrintTable(rows);
  MoreHint(all.next_page_token(), "pba project list");
  return kExitOk;
}

int SetRole(Connection& connection, const std::string& project, const std::string& user,
            const std::string& role) {
  v1::SetRoleRequest request;
  v1::Role parsed;
  if (!ParseRoleText(role, &parsed)) {
    std::fprintf(stderr, "pba: role must be viewer, editor or admin, not '%s'\n", role.c_str());
    return kExitUsage;
  }
  request.set_project(project);
  request.set_user(user);
  request.set_role(parsed);
  v1::Member member;
  auto context = connection.UnaryContext();
  grpc::Status status = connection.atlas().SetRole(context.get(), request, &member);
  if (!status.ok()) return connection.Fail("setting " + user + "'s role", status, kExitConflict);
  if (connection.options().json) {
    PrintJson(member);
  } else {
    std::printf("%s is %s in %s\n", member.user().c_str(), RoleText(member.role()).c_str(),
                member.project().c_str());
  }
  return kExitOk;
}

int RemoveMember(Connection& connection, const std::string& project, const std::string& user) {
  v1::RemoveMemberRequest request;
  request.set_project(project);
  request.set_user(user);
  v1::RemoveMemberResponse response;
  auto context = connection.UnaryContext();
  grpc::Status status = connection.atlas().RemoveMember(context.get(), request, &response);
  if (!status.ok()) {
    return connection.Fail("removing " + user + " from " + project, status, kExitConflict);
  }
  if (connection.options().json) {
    PrintJson(response);
    return kExitOk;
  }
  std::printf("%s is no longer a member of %s\n", user.c_str(), project.c_str());
  for (const std::string& structure : response.released_locks()) {
    std::printf("released their lock on %s\n", structure.c_str());
  }
  return kExitOk;
}

void RegisterLoginCommands(CLI::App& app, CommandContext& context) {
  auto login = std::make_shared<LoginArgs>();
  CLI::App* login_cmd =
      app.add_subcommand("login", "Check a token with the server and keep it for later commands");
  login_cmd->add_option("--token", login->token, "The access token");
  login_cmd
      ->add_option("--token-file", login->token_file,
                   "Read the token from a file (the server's DATA/admin.token, say)")
      ->check(CLI::ExistingFile);
  context.Add(login_cmd, [login](Connection& c) { return Login(c, *login); });
  context.Add(app.add_subcommand("logout", "Forget the token kept for the server"), Logout);
  context.Add(app.add_subcommand("whoami", "The user the kept token belongs to"), WhoAmI);
  context.Add(
      app.add_subcommand("server", "How the server runs jobs and the bounds a submit meets"),
      ServerInfo);
}

void RegisterProjectCommands(CLI::App& app, CommandContext& context) {
  CLI::App* project = AddCommandGroup(app, "project", "Create and list projects, set roles");

  struct CreateArgs {
    std::string name, request_id;
  };
  auto create = std::make_shared<CreateArgs>();
  CLI::App* create_cmd = project->add_subcommand("create", "Create a project (you are its admin)");
  create_cmd->add_option("name", create->name, "Project name")->required();
  AddRequestIdOption(create_cmd, &create->request_id, "project");
  context.Add(create_cmd, [create](Connection& c) {
    return CreateProject(c, create->name, create->request_id);
  });

  auto page = std::make_shared<PageArgs>();
  CLI::App* list_cmd = project->add_subcommand("list", "Projects you are a member of");
  AddPagingOptions(list_cmd, page.get());
  context.Add(list_cmd, [page](Connection& c) { return ListProjects(c, *page); });

  struct MemberArgs {
    std::string project, user, role;
  };
  auto role = std::make_shared<MemberArgs>();
  CLI::App* role_cmd =
      project->add_subcommand("role", "Give a user a role in a project (admins only)");
  role_cmd->add_option("project", role->project, "Project")->required();
  role_cmd->add_option("user", role->user, "User")->required();
  role_cmd->add_option("role", role->role, "viewer, editor or admin")->required();
  context.Add(role_cmd,
              [role](Connection& c) { return SetRole(c, role->project, role->user, role->role); });

  auto remove = std::make_shared<MemberArgs>();
  CLI::App* remove_cmd = project->add_subcommand(
      "remove-member", "Remove a user from a project, releasing their locks (admins only)");
  remove_cmd->add_option("project", remove->project, "Project")->required();
  remove_cmd->add_option("user", remove->user, "User")->required();
  context.Add(remove_cmd,
              [remove](Connection& c) { return RemoveMember(c, remove->project, remove->user); });
}

}  // namespace pba::cli
