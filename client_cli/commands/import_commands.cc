// `pba atlas import`: an atlas (the synthetic one, a plate directory or a
// label volume) imported into a project as a job: the files are uploaded,
// the job is submitted and followed, and the snapshot it made is printed.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <vector>

#include "commands/atlas_commands.h"
#include "commands/atlas_shared.h"
#include "commands/command_context.h"
#include "commands/job_commands.h"
#include "exit_codes.h"
#include "output.h"
#include "pba/v1/job.grpc.pb.h"

namespace pba::cli {
namespace fs = std::filesystem;
namespace {

// The files of a plate directory: plates.json, the colour table and the
// PNGs (nothing else is read by the importer, so nothing else is sent).
std::vector<fs::path> PlateFiles(const fs::path& dir) {
  std::vector<fs::path> files;
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
    if (!entry.is_regular_file()) continue;
    const std::string ext = entry.path().extension().string();
    if (ext == ".json" || ext == ".csv" || ext == ".png") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace

int ImportAtlas(Connection& connection, const ImportArgs& args) {
  v1::SubmitJobRequest request;
  v1::AtlasImport& spec = *request.mutable_atlas_import();
  spec.set_project(args.project);
  spec.set_snapshot_name(args.snapshot_name);
  spec.set_message(args.message);
  for (const std::string& s : args.structures) spec.add_structures(s);
  std::vector<fs::path> files;
  const int sources =
      (args.synthetic ? 1 : 0) + (args.plates.empty() ? 0 : 1) + (args.labels.empty() ? 0 : 1);
  if (sources != 1) {
    std::fprintf(stderr, "pba: give exactly one of --synthetic, --plates DIR, --labels FILE\n");
    return kExitUsage;
  }
  if (args.synthetic) {
    spec.set_source(v1::AtlasImport::SYNTHETIC);
  } else if (!args.plates.empty()) {
    spec.set_source(v1::AtlasImport::PLATES);
    if (!fs::exists(fs::path(args.plates) / "plates.json")) {
      std::fprintf(stderr, "pba: %s has no plates.json: not a plate directory\n",
                   args.plates.c_str());
      return kExitUsage;
    }
    files = PlateFiles(args.plates);
  } else {
    spec.set_source(v1::AtlasImport::LABEL_VOLUME);
    files.push_back(args.labels);
    if (!args.colour_table.empty()) {
      files.push_back(args.colour_table);
      spec.set_colour_table(fs::path(args.colour_table).filename().string());
    }
  }
  for (const fs::path& file : files) {
    std::string upload_id;
    if (int code = UploadFile(connection, file.string(), &upload_id); code != kExitOk) return code;
    v1::ImportFile* f = spec.add_files();
    f->set_name(file.filename().string());
    f->set_upload_id(upload_id);
  }
  request.set_request_id(RequestIdOr(args.request_id));
  v1::Job job;
  {
    auto context = connection.UnaryContext();
    grpc::Status status = connection.jobs().SubmitJob(context.get(), request, &job);
    if (!status.ok()) return connection.Fail("importing into " + args.project, status);
  }
  if (!connection.options().json) {
    std::printf("Submitted import job %s (%zu file%s uploaded)\n", job.id().c_str(), files.size(),
                files.size() == 1 ? "" : "s");
    std::fflush(stdout);
  } else if (!args.wait) {
    PrintJson(job);
  }
  if (!args.wait) return kExitOk;
  return WaitForJob(connection, job.id());
}

int ExportAtlas(Connection& connection, const std::string& project, const std::string& snapshot,
                const std::string& dir) {
  return ExportSnapshot(connection, project, snapshot, dir);
}

void RegisterImportExportCommands(CLI::App& atlas, CommandContext& context) {
  struct ImportCommandArgs {
    ImportArgs args;
    bool no_wait = false;
  };
  auto import_args = std::make_shared<ImportCommandArgs>();
  ImportArgs& args = import_args->args;
  CLI::App* import_cmd = atlas.add_subcommand(
      "import", "Import an atlas into a project as a job: its structures and a snapshot of them");
  context.AddProjectOption(import_cmd, &args.project);
  import_cmd->add_flag("--synthetic", args.synthetic, "The built-in synthetic atlas");
  import_cmd->add_option("--plates", args.plates, "A plate directory (plates.json)")
      ->check(CLI::ExistingDirectory);
  import_cmd->add_option("--labels", args.labels, "A label volume (.nii, .nii.gz, .nrrd)")
      ->check(CLI::ExistingFile);
  import_cmd
      ->add_option("--colour-table", args.colour_table,
                   "With --labels: its label table (CSV); default the built-in one")
      ->check(CLI::ExistingFile);
  import_cmd->add_option("--structure", args.structures,
                         "Import only this structure (repeatable; group prefixes allowed)");
  import_cmd->add_option("--snapshot-name", args.snapshot_name,
                         "Name of the snapshot the import ends with");
  import_cmd->add_option("-m,--message", args.message, "Message of the new revisions");
  import_cmd->add_option("--request-id", args.request_id,
                         "Idempotency key: a repeated import with it returns the same job");
  import_cmd->add_flag("--no-wait", import_args->no_wait,
                       "Submit and return; do not follow the job");
  context.Add(import_cmd, [import_args](Connection& c) {
    import_args->args.wait = !import_args->no_wait;
    return ImportAtlas(c, import_args->args);
  });

  struct ExportArgs {
    std::string project, which, dir;
  };
  auto out = std::make_shared<ExportArgs>();
  CLI::App* export_cmd = atlas.add_subcommand(
      "export", "Download a snapshot as a structure set (manifest.json + one file per structure)");
  context.AddProjectOption(export_cmd, &out->project);
  export_cmd->add_option("snapshot", out->which, "Id or tag")->required();
  export_cmd->add_option("-o,--out", out->dir, "New directory to write")->required();
  context.Add(export_cmd,
              [out](Connection& c) { return ExportAtlas(c, out->project, out->which, out->dir); });
}

}  // namespace pba::cli
