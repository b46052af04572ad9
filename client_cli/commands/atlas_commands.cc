#include "commands/atlas_commands.h"

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <thread>

#include "commands/atlas_shared.h"
#include "commands/command_context.h"
#include "core/sha256.h"
#include "exit_codes.h"
#include "files.h"
#include "output.h"
#include "transfer.h"

namespace pba::cli {
namespace fs = std::filesystem;
namespace {

// --- small helpers ------------------------------------------------------------

// The format named (`format`), else the one the file's extension says.
bool ParseFormat(const std::string& format, const std::string& file, v1::GeometryFormat* out) {
  std::string name = format;
  if (name.empty()) {
    const std::string f = fs::path(file).filename().string();
    const auto ends = [&f](const std::string& suffix) {
      return f.size() >= suffix.size() &&
             f.compare(f.size() - suffix.size(), suffix.size(), suffix) == 0;
    };
    if (ends(".json")) name = "contours_json";
    if (ends(".nii") || ends(".nii.gz")) name = "nifti";
    if (ends(".stl")) name = "stl";
    if (ends(".obj")) name = "obj";
    if (ends(".vtk")) name = "vtk";
    if (ends(".yaml") || ends(".yml")) name = "derived";
  }
  static const std::map<std::string, v1::GeometryFormat> kFormats = {
      {"contours_json", v1::CONTOURS_JSON},
      {"nifti", v1::NIFTI},
      {"stl", v1::STL},
      {"obj", v1::OBJ},
      {"vtk", v1::VTK},
      {"derived", v1::DERIVED}};
  const auto it = kFormats.find(name);
  if (it == kFormats.end()) return false;
  *out = it->second;
  return true;
}

bool ParseColour(const std::string& text, v1::Colour* colour) {
  int r = 0, g = 0, b = 0;
  char c1 = 0, c2 = 0;
  std::istringstream in(text);
  if (!(in >> r >> c1 >> g >> c2 >> b) || c1 != ',' || c2 != ',' || !in.eof()) return false;
  for (int v : {r, g, b}) {
    if (v < 0 || v > 255) return false;
  }
  colour->set_r(r);
  colour->set_g(g);
  colour->set_b(b);
  return true;
}

// Material JSON given inline or as @FILE; false (message printed) on a
// file that cannot be read.
bool ReadMaterial(const std::string& arg, std::string* json) {
  if (arg.empty() || arg[0] != '@') {
    *json = arg;
    return true;
  }
  std::ifstream in(arg.substr(1));
  if (!in) {
    std::fprintf(stderr, "pba: cannot read material file %s\n", arg.substr(1).c_str());
    return false;
  }
  std::stringstream buffer;
  buffer << in.rdbuf();
  *json = buffer.str();
  return true;
}

void PrintRevisions(const std::vector<v1::Revision>& revisions) {
  std::vector<std::vector<std::string>> rows = {
      {"REV", "KIND", "AUTHOR", "TIME (UTC)", "FORMAT", "BYTES", "SHA-256", "MESSAGE"}};
  for (const v1::Revision& r : revisions) {
    rows.push_back({std::to_string(r.number()), r.kind(), r.author(), FormatTime(r.time()),
                    FormatText(r.format()), std::to_string(r.size_bytes()),
                    r.content_sha256().substr(0, 12), r.message()});
  }
  PrintTable(rows);
}

// --- the checkout file ----------------------------------------------------------

struct CheckoutState {
  std::string server, project, structure, lock_id;
  int64_t base_revision = 0;
  std::string format;
};

fs::path CheckoutPath(const std::string& file) { return file + ".pba-checkout"; }

bool WriteCheckout(const std::string& file, const CheckoutState& s) {
  std::ostringstream out;
  out << "# pba atlas checkout of " << s.project << "/" << s.structure
      << "; `pba atlas commit` reads it\n"
      << "server=" << s.server << "\nproject=" << s.project << "\nstructure=" << s.structure
      << "\nlock_id=" << s.lock_id << "\nbase_revision=" << s.base_revision
      << "\nformat=" << s.format << "\n";
  return WriteFileAtomically(CheckoutPath(file), out.str(), 0600);
}

bool ReadCheckout(const std::string& file, CheckoutState* s) {
  std::ifstream in(CheckoutPath(file));
  if (!in) return false;
  std::map<std::string, std::string> values;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    const auto eq = line.find('=');
    if (eq != std::string::npos) values[line.substr(0, eq)] = line.substr(eq + 1);
  }
  s->server = values["server"];
  s->project = values["project"];
  s->structure = values["structure"];
  s->lock_id = values["lock_id"];
  s->format = values["format"];
  try {
    s->base_revision = std::stoll(values["base_revision"]);
  } catch (...) {
    return false;
  }
  return !s->project.empty() && !s->structure.empty() && !s->lock_id.empty();
}

// --- transfers ------------------------------------------------------------------

int ReleaseLockId(Connection& connection, const std::string& lock_id, const std::string& what) {
  v1::ReleaseLockRequest request;
  request.set_lock_id(lock_id);
  v1::ReleaseLockResponse response;
  auto context = connection.UnaryContext();
  grpc::Status status = connection.atlas().ReleaseLock(context.get(), request, &response);
  if (!status.ok()) return connection.Fail("unlocking " + what, status, kExitConflict);
  return kExitOk;
}

volatile std::sig_atomic_t g_stop = 0;
extern "C" void OnStopSignal(int) { g_stop = 1; }

// Renews the lease every third of it until SIGINT or SIGTERM.
int HoldLock(Connection& connection, const std::string& lock_id, int lease_s,
             const std::string& what) {
  std::signal(SIGINT, OnStopSignal);
  std::signal(SIGTERM, OnStopSignal);
  const auto period = std::chrono::seconds(std::max(1, lease_s / 3));
  auto next = std::chrono::steady_clock::now() + period;
  while (g_stop == 0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    if (std::chrono::steady_clock::now() < next) continue;
    v1::RenewLockRequest request;
    request.set_lock_id(lock_id);
    request.set_lease_seconds(lease_s);
    v1::Lock lock;
    auto context = connection.UnaryContext();
    grpc::Status status = connection.atlas().RenewLock(context.get(), request, &lock);
    if (!status.ok()) return connection.Fail("keeping the lock on " + what, status, kExitConflict);
    next = std::chrono::steady_clock::now() + period;
  }
  return kExitOk;
}

}  // namespace

// --- structures -----------------------------------------------------------------

int ListStructures(Connection& connection, const std::string& project, const PageArgs& page) {
  v1::ListStructuresResponse all;
  v1::ListStructuresRequest request;
  request.set_project(project);
  int code = FetchPages(connection, page, request, &v1::AtlasService::Stub::ListStructures,
                        &v1::ListStructuresResponse::mutable_structures,
                        "listing the structures of " + project, &all);
  if (code != kExitOk) return code;
  if (connection.options().json) {
    PrintJson(all);
    return kExitOk;
  }
  if (all.structures().empty()) {
    std::printf("No structures in %s.\n", project.c_str());
    return kExitOk;
  }
  std::vector<std::vector<std::string>> rows = {
      {"STRUCTURE", "HEAD", "COLOUR", "GROUP", "LOCKED BY", "LEASE ENDS (UTC)"}};
  for (const auto& s : all.structures()) {
    rows.push_back({s.name(), std::to_string(s.head()), ColourText(s.metadata().colour()),
                    s.metadata().group_path().empty() ? "-" : s.metadata().group_path(),
                    s.has_lock() ? s.lock().holder() : "-",
                    s.has_lock() ? FormatTime(s.lock().expire_time()) : "-"});
  }
  PrintTable(rows);
  MoreHint(all.next_page_token(), "pba atlas list -p " + project);
  return kExitOk;
}

int ShowStructure(Connection& connection, const StructureArgs& target) {
  v1::GetStructureRequest request;
  request.set_project(target.project);
  request.set_structure(target.structure);
  v1::Structure s;
  auto context = connection.UnaryContext();
  grpc::Status status = connection.atlas().GetStructure(context.get(), request, &s);
  if (!status.ok()) return connection.Fail(target.project + "/" + target.structure, status);
  if (connection.options().json) {
    PrintJson(s);
    return kExitOk;
  }
  v1::Revision head;
  if (int code = GetHead(connection, target, s.head(), &head); code != kExitOk) return code;
  PrintTable({{"Structure", s.project() + "/" + s.name()},
              {"Head", std::to_string(s.head()) + " (" + head.kind() + " by " + head.author() +
                           ", " + FormatTime(head.time()) + " UTC)"},
              {"Geometry", FormatText(head.format()) + ", " + std::to_string(head.size_bytes()) +
                               " bytes, sha256 " + head.content_sha256()},
              {"Colour", ColourText(s.metadata().colour())},
              {"Group", s.metadata().group_path().empty() ? "-" : s.metadata().group_path()},
              {"Material", s.metadata().material_json()},
              {"Metadata etag", s.metadata_etag()},
              {"Lock", s.has_lock() ? s.lock().holder() + " until " +
                                          FormatTime(s.lock().expire_time()) + " UTC"
                                    : "none"}});
  return kExitOk;
}

int History(Connection& connection, const StructureArgs& target, const PageArgs& page) {
  v1::ListRevisionsResponse all;
  v1::ListRevisionsRequest request;
  request.set_project(target.project);
  request.set_structure(target.structure);
  int code = FetchPages(connection, page, request, &v1::AtlasService::Stub::ListRevisions,
                        &v1::ListRevisionsResponse::mutable_revisions,
                        target.project + "/" + target.structure, &all);
  if (code != kExitOk) return code;
  if (connection.options().json) {
    PrintJson(all);
    return kExitOk;
  }
  PrintRevisions({all.revisions().begin(), all.revisions().end()});
  MoreHint(all.next_page_token(),
           "pba atlas history -p " + target.project + " '" + target.structure + "'");
  return kExitOk;
}

int CreateStructure(Connection& connection, const CreateStructureArgs& args) {
  v1::CreateStructureRequest request;
  request.set_project(args.target.project);
  request.set_name(args.target.structure);
  v1::GeometryFormat format;
  if (!ParseFormat(args.format, args.file, &format)) {
    std::fprintf(stderr,
                 "pba: cannot tell the geometry format of %s: name it with --format "
                 "(contours_json, nifti, stl, obj, vtk or derived)\n",
                 args.file.c_str());
    return kExitUsage;
  }
  request.set_format(format);
  if (!args.colour.empty() &&
      !ParseColour(args.colour, request.mutable_metadata()->mutable_colour())) {
    std::fprintf(stderr, "pba: --colour must be R,G,B with components 0..255, not '%s'\n",
                 args.colour.c_str());
    return kExitUsage;
  }
  request.mutable_metadata()->set_group_path(args.group);
  std::string material = "{}";
  if (!args.material.empty() && !ReadMaterial(args.material, &material)) return kExitError;
  request.mutable_metadata()->set_material_json(material);
  request.set_message(args.message);
  request.set_request_id(RequestIdOr(args.request_id));
  std::string upload_id;
  if (int code = UploadFile(connection, args.file, &upload_id); code != kExitOk) return code;
  request.set_upload_id(upload_id);
  v1::Revision revision;
  auto context = connection.UnaryContext();
  grpc::Status status = connection.atlas().CreateStructure(context.get(), request, &revision);
  if (!status.ok()) {
    DiscardUpload(connection, upload_id);
    return connection.Fail("creating " + args.target.project + "/" + args.target.structure, status,
                           kExitConflict);
  }
  if (connection.options().json) {
    PrintJson(revision);
  } else {
    std::printf("Created %s/%s, revision 1 (%lld bytes of %s)\n", revision.project().c_str(),
                revision.structure().c_str(), static_cast<long long>(revision.size_bytes()),
                FormatText(revision.format()).c_str());
  }
  return kExitOk;
}

namespace {

// Locks args.target for args.lease_s seconds.
int AcquireLock(Connection& connection, const CheckoutArgs& args, v1::Lock* lock) {
  v1::AcquireLockRequest request;
  request.set_project(args.target.project);
  request.set_structure(args.target.structure);
  request.set_lease_seconds(args.lease_s);
  auto context = connection.UnaryContext();
  grpc::Status status = connection.atlas().AcquireLock(context.get(), request, lock);
  if (!status.ok()) {
    return connection.Fail("locking " + args.target.project + "/" + args.target.structure, status,
                           kExitConflict);
  }
  return kExitOk;
}

// Whether the structure has a revision with this content: one of its 100
// newest (the head is the newest).
bool ServerHasContent(Connection& connection, const StructureArgs& target,
                      const std::string& sha256) {
  v1::ListRevisionsRequest request;
  request.set_project(target.project);
  request.set_structure(target.structure);
  request.set_page_size(100);
  v1::ListRevisionsResponse response;
  auto context = connection.UnaryContext();
  if (!connection.atlas().ListRevisions(context.get(), request, &response).ok()) return false;
  return std::any_of(response.revisions().begin(), response.revisions().end(),
                     [&](const v1::Revision& r) { return r.content_sha256() == sha256; });
}

// Before a checkout writes `out`: a file there whose content the server
// does not have (an edit whose commit was refused, as after a stale base;
// or any file of the user's) is moved aside to OUT.mine (OUT.mine.2, ...
// when that is taken), not overwritten; *kept names where. Content the
// server has is simply replaced, and so is anything with `force`.
int KeepLocalEdit(Connection& connection, const StructureArgs& target, const std::string& out,
                  bool force, std::string* kept) {
  kept->clear();
  std::error_code ec;
  if (force || !fs::is_regular_file(fs::symlink_status(out, ec))) return kExitOk;
  const std::string sha256 = Sha256File(out);
  if (!sha256.empty() && ServerHasContent(connection, target, sha256)) return kExitOk;
  for (int n = 1; n < 100; ++n) {
    const std::string aside = out + ".mine" + (n == 1 ? "" : "." + std::to_string(n));
    if (RenameNoReplace(out, aside)) {
      *kept = aside;
      return kExitOk;
    }
    if (errno != EEXIST) break;
  }
  std::fprintf(stderr,
               "pba: %s holds changes the server does not have and cannot be moved aside; keep it "
               "elsewhere, or pass --force to overwrite it\n",
               out.c_str());
  return kExitConflict;
}

}  // namespace

int Checkout(Connection& connection, const CheckoutArgs& args) {
  const std::string what = args.target.project + "/" + args.target.structure;
  v1::Lock lock;
  if (int code = AcquireLock(connection, args, &lock); code != kExitOk) return code;
  // From here on a failure gives the lock back: nothing is left held.
  const auto give_back = [&](int code) {
    ReleaseLockId(connection, lock.lock_id(), what);
    return code;
  };
  v1::Revision head;
  if (int code = GetHead(connection, args.target, 0, &head); code != kExitOk)
    return give_back(code);
  const std::string out =
      args.out.empty() ? args.target.structure + Extension(head.format()) : args.out;
  std::string kept;
  if (int code = KeepLocalEdit(connection, args.target, out, args.force, &kept); code != kExitOk) {
    return give_back(code);
  }
  if (!kept.empty()) {
    std::fprintf(stderr,
                 "pba: %s held changes the server does not have (an edit not committed?); kept "
                 "them as %s. Redo them on revision %lld in %s.\n",
                 out.c_str(), kept.c_str(), static_cast<long long>(head.number()), out.c_str());
  }
  if (int code = DownloadRevision(connection, head, out, /*overwrite=*/true); code != kExitOk) {
    return give_back(code);
  }
  CheckoutState state{connection.options().server,
                      args.target.project,
                      args.target.structure,
                      lock.lock_id(),
                      head.number(),
                      FormatText(head.format())};
  if (!WriteCheckout(out, state)) {
    std::fprintf(stderr, "pba: cannot write %s\n", CheckoutPath(out).c_str());
    return give_back(kExitError);
  }
  if (connection.options().json) {
    PrintJson(lock);
  } else {
    std::printf(
        "Locked %s until %s UTC%s; revision %lld is in %s\n", what.c_str(),
        FormatTime(lock.expire_time()).c_str(),
        lock.took_over_from().empty()
            ? ""
            : (" (taken over from " + lock.took_over_from() + ", whose lease had lapsed)").c_str(),
        static_cast<long long>(head.number()), out.c_str());
    std::printf("Edit it, then: pba atlas commit %s -m \"...\"\n", out.c_str());
  }
  if (!args.hold) return kExitOk;
  std::fflush(stdout);
  if (!connection.options().json) {
    std::printf("Keeping the lock alive until Ctrl-C (then it is released)...\n");
    std::fflush(stdout);
  }
  const int held = HoldLock(connection, lock.lock_id(), args.lease_s, what);
  if (held != kExitOk) return held;
  // A commit made meanwhile may already have released it and removed the
  // checkout file; releasing again is then refused, which is fine.
  if (fs::exists(CheckoutPath(out))) {
    const int code = ReleaseLockId(connection, lock.lock_id(), what);
    std::error_code ec;
    fs::remove(CheckoutPath(out), ec);
    if (code != kExitOk) return code;
    std::printf("Released the lock on %s\n", what.c_str());
  }
  return kExitOk;
}

int LockStructure(Connection& connection, const CheckoutArgs& args) {
  const std::string what = args.target.project + "/" + args.target.structure;
  v1::Lock lock;
  if (int code = AcquireLock(connection, args, &lock); code != kExitOk) return code;
  if (connection.options().json) {
    PrintJson(lock);
  } else {
    std::printf("Locked %s until %s UTC%s; lock id %s (pba atlas unlock %s gives it back)\n",
                what.c_str(), FormatTime(lock.expire_time()).c_str(),
                lock.took_over_from().empty()
                    ? ""
                    : (" (taken over from " + lock.took_over_from() + ")").c_str(),
                lock.lock_id().c_str(), lock.lock_id().c_str());
  }
  if (!args.hold) return kExitOk;
  std::fflush(stdout);
  const int held = HoldLock(connection, lock.lock_id(), args.lease_s, what);
  if (held != kExitOk) return held;
  const int code = ReleaseLockId(connection, lock.lock_id(), what);
  if (code == kExitOk && !connection.options().json) {
    std::printf("Released the lock on %s\n", what.c_str());
  }
  return code;
}

int Commit(Connection& connection, const CommitArgs& args) {
  CheckoutState state;
  if (!ReadCheckout(args.file, &state)) {
    std::fprintf(stderr,
                 "pba: %s is not a checkout (no readable %s): check the structure out first with "
                 "`pba atlas checkout -p PROJECT NAME -o %s`\n",
                 args.file.c_str(), CheckoutPath(args.file).c_str(), args.file.c_str());
    return kExitUsage;
  }
  if (!state.server.empty() && state.server != connection.options().server) {
    std::fprintf(stderr, "pba: %s was checked out from %s, not %s; pass --server %s\n",
                 args.file.c_str(), state.server.c_str(), connection.options().server.c_str(),
                 state.server.c_str());
    return kExitUsage;
  }
  const std::string what = state.project + "/" + state.structure;
  v1::CommitStructureRequest request;
  request.set_project(state.project);
  request.set_structure(state.structure);
  request.set_lock_id(state.lock_id);
  request.set_base_revision(state.base_revision);
  v1::GeometryFormat format;
  if (!ParseFormat(state.format, args.file, &format)) {
    std::fprintf(stderr, "pba: %s names no known format\n", CheckoutPath(args.file).c_str());
    return kExitError;
  }
  request.set_format(format);
  request.set_message(args.message);
  if (!args.material.empty()) {
    std::string material;
    if (!ReadMaterial(args.material, &material)) return kExitError;
    request.set_material_json(material);
  }
  // The same checkout and the same file make the same key: a commit rerun
  // after a lost reply gets the revision it made, not a refusal.
  request.set_request_id(Sha256Hex(state.lock_id + "\n" + std::to_string(state.base_revision) +
                                   "\n" + Sha256File(args.file))
                             .substr(0, 32));
  std::string upload_id;
  if (int code = UploadFile(connection, args.file, &upload_id); code != kExitOk) return code;
  request.set_upload_id(upload_id);
  v1::Revision revision;
  {
    auto context = connection.UnaryContext();
    grpc::Status status = connection.atlas().CommitStructure(context.get(), request, &revision);
    if (!status.ok()) {
      DiscardUpload(connection, upload_id);
      return connection.Fail("committing " + what, status, kExitConflict);
    }
  }
  // The revision has landed. A lock that is no longer held (this is a rerun
  // whose first run gave it back, or the lease lapsed and was taken over) is
  // nothing to give back: still exit 0, or a script would take the landed
  // commit for a refused one and redo it.
  std::string lock_note = "; unlocked";
  int code = kExitOk;
  if (args.keep_lock) {
    state.base_revision = revision.number();
    WriteCheckout(args.file, state);
    lock_note = " (still locked: commit again, or `pba atlas unlock FILE`)";
  } else {
    v1::ReleaseLockRequest release;
    release.set_lock_id(state.lock_id);
    v1::ReleaseLockResponse released;
    auto context = connection.UnaryContext();
    const grpc::Status status = connection.atlas().ReleaseLock(context.get(), release, &released);
    if (status.ok() || status.error_code() == grpc::StatusCode::FAILED_PRECONDITION) {
      if (!status.ok()) lock_note = "; the lock was no longer held";
      std::error_code ec;
      fs::remove(CheckoutPath(args.file), ec);
    } else {
      // The checkout file stays, so that `pba atlas unlock FILE` (or a rerun
      // of this commit) can give the lock back later.
      lock_note = "; still locked";
      code = connection.Fail("committed " + what + " revision " +
                                 std::to_string(revision.number()) + ", but unlocking it",
                             status);
    }
  }
  if (connection.options().json) {
    PrintJson(revision);
  } else {
    std::printf("Committed %s revision %lld%s\n", what.c_str(),
                static_cast<long long>(revision.number()), lock_note.c_str());
  }
  return code;
}

int Unlock(Connection& connection, const std::string& what) {
  CheckoutState state;
  const bool file = ReadCheckout(what, &state);
  const std::string lock_id = file ? state.lock_id : what;
  const std::string name = file ? state.project + "/" + state.structure : "lock " + what;
  if (int code = ReleaseLockId(connection, lock_id, name); code != kExitOk) return code;
  if (file) {
    std::error_code ec;
    fs::remove(CheckoutPath(what), ec);
  }
  if (!connection.options().json) std::printf("Released the lock on %s\n", name.c_str());
  return kExitOk;
}

int BreakLock(Connection& connection, const StructureArgs& target, const std::string& reason) {
  v1::BreakLockRequest request;
  request.set_project(target.project);
  request.set_structure(target.structure);
  request.set_reason(reason);
  v1::BreakLockResponse response;
  auto context = connection.UnaryContext();
  grpc::Status status = connection.atlas().BreakLock(context.get(), request, &response);
  const std::string what = target.project + "/" + target.structure;
  if (!status.ok()) return connection.Fail("breaking the lock on " + what, status, kExitConflict);
  if (connection.options().json) {
    PrintJson(response);
  } else {
    std::printf("Broke %s's lock on %s (audited)\n", response.holder().c_str(), what.c_str());
  }
  return kExitOk;
}

int Revert(Connection& connection, const RevertArgs& args) {
  const std::string what = args.target.project + "/" + args.target.structure;
  v1::AcquireLockRequest lock_request;
  lock_request.set_project(args.target.project);
  lock_request.set_structure(args.target.structure);
  lock_request.set_lease_seconds(60);
  v1::Lock lock;
  {
    auto context = connection.UnaryContext();
    grpc::Status status = connection.atlas().AcquireLock(context.get(), lock_request, &lock);
    if (!status.ok()) return connection.Fail("locking " + what, status, kExitConflict);
  }
  v1::Revision head;
  int code = GetHead(connection, args.target, 0, &head);
  v1::Revision revision;
  if (code == kExitOk) {
    v1::RevertStructureRequest request;
    request.set_project(args.target.project);
    request.set_structure(args.target.structure);
    request.set_lock_id(lock.lock_id());
    request.set_base_revision(head.number());
    request.set_to_revision(args.to);
    request.set_message(args.message);
    auto context = connection.UnaryContext();
    grpc::Status status = connection.atlas().RevertStructure(context.get(), request, &revision);
    if (!status.ok()) code = connection.Fail("reverting " + what, status, kExitConflict);
  }
  const int released = ReleaseLockId(connection, lock.lock_id(), what);
  if (code != kExitOk) return code;
  if (released != kExitOk) return released;
  if (connection.options().json) {
    PrintJson(revision);
  } else {
    std::printf("Reverted %s to revision %lld: new revision %lld\n", what.c_str(),
                static_cast<long long>(args.to), static_cast<long long>(revision.number()));
  }
  return kExitOk;
}

int SetMetadata(Connection& connection, const MetadataArgs& args) {
  const std::string what = args.target.project + "/" + args.target.structure;
  v1::UpdateMetadataRequest request;
  request.set_project(args.target.project);
  request.set_structure(args.target.structure);
  request.set_message(args.message);
  if (args.colour && !ParseColour(*args.colour, request.mutable_colour())) {
    std::fprintf(stderr, "pba: --colour must be R,G,B with components 0..255, not '%s'\n",
                 args.colour->c_str());
    return kExitUsage;
  }
  if (args.group) request.set_group_path(*args.group);
  if (args.material) {
    std::string material;
    if (!ReadMaterial(*args.material, &material)) return kExitError;
    request.set_material_json(material);
  }
  if (!args.colour && !args.group && !args.material) {
    std::fprintf(stderr, "pba: nothing to change: give --colour, --group or --material\n");
    return kExitUsage;
  }
  // The etag of what this command read: a change landing in between is
  // refused (exit 9), not overwritten.
  v1::GetStructureRequest get;
  get.set_project(args.target.project);
  get.set_structure(args.target.structure);
  v1::Structure current;
  {
    auto context = connection.UnaryContext();
    grpc::Status status = connection.atlas().GetStructure(context.get(), get, &current);
    if (!status.ok()) return connection.Fail(what, status);
  }
  request.set_etag(current.metadata_etag());
  v1::UpdateMetadataResponse response;
  auto context = connection.UnaryContext();
  grpc::Status status = connection.atlas().UpdateMetadata(context.get(), request, &response);
  if (!status.ok()) return connection.Fail("changing " + what, status, kExitConflict);
  if (connection.options().json) {
    PrintJson(response);
  } else {
    std::printf("Changed %s: revision %lld\n", what.c_str(),
                static_cast<long long>(response.revision().number()));
  }
  return kExitOk;
}

int Download(Connection& connection, const DownloadArgs& args) {
  v1::Revision revision;
  if (int code = GetHead(connection, args.target, args.revision, &revision); code != kExitOk)
    return code;
  const std::string out =
      args.out.empty() ? args.target.structure + Extension(revision.format()) : args.out;
  if (int code = DownloadRevision(connection, revision, out, /*overwrite=*/true); code != kExitOk) {
    return code;
  }
  if (connection.options().json) {
    PrintJson(revision);
  } else {
    std::printf("Wrote %s/%s revision %lld to %s (%lld bytes)\n", revision.project().c_str(),
                revision.structure().c_str(), static_cast<long long>(revision.number()),
                out.c_str(), static_cast<long long>(revision.size_bytes()));
  }
  return kExitOk;
}

int Diff(Connection& connection, const StructureArgs& target, int64_t from, int64_t to) {
  v1::DiffRevisionsRequest request;
  request.set_project(target.project);
  request.set_structure(target.structure);
  request.set_from_revision(from);
  request.set_to_revision(to);
  v1::RevisionDiff diff;
  auto context = connection.UnaryContext();
  grpc::Status status = connection.atlas().DiffRevisions(context.get(), request, &diff);
  if (!status.ok()) return connection.Fail(target.project + "/" + target.structure, status);
  if (connection.options().json) {
    PrintJson(diff);
    return kExitOk;
  }
  std::printf("%s/%s, revision %lld -> %lld\n", diff.project().c_str(), diff.structure().c_str(),
              static_cast<long long>(diff.from_revision()),
              static_cast<long long>(diff.to_revision()));
  std::vector<std::vector<std::string>> rows = {{"WHAT", "FROM", "TO"}};
  for (const auto& change : diff.material_changes()) {
    rows.push_back({"material " + change.parameter(), change.from().empty() ? "-" : change.from(),
                    change.to().empty() ? "-" : change.to()});
  }
  if (ColourText(diff.from_colour()) != ColourText(diff.to_colour())) {
    rows.push_back({"colour", ColourText(diff.from_colour()), ColourText(diff.to_colour())});
  }
  if (diff.from_group() != diff.to_group()) {
    rows.push_back({"group", diff.from_group(), diff.to_group()});
  }
  if (diff.has_contours()) {
    const v1::ContoursDiff& c = diff.contours();
    char from_volume[32], to_volume[32];
    std::snprintf(from_volume, sizeof from_volume, "%.1f mm^3", c.from_volume_mm3());
    std::snprintf(to_volume, sizeof to_volume, "%.1f mm^3", c.to_volume_mm3());
    rows.push_back({"volume (plates x slabs)", from_volume, to_volume});
  }
  if (diff.has_shape()) {
    const v1::ShapeDiff& shape = diff.shape();
    char from_volume[48], to_volume[48];
    std::snprintf(from_volume, sizeof from_volume, "%.0f mm^3", shape.from_volume_mm3());
    std::snprintf(to_volume, sizeof to_volume, "%.0f mm^3", shape.to_volume_mm3());
    rows.push_back({"volume (" + std::to_string(shape.voxel_mm()).substr(0, 3) + " mm voxels)",
                    from_volume, to_volume});
  }
  if (rows.size() > 1) PrintTable(rows);
  if (!diff.geometry_changed()) {
    std::puts("Geometry: unchanged.");
  } else if (diff.has_contours()) {
    const v1::ContoursDiff& c = diff.contours();
    std::printf(
        "Contours: over %d plate%s at shared heights the contours are at most %.3f mm apart "
        "(Hausdorff), %.3f mm on average",
        c.plates_compared(), c.plates_compared() == 1 ? "" : "s", c.hausdorff_mm(),
        c.mean_distance_mm());
    const auto heights = [](const google::protobuf::RepeatedField<double>& z) {
      std::string out;
      for (double h : z) out += (out.empty() ? "" : ", ") + std::to_string(h).substr(0, 6);
      return out;
    };
    if (!c.only_in_from_z_mm().empty())
      std::printf("; plates removed at z = %s mm", heights(c.only_in_from_z_mm()).c_str());
    if (!c.only_in_to_z_mm().empty())
      std::printf("; plates added at z = %s mm", heights(c.only_in_to_z_mm()).c_str());
    std::puts(".");
  }
  if (diff.has_shape()) {
    const v1::ShapeDiff& shape = diff.shape();
    std::printf(
        "Shape: %.0f mm^3 shared, Dice %.3f; surfaces at most %.2f mm apart (Hausdorff), %.2f mm "
        "on average (%.3g mm voxels).\n",
        shape.shared_volume_mm3(), shape.dice(), shape.hausdorff_mm(),
        shape.mean_surface_distance_mm(), shape.voxel_mm());
  }
  return kExitOk;
}

// --- registration ---------------------------------------------------------------

namespace {

// -p,--project and the structure's name.
void AddTarget(const CommandContext& context, CLI::App* cmd, StructureArgs* target) {
  context.AddProjectOption(cmd, &target->project);
  cmd->add_option("structure", target->structure, "Structure name")->required();
}

// `pba atlas list|show|history`.
void RegisterBrowseCommands(CLI::App& atlas, CommandContext& context) {
  struct ListArgs {
    std::string project;
    PageArgs page;
  };
  auto list = std::make_shared<ListArgs>();
  CLI::App* list_cmd = atlas.add_subcommand("list", "The structures of a project");
  context.AddProjectOption(list_cmd, &list->project);
  AddPagingOptions(list_cmd, &list->page);
  context.Add(list_cmd,
              [list](Connection& c) { return ListStructures(c, list->project, list->page); });

  auto show = std::make_shared<StructureArgs>();
  CLI::App* show_cmd = atlas.add_subcommand("show", "One structure: head, metadata, lock");
  AddTarget(context, show_cmd, show.get());
  context.Add(show_cmd, [show](Connection& c) { return ShowStructure(c, *show); });

  struct HistoryArgs {
    StructureArgs target;
    PageArgs page;
  };
  auto history = std::make_shared<HistoryArgs>();
  CLI::App* history_cmd = atlas.add_subcommand("history", "A structure's revisions, newest first");
  AddTarget(context, history_cmd, &history->target);
  AddPagingOptions(history_cmd, &history->page);
  context.Add(history_cmd,
              [history](Connection& c) { return History(c, history->target, history->page); });
}

// `pba atlas create`.
void RegisterCreateCommand(CLI::App& atlas, CommandContext& context) {
  auto create = std::make_shared<CreateStructureArgs>();
  CLI::App* cmd =
      atlas.add_subcommand("create", "Add a structure from a geometry file (revision 1)");
  AddTarget(context, cmd, &create->target);
  cmd->add_option("file", create->file,
                  "Geometry: contours .json, .nii(.gz), .stl, .obj, .vtk; or a derived "
                  "structure's recipe, .yaml")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--format", create->format,
                  "contours_json, nifti, stl, obj, vtk or derived (default: from the extension)");
  cmd->add_option("--colour", create->colour, "Display colour R,G,B (0..255)");
  cmd->add_option("--group", create->group, "Group path, e.g. cerebrum/basal ganglia");
  cmd->add_option("--material", create->material, "Material parameters: JSON or @FILE");
  cmd->add_option("-m,--message", create->message, "Why");
  AddRequestIdOption(cmd, &create->request_id, "revision");
  context.Add(cmd, [create](Connection& c) { return CreateStructure(c, *create); });
}

// `pba atlas checkout|lock|commit|unlock|break`: editing under a lock.
void RegisterLockCommands(CLI::App& atlas, CommandContext& context) {
  auto checkout = std::make_shared<CheckoutArgs>();
  CLI::App* checkout_cmd = atlas.add_subcommand(
      "checkout", "Lock a structure and download its head for editing (writes FILE.pba-checkout)");
  AddTarget(context, checkout_cmd, &checkout->target);
  checkout_cmd->add_option("-o,--out", checkout->out, "File to write (default NAME.<format>)");
  checkout_cmd->add_option("--lease", checkout->lease_s, "Lease in seconds (renew with --hold)")
      ->check(CLI::Range(1, 3600))
      ->capture_default_str();
  checkout_cmd->add_flag("--hold", checkout->hold,
                         "Stay running and keep the lease alive until Ctrl-C, then unlock");
  checkout_cmd->add_flag("--force", checkout->force,
                         "Overwrite FILE even when it holds changes the server does not have "
                         "(by default they are kept as FILE.mine)");
  context.Add(checkout_cmd, [checkout](Connection& c) { return Checkout(c, *checkout); });

  auto lock = std::make_shared<CheckoutArgs>();
  CLI::App* lock_cmd = atlas.add_subcommand(
      "lock", "Lock a structure without downloading it (no one else may change it)");
  AddTarget(context, lock_cmd, &lock->target);
  lock_cmd->add_option("--lease", lock->lease_s, "Lease in seconds (renew with --hold)")
      ->check(CLI::Range(1, 3600))
      ->capture_default_str();
  lock_cmd->add_flag("--hold", lock->hold,
                     "Stay running and keep the lease alive until Ctrl-C, then unlock");
  context.Add(lock_cmd, [lock](Connection& c) { return LockStructure(c, *lock); });

  auto commit = std::make_shared<CommitArgs>();
  CLI::App* commit_cmd =
      atlas.add_subcommand("commit", "Commit a checked-out file as a new revision, then unlock");
  commit_cmd->add_option("file", commit->file, "The checked-out file")
      ->required()
      ->check(CLI::ExistingFile);
  commit_cmd->add_option("-m,--message", commit->message, "Why")->required();
  commit_cmd->add_option("--material", commit->material,
                         "New material parameters with it: JSON or @FILE");
  commit_cmd->add_flag("--keep-lock", commit->keep_lock, "Keep the lock to commit again");
  context.Add(commit_cmd, [commit](Connection& c) { return Commit(c, *commit); });

  auto unlock_what = std::make_shared<std::string>();
  CLI::App* unlock_cmd = atlas.add_subcommand("unlock", "Release a lock without committing");
  unlock_cmd->add_option("what", *unlock_what, "The checked-out file, or a lock id")->required();
  context.Add(unlock_cmd, [unlock_what](Connection& c) { return Unlock(c, *unlock_what); });

  struct BreakArgs {
    StructureArgs target;
    std::string reason;
  };
  auto broken = std::make_shared<BreakArgs>();
  CLI::App* break_cmd =
      atlas.add_subcommand("break", "Break someone's lock (project admins; audited)");
  AddTarget(context, break_cmd, &broken->target);
  break_cmd->add_option("--reason", broken->reason, "Why (recorded in the audit log)")->required();
  context.Add(break_cmd,
              [broken](Connection& c) { return BreakLock(c, broken->target, broken->reason); });
}

// `pba atlas revert|set`: changes that need no lock.
void RegisterChangeCommands(CLI::App& atlas, CommandContext& context) {
  auto revert = std::make_shared<RevertArgs>();
  CLI::App* revert_cmd = atlas.add_subcommand(
      "revert", "A new revision with the content of an older one (history is kept)");
  AddTarget(context, revert_cmd, &revert->target);
  revert_cmd->add_option("--to", revert->to, "The revision to go back to")->required();
  revert_cmd->add_option("-m,--message", revert->message, "Why");
  context.Add(revert_cmd, [revert](Connection& c) { return Revert(c, *revert); });

  auto metadata = std::make_shared<MetadataArgs>();
  CLI::App* set_cmd = atlas.add_subcommand(
      "set", "Change a structure's colour, group or material (no lock needed)");
  AddTarget(context, set_cmd, &metadata->target);
  set_cmd->add_option("--colour", metadata->colour, "R,G,B (0..255)");
  set_cmd->add_option("--group", metadata->group, "Group path");
  set_cmd->add_option("--material", metadata->material, "Material parameters: JSON or @FILE");
  set_cmd->add_option("-m,--message", metadata->message, "Why");
  context.Add(set_cmd, [metadata](Connection& c) { return SetMetadata(c, *metadata); });
}

// `pba atlas download|diff`: reading revisions.
void RegisterRevisionCommands(CLI::App& atlas, CommandContext& context) {
  auto download = std::make_shared<DownloadArgs>();
  CLI::App* download_cmd =
      atlas.add_subcommand("download", "Download a revision's geometry (no lock)");
  AddTarget(context, download_cmd, &download->target);
  download_cmd->add_option("-r,--revision", download->revision, "Revision (default the head)");
  download_cmd->add_option("-o,--out", download->out, "File to write (default NAME.<format>)");
  context.Add(download_cmd, [download](Connection& c) { return Download(c, *download); });

  struct DiffArgs {
    StructureArgs target;
    int64_t from = 0, to = 0;
  };
  auto diff = std::make_shared<DiffArgs>();
  CLI::App* diff_cmd = atlas.add_subcommand(
      "diff", "What changed between two revisions: material, colour, group, shape");
  AddTarget(context, diff_cmd, &diff->target);
  diff_cmd->add_option("--from", diff->from, "Older revision (default the head's parent)");
  diff_cmd->add_option("--to", diff->to, "Newer revision (default the head)");
  context.Add(diff_cmd,
              [diff](Connection& c) { return Diff(c, diff->target, diff->from, diff->to); });
}

}  // namespace

void RegisterAtlasCommands(CLI::App& app, CommandContext& context) {
  CLI::App* atlas = AddCommandGroup(app, "atlas", "Share and edit atlas structures");
  // In the order `pba atlas --help` lists them.
  RegisterBrowseCommands(*atlas, context);
  RegisterCreateCommand(*atlas, context);
  RegisterLockCommands(*atlas, context);
  RegisterChangeCommands(*atlas, context);
  RegisterRevisionCommands(*atlas, context);
  RegisterSnapshotCommands(*atlas, context);       // snapshot_commands.cc
  RegisterImportExportCommands(*atlas, context);   // import_commands.cc
  RegisterTagAuditWatchCommands(*atlas, context);  // snapshot_commands.cc
}

}  // namespace pba::cli
