// The `pba login`, `pba project ...` and `pba atlas ...` commands: the shared
// atlas repository (pba.v1.AtlasService). Each returns the process exit code
// (exit_codes.h) and prints human text, or JSON with --json.
//
// Editing a structure:
//   pba atlas checkout -p P NAME [-o FILE] [--hold]   lock it, download its head
//   (edit FILE)
//   pba atlas commit FILE -m "why"                     upload, commit, unlock
// checkout writes FILE.pba-checkout beside FILE (server, project, structure,
// lock id, base revision, format); commit reads it, so the commit is made on
// the revision that was checked out and is refused (exit 9, head named) if
// someone else's landed first. --hold keeps the lease alive until Ctrl-C,
// then unlocks.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "connection.h"

namespace CLI {
class App;
}

namespace pba::cli {

class CommandContext;

// Adds `pba atlas ...` to `app`: the structure commands of
// atlas_commands.cc, then the three below.
void RegisterAtlasCommands(CLI::App& app, CommandContext& context);
// Adds `pba atlas snapshot create|list|show|export` to `atlas`
// (snapshot_commands.cc).
void RegisterSnapshotCommands(CLI::App& atlas, CommandContext& context);
// Adds `pba atlas import|export` to `atlas` (import_commands.cc).
void RegisterImportExportCommands(CLI::App& atlas, CommandContext& context);
// Adds `pba atlas tag|audit|watch` to `atlas` (snapshot_commands.cc).
void RegisterTagAuditWatchCommands(CLI::App& atlas, CommandContext& context);

struct PageArgs {
  int page_size = 50;
  std::string page_token;
  bool all = false;
};

struct LoginArgs {
  std::string token;
  std::string token_file;  // e.g. the server's DATA/admin.token
};

struct StructureArgs {
  std::string project;
  std::string structure;
};

struct CreateStructureArgs {
  StructureArgs target;
  std::string file;
  std::string format;  // contours_json, nifti, stl, obj, vtk, derived; default from the extension
  std::string colour;  // "R,G,B"
  std::string group;
  std::string material;  // JSON, or @FILE
  std::string message;
  std::string request_id;  // --request-id; a fresh one when empty
};

struct CheckoutArgs {
  StructureArgs target;
  std::string out;  // default NAME.<extension of its format>
  int lease_s = 300;
  bool hold = false;
  // Replace an `out` holding content the server does not have (by default
  // it is kept as OUT.mine).
  bool force = false;
};

struct CommitArgs {
  std::string file;
  std::string message;
  std::string material;  // JSON or @FILE; empty keeps the head's
  bool keep_lock = false;
};

struct RevertArgs {
  StructureArgs target;
  int64_t to = 0;
  std::string message;
};

struct MetadataArgs {
  StructureArgs target;
  std::optional<std::string> colour, group, material;
  std::string message;
};

struct DownloadArgs {
  StructureArgs target;
  int64_t revision = 0;  // 0: head
  std::string out;
};

// `pba atlas import` (import_commands.cc).
struct ImportArgs {
  std::string project;
  bool synthetic = false;
  std::string plates;        // a plate directory
  std::string labels;        // a label volume
  std::string colour_table;  // with --labels
  std::vector<std::string> structures;
  std::string snapshot_name;
  std::string message;
  std::string request_id;
  bool wait = true;
};
int ImportAtlas(Connection& connection, const ImportArgs& args);
// `pba atlas export`: ExportSnapshot under the verb people look for.
int ExportAtlas(Connection& connection, const std::string& project, const std::string& snapshot,
                const std::string& dir);

int Login(Connection& connection, const LoginArgs& args);
int Logout(Connection& connection);
int WhoAmI(Connection& connection);

// `request_id` (--request-id) makes a rerun return the project the first run
// made; a fresh one is sent when empty. So for the other creates.
int CreateProject(Connection& connection, const std::string& name, const std::string& request_id);
int ListProjects(Connection& connection, const PageArgs& page);
int SetRole(Connection& connection, const std::string& project, const std::string& user,
            const std::string& role);

int ListStructures(Connection& connection, const std::string& project, const PageArgs& page);
int ShowStructure(Connection& connection, const StructureArgs& target);
int History(Connection& connection, const StructureArgs& target, const PageArgs& page);
int CreateStructure(Connection& connection, const CreateStructureArgs& args);
int Checkout(Connection& connection, const CheckoutArgs& args);
// Locks a structure without downloading it (args.out unused): to keep it
// from changing, and others' commits from overlapping it, while you work
// elsewhere; --hold renews the lease until Ctrl-C, then releases it.
int LockStructure(Connection& connection, const CheckoutArgs& args);
int Commit(Connection& connection, const CommitArgs& args);
// `what` is a checked-out file (its .pba-checkout names the lock) or a lock id.
int Unlock(Connection& connection, const std::string& what);
int BreakLock(Connection& connection, const StructureArgs& target, const std::string& reason);
int Revert(Connection& connection, const RevertArgs& args);
int SetMetadata(Connection& connection, const MetadataArgs& args);
int Download(Connection& connection, const DownloadArgs& args);
// What changed from revision `from` to `to` (0, 0: the head's parent to the
// head).
int Diff(Connection& connection, const StructureArgs& target, int64_t from, int64_t to);

// An empty `name` leaves the server to name it by its UTC time.
int CreateSnapshot(Connection& connection, const std::string& project, const std::string& name,
                   const std::string& request_id);
int TagSnapshot(Connection& connection, const std::string& project, int64_t id,
                const std::string& tag);
int ShowSnapshot(Connection& connection, const std::string& project, const std::string& snapshot);
int ListSnapshots(Connection& connection, const std::string& project, const PageArgs& page);
// Downloads every structure a snapshot pins into `dir` (created): one file
// per structure named by it and its format, and manifest.json with the
// snapshot and each structure's revision, metadata and SHA-256. `dir` must
// not exist yet or be empty: an export is whole or absent.
int ExportSnapshot(Connection& connection, const std::string& project, const std::string& which,
                   const std::string& dir);
int Audit(Connection& connection, const std::string& project, const PageArgs& page);
// Prints the project's events until interrupted, or after `count` events
// (0: no limit) not counting the READY one.
int Watch(Connection& connection, const std::string& project, int count);

}  // namespace pba::cli
