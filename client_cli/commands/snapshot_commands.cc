// `pba atlas snapshot ...`, `tag`, `audit` and `watch` (atlas_commands.h).
#include <google/protobuf/struct.pb.h>
#include <sys/stat.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "codec/yaml_codec.h"
#include "commands/atlas_commands.h"
#include "commands/atlas_shared.h"
#include "commands/command_context.h"
#include "core/atomic_write.h"
#include "exit_codes.h"
#include "files.h"
#include "output.h"

namespace pba::cli {
namespace fs = std::filesystem;
namespace {

constexpr char kManifestName[] = "manifest.json";

// The process's umask (reading it means setting it; set straight back).
mode_t CurrentUmask() {
  const mode_t mask = ::umask(0);
  ::umask(mask);
  return mask;
}

}  // namespace

int CreateSnapshot(Connection& connection, const std::string& project, const std::string& name,
                   const std::string& request_id) {
  v1::CreateSnapshotRequest request;
  request.set_project(project);
  // Unnamed, the server names it by its time. Left to the server so that a
  // rerun with the same --request-id asks for the same thing.
  request.set_name(name);
  request.set_request_id(RequestIdOr(request_id));
  v1::Snapshot snapshot;
  auto context = connection.UnaryContext();
  grpc::Status status = connection.atlas().CreateSnapshot(context.get(), request, &snapshot);
  if (!status.ok()) return connection.Fail("snapshotting " + project, status);
  if (connection.options().json) {
    PrintJson(snapshot);
  } else {
    std::printf(
        "Snapshot %lld of %s pins %d structure%s; tag it with: pba atlas tag -p %s %lld TAG\n",
        static_cast<long long>(snapshot.id()), project.c_str(), snapshot.members_size(),
        snapshot.members_size() == 1 ? "" : "s", project.c_str(),
        static_cast<long long>(snapshot.id()));
  }
  return kExitOk;
}

int TagSnapshot(Connection& connection, const std::string& project, int64_t id,
                const std::string& tag) {
  v1::TagSnapshotRequest request;
  request.set_project(project);
  request.set_snapshot_id(id);
  request.set_tag(tag);
  v1::Snapshot snapshot;
  auto context = connection.UnaryContext();
  grpc::Status status = connection.atlas().TagSnapshot(context.get(), request, &snapshot);
  if (!status.ok()) return connection.Fail("tagging snapshot " + std::to_string(id), status);
  if (connection.options().json) {
    PrintJson(snapshot);
  } else {
    std::printf("Snapshot %lld of %s is tagged %s\n", static_cast<long long>(id), project.c_str(),
                tag.c_str());
  }
  return kExitOk;
}

int ShowSnapshot(Connection& connection, const std::string& project, const std::string& which) {
  v1::GetSnapshotRequest request;
  request.set_project(project);
  request.set_snapshot(which);
  v1::Snapshot s;
  auto context = connection.UnaryContext();
  grpc::Status status = connection.atlas().GetSnapshot(context.get(), request, &s);
  if (!status.ok()) return connection.Fail("snapshot " + which + " of " + project, status);
  if (connection.options().json) {
    PrintJson(s);
    return kExitOk;
  }
  std::string tags;
  for (const auto& t : s.tags()) tags += (tags.empty() ? "" : ", ") + t;
  std::printf("Snapshot %lld of %s: %s, by %s at %s UTC; tags: %s\n",
              static_cast<long long>(s.id()), s.project().c_str(),
              s.name().empty() ? "(unnamed)" : s.name().c_str(), s.author().c_str(),
              FormatTime(s.create_time()).c_str(), tags.empty() ? "none" : tags.c_str());
  std::vector<std::vector<std::string>> rows = {{"STRUCTURE", "REVISION"}};
  for (const auto& m : s.members()) rows.push_back({m.structure(), std::to_string(m.revision())});
  PrintTable(rows);
  return kExitOk;
}

namespace {

// The file a member of an export gets: its name and its format's
// extension, as exports always had ("Putamen.json"), so that the files
// people know stay where they were. A name that would be the manifest's
// (a structure named "manifest") or another member's, ignoring case (one
// file on macOS and Windows), gets "_2", "_3", ... before the extension:
// "manifest_2.json". The manifest says which file is whose, so readers
// never guess. False (with *why) when the structure's name, which the
// server sent, cannot be a file name.
bool ExportFileName(const std::string& structure, const std::string& extension,
                    std::set<std::string>* taken, std::string* file, std::string* why) {
  // The name itself too: ".." + ".json" would be a plain file name, but a
  // server that sends ".." for a structure is not to be trusted with paths.
  *why = UnsafeFileNameReason(structure);
  if (!why->empty()) return false;
  for (int n = 1; n < 1000; ++n) {
    const std::string candidate =
        (n == 1 ? structure : structure + "_" + std::to_string(n)) + extension;
    *why = UnsafeFileNameReason(candidate);
    if (!why->empty()) return false;
    if (taken->insert(FoldCase(candidate)).second) {
      *file = candidate;
      return true;
    }
  }
  *why = "too many structures share its name";
  return false;
}

// Why the members of an export (their revisions, in order) would not make
// a structure set pba-solve and pba-atlas read; "" when they would. A set
// needs each structure's colour to be its own and not black, 0,0,0 (the
// background; solver/atlas/structure_set.h), which the store does not ask
// (a structure created without --colour is 0,0,0; a job against the
// snapshot moves a repeated colour aside for its build, but an export is
// the snapshot as pinned). Names the structures and what to change.
std::string ExportColourProblem(const std::string& project,
                                const std::vector<v1::Revision>& revisions) {
  std::map<std::string, std::string> owner;  // colour -> first structure with it
  for (const v1::Revision& revision : revisions) {
    const v1::Colour& colour = revision.metadata().colour();
    const std::string name = QuotedName(revision.structure());
    const std::string set_colour =
        "pba atlas set -p " + QuotedName(project) + " " + name + " --colour R,G,B";
    if (colour.r() == 0 && colour.g() == 0 && colour.b() == 0) {
      return "structure " + name +
             " has no colour (0,0,0 is the background's); give it one with: " + set_colour;
    }
    const auto [it, first] = owner.emplace(ColourText(colour), name);
    if (!first) {
      return "structures " + it->second + " and " + name + " share the colour " + it->first +
             "; give " + name + " another with: " + set_colour;
    }
  }
  return "";
}

}  // namespace

int ExportSnapshot(Connection& connection, const std::string& project, const std::string& which,
                   const std::string& dir) {
  std::error_code ec;
  if (fs::exists(dir) && !fs::is_empty(dir, ec)) {
    std::fprintf(stderr, "pba: %s is not empty: export into a new directory\n", dir.c_str());
    return kExitUsage;
  }
  v1::GetSnapshotRequest request;
  request.set_project(project);
  request.set_snapshot(which);
  v1::Snapshot snapshot;
  {
    auto context = connection.UnaryContext();
    grpc::Status status = connection.atlas().GetSnapshot(context.get(), request, &snapshot);
    if (!status.ok()) return connection.Fail("snapshot " + which + " of " + project, status);
  }
  // Every member's revision and file name first: a name that cannot be a
  // file is refused before anything is written.
  std::vector<v1::Revision> revisions;
  std::vector<std::string> files;
  std::set<std::string> taken = {FoldCase(kManifestName)};
  for (const auto& member : snapshot.members()) {
    v1::Revision revision;
    const StructureArgs structure{project, member.structure()};
    if (int code = GetHead(connection, structure, member.revision(), &revision); code != kExitOk) {
      return code;
    }
    std::string file, why;
    if (!ExportFileName(member.structure(), Extension(revision.format()), &taken, &file, &why)) {
      std::fprintf(stderr,
                   "pba: snapshot %s of %s has a structure named %s, which cannot be a file name "
                   "(%s); nothing was written\n",
                   which.c_str(), project.c_str(), QuotedName(member.structure()).c_str(),
                   why.c_str());
      return kExitInvalid;
    }
    revisions.push_back(std::move(revision));
    files.push_back(std::move(file));
  }
  if (const std::string problem = ExportColourProblem(project, revisions); !problem.empty()) {
    std::fprintf(stderr,
                 "pba: snapshot %s of %s cannot be exported as a structure set (each structure "
                 "needs a colour of its own, or pba-solve and pba-atlas refuse the set): %s; "
                 "then snapshot again and export that; nothing was written\n",
                 which.c_str(), project.c_str(), problem.c_str());
    return kExitInvalid;
  }
  // Written into a fresh directory beside the target and renamed into
  // place, whole or absent (AtomicWriteDirectory: its temporary name is one
  // no one else has, so nothing already there is reused or removed, and a
  // rename takes the place of an empty directory only).
  fs::path target = fs::absolute(dir).lexically_normal();
  if (target.filename().empty()) target = target.parent_path();
  fs::create_directories(target.parent_path(), ec);
  int exit_code = kExitError;
  google::protobuf::Struct manifest;
  const Status written = AtomicWriteDirectory(target, [&](const fs::path& staging) -> Status {
    google::protobuf::ListValue manifest_structures;
    for (int i = 0; i < snapshot.members_size(); ++i) {
      const auto& member = snapshot.members(i);
      const v1::Revision& revision = revisions[static_cast<size_t>(i)];
      const std::string& file = files[static_cast<size_t>(i)];
      if (int code = DownloadRevision(connection, revision, staging / file, /*overwrite=*/false);
          code != kExitOk) {
        exit_code = code;  // DownloadRevision said why
        return Status::Io("");
      }
      auto& entry = *manifest_structures.add_values()->mutable_struct_value()->mutable_fields();
      entry["name"].set_string_value(member.structure());
      entry["revision"].set_number_value(static_cast<double>(member.revision()));
      entry["file"].set_string_value(file);
      entry["format"].set_string_value(FormatText(revision.format()));
      entry["sha256"].set_string_value(revision.content_sha256());
      entry["colour"].set_string_value(ColourText(revision.metadata().colour()));
      entry["group_path"].set_string_value(revision.metadata().group_path());
      entry["material_json"].set_string_value(revision.metadata().material_json());
    }
    auto& fields = *manifest.mutable_fields();
    fields["format"].set_string_value("pba-structure-set");
    fields["version"].set_number_value(1);
    fields["project"].set_string_value(project);
    fields["snapshot"].set_number_value(static_cast<double>(snapshot.id()));
    fields["snapshot_name"].set_string_value(snapshot.name());
    *fields["structures"].mutable_list_value() = manifest_structures;
    if (!WriteFileAtomically(staging / kManifestName, codec::ToJson(manifest))) {
      std::fprintf(stderr, "pba: cannot write %s\n", (staging / kManifestName).c_str());
      return Status::Io("");
    }
    // The temporary directory is private (0700); the export is not.
    if (::chmod(staging.c_str(), 0755 & ~CurrentUmask()) != 0) {
      return Status::Io("cannot set the mode of " + staging.string() + ": " + std::strerror(errno));
    }
    return Status::Ok();
  });
  if (!written.ok()) {
    if (!written.message().empty()) {
      std::fprintf(stderr, "pba: cannot export into %s: %s\n", target.c_str(),
                   written.message().c_str());
    }
    return exit_code;
  }
  if (connection.options().json) {
    PrintJson(manifest);
  } else {
    std::printf("Exported snapshot %lld of %s (%d structure%s) into %s, with manifest.json\n",
                static_cast<long long>(snapshot.id()), project.c_str(), snapshot.members_size(),
                snapshot.members_size() == 1 ? "" : "s", target.c_str());
  }
  return kExitOk;
}

int ListSnapshots(Connection& connection, const std::string& project, const PageArgs& page) {
  v1::ListSnapshotsResponse all;
  v1::ListSnapshotsRequest request;
  request.set_project(project);
  int code = FetchPages(connection, page, request, &v1::AtlasService::Stub::ListSnapshots,
                        &v1::ListSnapshotsResponse::mutable_snapshots,
                        "listing the snapshots of " + project, &all);
  if (code != kExitOk) return code;
  if (connection.options().json) {
    PrintJson(all);
    return kExitOk;
  }
  std::vector<std::vector<std::string>> rows = {{"ID", "NAME", "TAGS", "AUTHOR", "CREATED (UTC)"}};
  for (const auto& s : all.snapshots()) {
    std::string tags;
    for (const auto& t : s.tags()) tags += (tags.empty() ? "" : ",") + t;
    rows.push_back({std::to_string(s.id()), s.name(), tags.empty() ? "-" : tags, s.author(),
                    FormatTime(s.create_time())});
  }
  PrintTable(rows);
  MoreHint(all.next_page_token(), "pba atlas snapshots -p " + project);
  return kExitOk;
}

int Audit(Connection& connection, const std::string& project, const PageArgs& page) {
  v1::ListAuditResponse all;
  v1::ListAuditRequest request;
  request.set_project(project);
  int code =
      FetchPages(connection, page, request, &v1::AtlasService::Stub::ListAudit,
                 &v1::ListAuditResponse::mutable_entries, "the audit log of " + project, &all);
  if (code != kExitOk) return code;
  if (connection.options().json) {
    PrintJson(all);
    return kExitOk;
  }
  std::vector<std::vector<std::string>> rows = {
      {"SEQ", "TIME (UTC)", "USER", "ACTION", "TARGET", "REV", "DETAIL"}};
  for (const auto& e : all.entries()) {
    rows.push_back({std::to_string(e.sequence()), FormatTime(e.time()), e.user(), e.action(),
                    e.target(), e.revision() > 0 ? std::to_string(e.revision()) : "-", e.detail()});
  }
  PrintTable(rows);
  MoreHint(all.next_page_token(), "pba atlas audit -p " + project);
  return kExitOk;
}

int Watch(Connection& connection, const std::string& project, int count) {
  v1::WatchRequest request;
  request.set_project(project);
  auto context = connection.StreamContext();
  auto reader = connection.atlas().Watch(context.get(), request);
  v1::AtlasEvent event;
  int seen = 0;
  while (reader->Read(&event)) {
    if (connection.options().json) {
      std::puts(codec::ToJsonLine(event).c_str());
    } else if (event.kind() == v1::AtlasEvent::READY) {
      std::printf("Watching %s (Ctrl-C to stop)\n", project.c_str());
    } else {
      std::string kind = v1::AtlasEvent::Kind_Name(event.kind());
      std::transform(kind.begin(), kind.end(), kind.begin(),
                     [](unsigned char c) { return c == '_' ? ' ' : std::tolower(c); });
      std::string target = event.structure();
      if (event.revision() > 0) target += " r" + std::to_string(event.revision());
      if (event.kind() == v1::AtlasEvent::JOB_STATE_CHANGED) {
        kind = "job " + event.job_state();
        std::transform(kind.begin(), kind.end(), kind.begin(),
                       [](unsigned char c) { return std::tolower(c); });
        target = event.job_id();
        if (event.snapshot() > 0) target += " (snapshot " + std::to_string(event.snapshot()) + ")";
      } else if (event.snapshot() > 0) {
        target += "snapshot " + std::to_string(event.snapshot());
      }
      std::printf("%s  %-10s %-18s %s%s%s\n", FormatTime(event.time()).c_str(),
                  event.user().c_str(), kind.c_str(), target.c_str(),
                  event.detail().empty() ? "" : ": ", event.detail().c_str());
    }
    std::fflush(stdout);
    if (event.kind() != v1::AtlasEvent::READY && count > 0 && ++seen >= count) {
      context->TryCancel();
      break;
    }
  }
  grpc::Status status = reader->Finish();
  if (!status.ok() && status.error_code() != grpc::StatusCode::CANCELLED) {
    return connection.Fail("watching " + project, status);
  }
  return kExitOk;
}

void RegisterSnapshotCommands(CLI::App& atlas, CommandContext& context) {
  CLI::App* snapshot = AddCommandGroup(atlas, "snapshot", "Pin, list, show and export snapshots");

  struct CreateArgs {
    std::string project, name, request_id;
  };
  auto create = std::make_shared<CreateArgs>();
  CLI::App* create_cmd =
      snapshot->add_subcommand("create", "Pin the head of every structure of a project");
  context.AddProjectOption(create_cmd, &create->project);
  create_cmd->add_option("--name", create->name, "A name for it (default: its UTC time)");
  AddRequestIdOption(create_cmd, &create->request_id, "snapshot");
  context.Add(create_cmd, [create](Connection& c) {
    return CreateSnapshot(c, create->project, create->name, create->request_id);
  });

  struct ListArgs {
    std::string project;
    PageArgs page;
  };
  auto list = std::make_shared<ListArgs>();
  CLI::App* list_cmd = snapshot->add_subcommand("list", "Snapshots, newest first");
  context.AddProjectOption(list_cmd, &list->project);
  AddPagingOptions(list_cmd, &list->page);
  context.Add(list_cmd,
              [list](Connection& c) { return ListSnapshots(c, list->project, list->page); });

  struct WhichArgs {
    std::string project, which, dir;
  };
  auto show = std::make_shared<WhichArgs>();
  CLI::App* show_cmd = snapshot->add_subcommand("show", "A snapshot's revisions");
  context.AddProjectOption(show_cmd, &show->project);
  show_cmd->add_option("snapshot", show->which, "Id or tag")->required();
  context.Add(show_cmd,
              [show](Connection& c) { return ShowSnapshot(c, show->project, show->which); });

  auto out = std::make_shared<WhichArgs>();
  CLI::App* export_cmd = snapshot->add_subcommand(
      "export", "Download every structure a snapshot pins, with a manifest");
  context.AddProjectOption(export_cmd, &out->project);
  export_cmd->add_option("snapshot", out->which, "Id or tag")->required();
  export_cmd->add_option("-o,--out", out->dir, "New directory to write")->required();
  context.Add(export_cmd, [out](Connection& c) {
    return ExportSnapshot(c, out->project, out->which, out->dir);
  });
}

void RegisterTagAuditWatchCommands(CLI::App& atlas, CommandContext& context) {
  struct TagArgs {
    std::string project;
    int64_t id = 0;
    std::string tag;
  };
  auto tag = std::make_shared<TagArgs>();
  CLI::App* tag_cmd = atlas.add_subcommand("tag", "Name a snapshot by a tag");
  context.AddProjectOption(tag_cmd, &tag->project);
  tag_cmd->add_option("id", tag->id, "Snapshot id")->required();
  tag_cmd->add_option("tag", tag->tag, "Tag (not all digits)")->required();
  context.Add(tag_cmd,
              [tag](Connection& c) { return TagSnapshot(c, tag->project, tag->id, tag->tag); });

  struct AuditArgs {
    std::string project;
    PageArgs page;
  };
  auto audit = std::make_shared<AuditArgs>();
  CLI::App* audit_cmd = atlas.add_subcommand("audit", "Who changed what, newest first");
  context.AddProjectOption(audit_cmd, &audit->project);
  AddPagingOptions(audit_cmd, &audit->page);
  context.Add(audit_cmd, [audit](Connection& c) { return Audit(c, audit->project, audit->page); });

  struct WatchArgs {
    std::string project;
    int count = 0;
  };
  auto watch = std::make_shared<WatchArgs>();
  CLI::App* watch_cmd =
      atlas.add_subcommand("watch", "Print a project's changes as they happen (Ctrl-C stops)");
  context.AddProjectOption(watch_cmd, &watch->project);
  watch_cmd->add_option("--count", watch->count, "Stop after this many changes");
  context.Add(watch_cmd, [watch](Connection& c) { return Watch(c, watch->project, watch->count); });
}

}  // namespace pba::cli
