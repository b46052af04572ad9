// pba: the command-line client of pba-server.
// Exit codes are listed in exit_codes.h and docs/cli.md.

#include <CLI/CLI.hpp>
#include <cstdlib>
#include <string>

#include "commands/atlas_commands.h"
#include "commands/batch_commands.h"
#include "commands/job_commands.h"
#include "commands/project_commands.h"
#include "commands/study_commands.h"
#include "connection.h"
#include "credentials.h"
#include "exit_codes.h"

int main(int argc, char** argv) {
  using namespace pba::cli;
  CLI::App app{
      "pba: submit brain-biomechanics jobs to pba-server, follow them, fetch results; share and "
      "edit atlas structures"};
  app.set_version_flag("--version", "pba 0.1.0");
  app.require_subcommand(1);

  GlobalOptions global;
  if (const char* env = std::getenv("PBA_SERVER"); env != nullptr && *env != '\0')
    global.server = env;
  app.add_option("--server", global.server, "pba-server address HOST:PORT (env PBA_SERVER)")
      ->capture_default_str();
  app.add_flag("--json", global.json, "Print machine-readable JSON instead of tables");
  if (const char* env = std::getenv("PBA_TLS_CA"); env != nullptr) global.tls_ca = env;
  app.add_option("--tls-ca", global.tls_ca,
                 "Connect with TLS, trusting this PEM certificate (env PBA_TLS_CA)")
      ->check(CLI::ExistingFile);
  app.add_flag("--tls", global.tls, "Connect with TLS, trusting the system's certificates");
  app.add_option("--timeout", global.timeout_s, "Deadline of each request in seconds")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();

  CLI::App* job = app.add_subcommand("job", "Submit, follow, cancel and fetch jobs");
  job->require_subcommand(1);

  SubmitArgs submit;
  CLI::App* submit_cmd = job->add_subcommand("submit", "Submit a scene file (YAML or JSON)");
  submit_cmd->add_option("file", submit.file, "Scene file")->required()->check(CLI::ExistingFile);
  submit_cmd->add_flag("--wait", submit.wait,
                       "Follow the job until it ends; exit with its outcome");
  submit_cmd->add_option(
      "--request-id", submit.request_id,
      "Idempotency key: a repeated submit with the same key returns the same job");
  submit_cmd->add_option("--snapshot", submit.snapshot,
                         "PROJECT/SNAPSHOT: build the scene's atlas from this snapshot of the "
                         "atlas store (its id or a tag)");
  submit_cmd->add_option("--priority", submit.priority, "Higher runs first (-100..100)")
      ->check(CLI::Range(-100, 100));
  submit_cmd
      ->add_option("--timeout", submit.timeout_s,
                   "Wall-clock limit [s] (at most the server's); 0: the server's")
      ->check(CLI::NonNegativeNumber);

  ListArgs list;
  CLI::App* list_cmd = job->add_subcommand("list", "List jobs, newest first");
  list_cmd->add_option("--page-size", list.page_size, "Jobs per page")->check(CLI::Range(1, 500));
  list_cmd->add_option("--page-token", list.page_token, "Continue from a previous page");
  list_cmd->add_flag("--all", list.all, "Fetch every page");

  std::string id;
  CLI::App* status_cmd = job->add_subcommand("status", "Show one job, with its summary when done");
  status_cmd->add_option("id", id, "Job id")->required();
  CLI::App* watch_cmd = job->add_subcommand("watch", "Follow a job's progress until it ends");
  watch_cmd->add_option("id", id, "Job id")->required();
  CLI::App* cancel_cmd = job->add_subcommand("cancel", "Cancel a queued or running job");
  cancel_cmd->add_option("id", id, "Job id")->required();

  FetchArgs fetch;
  CLI::App* fetch_cmd = job->add_subcommand("fetch", "Download a finished job's result files");
  fetch_cmd->add_option("id", fetch.id, "Job id")->required();
  fetch_cmd->add_option("-o,--out", fetch.out_dir, "Directory to write into (created)")->required();
  fetch_cmd->add_flag("--force", fetch.force, "Replace files of the same names already there");

  // --- identity ---
  LoginArgs login;
  CLI::App* login_cmd =
      app.add_subcommand("login", "Check a token with the server and keep it for later commands");
  login_cmd->add_option("--token", login.token, "The access token");
  login_cmd
      ->add_option("--token-file", login.token_file,
                   "Read the token from a file (the server's DATA/admin.token, say)")
      ->check(CLI::ExistingFile);
  CLI::App* logout_cmd = app.add_subcommand("logout", "Forget the token kept for the server");
  CLI::App* whoami_cmd = app.add_subcommand("whoami", "The user the kept token belongs to");

  // --- projects ---
  std::string project_env;
  if (const char* env = std::getenv("PBA_PROJECT"); env != nullptr) project_env = env;
  const auto add_project = [&project_env](CLI::App* cmd, std::string* project) {
    *project = project_env;
    auto* opt = cmd->add_option("-p,--project", *project, "Project (env PBA_PROJECT)");
    if (project_env.empty()) opt->required();
  };
  PageArgs page;
  const auto add_paging = [&page](CLI::App* cmd) {
    cmd->add_option("--page-size", page.page_size, "Entries per page")->check(CLI::Range(1, 1000));
    cmd->add_option("--page-token", page.page_token, "Continue from a previous page");
    cmd->add_flag("--all", page.all, "Fetch every page");
  };
  CLI::App* project = app.add_subcommand("project", "Create and list projects, set roles");
  project->require_subcommand(1);
  std::string name, user, role;
  CLI::App* project_create =
      project->add_subcommand("create", "Create a project (you are its admin)");
  project_create->add_option("name", name, "Project name")->required();
  // The creates' idempotency key (one command runs per invocation).
  std::string create_request_id;
  const auto add_request_id = [&create_request_id](CLI::App* cmd, const char* what) {
    cmd->add_option("--request-id", create_request_id,
                    std::string("Idempotency key: a rerun with the same key returns the ") + what +
                        " the first run created (default: a fresh random key)");
  };
  add_request_id(project_create, "project");
  CLI::App* project_list = project->add_subcommand("list", "Projects you are a member of");
  add_paging(project_list);
  std::string project_name;
  CLI::App* project_role =
      project->add_subcommand("role", "Give a user a role in a project (admins only)");
  project_role->add_option("project", project_name, "Project")->required();
  project_role->add_option("user", user, "User")->required();
  project_role->add_option("role", role, "viewer, editor or admin")->required();
  CLI::App* project_remove = project->add_subcommand(
      "remove-member", "Remove a user from a project, releasing their locks (admins only)");
  project_remove->add_option("project", project_name, "Project")->required();
  project_remove->add_option("user", user, "User")->required();

  // --- atlas ---
  CLI::App* atlas = app.add_subcommand("atlas", "Share and edit atlas structures");
  atlas->require_subcommand(1);
  StructureArgs target;
  const auto add_target = [&](CLI::App* cmd) {
    add_project(cmd, &target.project);
    cmd->add_option("structure", target.structure, "Structure name")->required();
  };
  CLI::App* atlas_list = atlas->add_subcommand("list", "The structures of a project");
  add_project(atlas_list, &target.project);
  add_paging(atlas_list);
  CLI::App* atlas_show = atlas->add_subcommand("show", "One structure: head, metadata, lock");
  add_target(atlas_show);
  CLI::App* atlas_history =
      atlas->add_subcommand("history", "A structure's revisions, newest first");
  add_target(atlas_history);
  add_paging(atlas_history);
  CreateStructureArgs create;
  CLI::App* atlas_create =
      atlas->add_subcommand("create", "Add a structure from a geometry file (revision 1)");
  add_project(atlas_create, &create.target.project);
  atlas_create->add_option("structure", create.target.structure, "Structure name")->required();
  atlas_create
      ->add_option("file", create.file, "Geometry: contours .json, .nii(.gz), .stl, .obj, .vtk")
      ->required()
      ->check(CLI::ExistingFile);
  atlas_create->add_option("--format", create.format,
                           "contours_json, nifti, stl, obj or vtk (default: from the extension)");
  atlas_create->add_option("--colour", create.colour, "Display colour R,G,B (0..255)");
  atlas_create->add_option("--group", create.group, "Group path, e.g. cerebrum/basal ganglia");
  atlas_create->add_option("--material", create.material, "Material parameters: JSON or @FILE");
  atlas_create->add_option("-m,--message", create.message, "Why");
  add_request_id(atlas_create, "revision");
  CheckoutArgs checkout;
  CLI::App* atlas_checkout = atlas->add_subcommand(
      "checkout", "Lock a structure and download its head for editing (writes FILE.pba-checkout)");
  add_project(atlas_checkout, &checkout.target.project);
  atlas_checkout->add_option("structure", checkout.target.structure, "Structure name")->required();
  atlas_checkout->add_option("-o,--out", checkout.out, "File to write (default NAME.<format>)");
  atlas_checkout->add_option("--lease", checkout.lease_s, "Lease in seconds (renew with --hold)")
      ->check(CLI::Range(1, 3600))
      ->capture_default_str();
  atlas_checkout->add_flag("--hold", checkout.hold,
                           "Stay running and keep the lease alive until Ctrl-C, then unlock");
  atlas_checkout->add_flag("--force", checkout.force,
                           "Overwrite FILE even when it holds changes the server does not have "
                           "(by default they are kept as FILE.mine)");
  CheckoutArgs lock_args;
  CLI::App* atlas_lock = atlas->add_subcommand(
      "lock", "Lock a structure without downloading it (no one else may change it)");
  add_project(atlas_lock, &lock_args.target.project);
  atlas_lock->add_option("structure", lock_args.target.structure, "Structure name")->required();
  atlas_lock->add_option("--lease", lock_args.lease_s, "Lease in seconds (renew with --hold)")
      ->check(CLI::Range(1, 3600))
      ->capture_default_str();
  atlas_lock->add_flag("--hold", lock_args.hold,
                       "Stay running and keep the lease alive until Ctrl-C, then unlock");
  CommitArgs commit;
  CLI::App* atlas_commit =
      atlas->add_subcommand("commit", "Commit a checked-out file as a new revision, then unlock");
  atlas_commit->add_option("file", commit.file, "The checked-out file")
      ->required()
      ->check(CLI::ExistingFile);
  atlas_commit->add_option("-m,--message", commit.message, "Why")->required();
  atlas_commit->add_option("--material", commit.material,
                           "New material parameters with it: JSON or @FILE");
  atlas_commit->add_flag("--keep-lock", commit.keep_lock, "Keep the lock to commit again");
  std::string unlock_what;
  CLI::App* atlas_unlock = atlas->add_subcommand("unlock", "Release a lock without committing");
  atlas_unlock->add_option("what", unlock_what, "The checked-out file, or a lock id")->required();
  std::string reason;
  CLI::App* atlas_break =
      atlas->add_subcommand("break", "Break someone's lock (project admins; audited)");
  add_target(atlas_break);
  atlas_break->add_option("--reason", reason, "Why (recorded in the audit log)")->required();
  RevertArgs revert;
  CLI::App* atlas_revert = atlas->add_subcommand(
      "revert", "A new revision with the content of an older one (history is kept)");
  add_project(atlas_revert, &revert.target.project);
  atlas_revert->add_option("structure", revert.target.structure, "Structure name")->required();
  atlas_revert->add_option("--to", revert.to, "The revision to go back to")->required();
  atlas_revert->add_option("-m,--message", revert.message, "Why");
  MetadataArgs metadata;
  CLI::App* atlas_set = atlas->add_subcommand(
      "set", "Change a structure's colour, group or material (no lock needed)");
  add_project(atlas_set, &metadata.target.project);
  atlas_set->add_option("structure", metadata.target.structure, "Structure name")->required();
  atlas_set->add_option("--colour", metadata.colour, "R,G,B (0..255)");
  atlas_set->add_option("--group", metadata.group, "Group path");
  atlas_set->add_option("--material", metadata.material, "Material parameters: JSON or @FILE");
  atlas_set->add_option("-m,--message", metadata.message, "Why");
  DownloadArgs download;
  CLI::App* atlas_download =
      atlas->add_subcommand("download", "Download a revision's geometry (no lock)");
  add_project(atlas_download, &download.target.project);
  atlas_download->add_option("structure", download.target.structure, "Structure name")->required();
  atlas_download->add_option("-r,--revision", download.revision, "Revision (default the head)");
  atlas_download->add_option("-o,--out", download.out, "File to write (default NAME.<format>)");
  int64_t diff_from = 0, diff_to = 0;
  CLI::App* atlas_diff = atlas->add_subcommand(
      "diff", "What changed between two revisions: material, colour, group, shape");
  add_target(atlas_diff);
  atlas_diff->add_option("--from", diff_from, "Older revision (default the head's parent)");
  atlas_diff->add_option("--to", diff_to, "Newer revision (default the head)");
  CLI::App* atlas_snapshot =
      atlas->add_subcommand("snapshot", "Pin, list, show and export snapshots");
  atlas_snapshot->require_subcommand(1);
  std::string snapshot_project, snapshot_which;
  CLI::App* snapshot_create =
      atlas_snapshot->add_subcommand("create", "Pin the head of every structure of a project");
  add_project(snapshot_create, &snapshot_project);
  snapshot_create->add_option("--name", name, "A name for it (default: its UTC time)");
  add_request_id(snapshot_create, "snapshot");
  CLI::App* snapshot_list = atlas_snapshot->add_subcommand("list", "Snapshots, newest first");
  add_project(snapshot_list, &snapshot_project);
  add_paging(snapshot_list);
  CLI::App* snapshot_show = atlas_snapshot->add_subcommand("show", "A snapshot's revisions");
  add_project(snapshot_show, &snapshot_project);
  snapshot_show->add_option("snapshot", snapshot_which, "Id or tag")->required();
  std::string export_dir;
  CLI::App* snapshot_export = atlas_snapshot->add_subcommand(
      "export", "Download every structure a snapshot pins, with a manifest");
  add_project(snapshot_export, &snapshot_project);
  snapshot_export->add_option("snapshot", snapshot_which, "Id or tag")->required();
  snapshot_export->add_option("-o,--out", export_dir, "New directory to write")->required();
  ImportArgs import_args;
  CLI::App* atlas_import = atlas->add_subcommand(
      "import", "Import an atlas into a project as a job: its structures and a snapshot of them");
  add_project(atlas_import, &import_args.project);
  atlas_import->add_flag("--synthetic", import_args.synthetic, "The built-in synthetic atlas");
  atlas_import->add_option("--plates", import_args.plates, "A plate directory (plates.json)")
      ->check(CLI::ExistingDirectory);
  atlas_import->add_option("--labels", import_args.labels, "A label volume (.nii, .nii.gz, .nrrd)")
      ->check(CLI::ExistingFile);
  atlas_import
      ->add_option("--colour-table", import_args.colour_table,
                   "With --labels: its label table (CSV); default the built-in one")
      ->check(CLI::ExistingFile);
  atlas_import->add_option("--structure", import_args.structures,
                           "Import only this structure (repeatable; group prefixes allowed)");
  atlas_import->add_option("--snapshot-name", import_args.snapshot_name,
                           "Name of the snapshot the import ends with");
  atlas_import->add_option("-m,--message", import_args.message, "Message of the new revisions");
  atlas_import->add_option("--request-id", import_args.request_id,
                           "Idempotency key: a repeated import with it returns the same job");
  bool import_no_wait = false;
  atlas_import->add_flag("--no-wait", import_no_wait, "Submit and return; do not follow the job");
  CLI::App* atlas_export = atlas->add_subcommand(
      "export", "Download a snapshot as a structure set (manifest.json + one file per structure)");
  add_project(atlas_export, &snapshot_project);
  atlas_export->add_option("snapshot", snapshot_which, "Id or tag")->required();
  atlas_export->add_option("-o,--out", export_dir, "New directory to write")->required();
  int64_t snapshot_id = 0;
  std::string tag;
  CLI::App* atlas_tag = atlas->add_subcommand("tag", "Name a snapshot by a tag");
  add_project(atlas_tag, &snapshot_project);
  atlas_tag->add_option("id", snapshot_id, "Snapshot id")->required();
  atlas_tag->add_option("tag", tag, "Tag (not all digits)")->required();
  CLI::App* atlas_audit = atlas->add_subcommand("audit", "Who changed what, newest first");
  add_project(atlas_audit, &snapshot_project);
  add_paging(atlas_audit);
  int watch_count = 0;
  CLI::App* atlas_watch =
      atlas->add_subcommand("watch", "Print a project's changes as they happen (Ctrl-C stops)");
  add_project(atlas_watch, &snapshot_project);
  atlas_watch->add_option("--count", watch_count, "Stop after this many changes");

  // --- batches ---
  CLI::App* batch = app.add_subcommand("batch", "Scripted batches of jobs");
  batch->require_subcommand(1);
  BatchArgs batch_args;
  CLI::App* batch_run = batch->add_subcommand(
      "run", "Run a base scene over parameter sweeps; one table of outputs per member");
  batch_run->add_option("file", batch_args.file, "Batch file (YAML)")
      ->required()
      ->check(CLI::ExistingFile);
  batch_run->add_option("-o,--out", batch_args.out, "CSV table (default FILE's name .csv)");
  batch_run->add_flag("--retry-failed", batch_args.retry_failed,
                      "Resubmit members whose earlier job failed or was cancelled");
  batch_run->add_flag("--dry-run", batch_args.dry_run, "Check the members, submit nothing");
  batch_run->add_flag("--no-plot", batch_args.no_plot,
                      "Draw no picture of the members' histories (the plot section)");

  // --- studies ---
  CLI::App* study = app.add_subcommand("study", "Studies over many jobs of one scene");
  study->require_subcommand(1);
  StudyArgs study_args;
  CLI::App* study_convergence = study->add_subcommand(
      "convergence",
      "Mesh convergence: the scene on successively finer meshes; change per mesh, observed "
      "order, Richardson extrapolate and grid convergence index");
  study_convergence->add_option("scene", study_args.scene, "Scene file (YAML)")
      ->required()
      ->check(CLI::ExistingFile);
  study_convergence
      ->add_option("-q,--quantity", study_args.quantities,
                   "A number of the summary, e.g. results.reactions[0].force_n[2] (repeatable)")
      ->required();
  auto* sizes_opt =
      study_convergence
          ->add_option("--sizes", study_args.sizes,
                       "Element sizes [mm], e.g. 8,5.6,4 (default: the scene's own, then divided "
                       "by --ratio)")
          ->delimiter(',');
  study_convergence->add_option("--meshes", study_args.meshes, "Number of meshes without --sizes")
      ->check(CLI::Range(2, 12))
      ->capture_default_str()
      ->excludes(sizes_opt);
  study_convergence
      ->add_option("--ratio", study_args.ratio, "Ratio of successive element sizes, > 1")
      ->check(CLI::Range(1.05, 4.0))
      ->capture_default_str()
      ->excludes(sizes_opt);
  study_convergence->add_option("--parallel", study_args.parallel, "Jobs in flight at most")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  study_convergence->add_option(
      "-o,--out", study_args.out,
      "CSV table (default SCENE's name .convergence.csv beside it; the state file beside it)");
  study_convergence->add_option("--snapshot", study_args.snapshot,
                                "PROJECT/SNAPSHOT: build an atlas scene from this snapshot");
  study_convergence
      ->add_option("--tolerance", study_args.tolerance_pct,
                   "A change from the previous mesh below it [%] counts as converged")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  study_convergence->add_flag("--retry-failed", study_args.retry_failed,
                              "Resubmit meshes whose earlier job failed or was cancelled");
  study_convergence->add_flag("--dry-run", study_args.dry_run,
                              "Print the sizes each mesh's scene gets, submit nothing");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitUsage;
  }

  global.token = FindToken(global.server);
  Connection connection(global);
  if (*batch_run) return RunBatch(connection, batch_args);
  if (*study_convergence) return RunConvergenceStudy(connection, study_args);
  if (*login_cmd) return Login(connection, login);
  if (*logout_cmd) return Logout(connection);
  if (*whoami_cmd) return WhoAmI(connection);
  if (*project_create) return CreateProject(connection, name, create_request_id);
  if (*project_list) return ListProjects(connection, page);
  if (*project_role) return SetRole(connection, project_name, user, role);
  if (*project_remove) return RemoveMember(connection, project_name, user);
  if (*atlas_list) return ListStructures(connection, target.project, page);
  if (*atlas_show) return ShowStructure(connection, target);
  if (*atlas_history) return History(connection, target, page);
  if (*atlas_create) {
    create.request_id = create_request_id;
    return CreateStructure(connection, create);
  }
  if (*atlas_checkout) return Checkout(connection, checkout);
  if (*atlas_lock) return LockStructure(connection, lock_args);
  if (*atlas_commit) return Commit(connection, commit);
  if (*atlas_unlock) return Unlock(connection, unlock_what);
  if (*atlas_break) return BreakLock(connection, target, reason);
  if (*atlas_revert) return Revert(connection, revert);
  if (*atlas_set) return SetMetadata(connection, metadata);
  if (*atlas_download) return Download(connection, download);
  if (*atlas_diff) return Diff(connection, target, diff_from, diff_to);
  if (*snapshot_create) {
    return CreateSnapshot(connection, snapshot_project, name, create_request_id);
  }
  if (*snapshot_list) return ListSnapshots(connection, snapshot_project, page);
  if (*snapshot_show) return ShowSnapshot(connection, snapshot_project, snapshot_which);
  if (*snapshot_export) {
    return ExportSnapshot(connection, snapshot_project, snapshot_which, export_dir);
  }
  if (*atlas_import) {
    import_args.wait = !import_no_wait;
    return ImportAtlas(connection, import_args);
  }
  if (*atlas_export) return ExportAtlas(connection, snapshot_project, snapshot_which, export_dir);
  if (*atlas_tag) return TagSnapshot(connection, snapshot_project, snapshot_id, tag);
  if (*atlas_audit) return Audit(connection, snapshot_project, page);
  if (*atlas_watch) return Watch(connection, snapshot_project, watch_count);
  if (*submit_cmd) return SubmitJob(connection, submit);
  if (*list_cmd) return ListJobs(connection, list);
  if (*status_cmd) return ShowJob(connection, id);
  if (*watch_cmd) return WatchJob(connection, id);
  if (*cancel_cmd) return CancelJob(connection, id);
  if (*fetch_cmd) return FetchJob(connection, fetch);
  return kExitUsage;
}
