#include "service/atlas_jobs.h"

#include <google/protobuf/util/time_util.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cstdint>
#include <set>
#include <system_error>

#include "atlas/derived_structure.h"
#include "atlas/label_volume_io.h"
#include "atlas/structure_set.h"
#include "core/atomic_write.h"
#include "service/geometry_check.h"
#include "store/mapped_file.h"

namespace pba {
namespace fs = std::filesystem;
namespace {

bool IsPlainFileName(const std::string& name) {
  return !name.empty() && name.size() <= 255 && name != "." && name != ".." &&
         name.find('/') == std::string::npos && name.find('\0') == std::string::npos;
}

bool EndsWith(const std::string& text, const std::string& end) {
  return text.size() >= end.size() && text.compare(text.size() - end.size(), end.size(), end) == 0;
}

bool IsVolumeFile(const std::string& name) {
  return EndsWith(name, ".nii") || EndsWith(name, ".nii.gz") || EndsWith(name, ".nrrd");
}

// The file name stem of a structure's geometry in a staged structure set:
// the name with characters other than [A-Za-z0-9._-] as '_'.
std::string FileStemFor(const std::string& structure) {
  std::string stem;
  for (char c : structure) {
    const bool keep = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                      c == '-' || c == '.' || c == '_';
    stem.push_back(keep ? c : '_');
  }
  return stem;
}

// "<group>: <name>" names (the thalamic nuclei of the built-in atlas) go
// into the group "<group>".
std::string GroupOf(const std::string& name) {
  const size_t colon = name.find(": ");
  return colon == std::string::npos ? "" : name.substr(0, colon);
}

}  // namespace

Status CheckAtlasImport(const v1::AtlasImport& request) {
  if (request.project().empty()) {
    return Status::InvalidArgument("atlas_import.project", "required");
  }
  std::set<std::string> names;
  for (int i = 0; i < request.files_size(); ++i) {
    const v1::ImportFile& file = request.files(i);
    const std::string field = "atlas_import.files[" + std::to_string(i) + "]";
    if (!IsPlainFileName(file.name())) {
      return Status::InvalidArgument(field + ".name",
                                     "must be a plain file name without directories");
    }
    if (!names.insert(file.name()).second) {
      return Status::InvalidArgument(field + ".name", "another file has this name");
    }
    if (file.upload_id().empty()) return Status::InvalidArgument(field + ".upload_id", "required");
  }
  if (!request.colour_table().empty() && names.count(request.colour_table()) == 0) {
    return Status::InvalidArgument("atlas_import.colour_table", "is not one of the files");
  }
  switch (request.source()) {
    case v1::AtlasImport::SYNTHETIC:
      if (!names.empty()) {
        return Status::InvalidArgument("atlas_import.files",
                                       "the synthetic atlas is built in: send no files");
      }
      break;
    case v1::AtlasImport::PLATES:
      if (names.count("plates.json") == 0) {
        return Status::InvalidArgument("atlas_import.files",
                                       "a plate directory needs its plates.json (and the files "
                                       "it names)");
      }
      break;
    case v1::AtlasImport::LABEL_VOLUME: {
      int volumes = 0;
      for (const std::string& name : names) volumes += IsVolumeFile(name) ? 1 : 0;
      if (volumes != 1) {
        return Status::InvalidArgument(
            "atlas_import.files",
            "a label volume import needs exactly one .nii, .nii.gz or .nrrd file, not " +
                std::to_string(volumes));
      }
      break;
    }
    default:
      return Status::InvalidArgument("atlas_import.source",
                                     "required: SYNTHETIC, PLATES or LABEL_VOLUME");
  }
  return Status::Ok();
}

namespace {

// A refused Take of the import's file `i`, naming its field.
Status TakeRefused(int i, const Status& taken) {
  const std::string field = "atlas_import.files[" + std::to_string(i) + "].upload_id";
  switch (taken.code()) {
    case Status::Code::kInvalidArgument:
      return Status::InvalidArgument(field, taken.message());
    case Status::Code::kNotFound:
      return Status::NotFound(field + ": " + taken.message());
    case Status::Code::kFailedPrecondition:
      return Status::FailedPrecondition(field + ": " + taken.message());
    default:
      return taken;
  }
}

}  // namespace

Status StageImportSource(UploadStore& uploads, const std::string& user,
                         const v1::AtlasImport& request, const fs::path& dir) {
  return AtomicWriteDirectory(dir, [&](const fs::path& staging) -> Status {
    for (int i = 0; i < request.files_size(); ++i) {
      const v1::ImportFile& file = request.files(i);
      std::unique_ptr<MappedFile> content;
      const Status taken = uploads.Take(user, file.upload_id(), &content);
      if (!taken.ok()) return TakeRefused(i, taken);
      // A second name for the checked bytes (a complete upload takes no more
      // writes), so nothing is copied and a refused submit leaves every
      // upload as it was; a copy where a link cannot be made.
      // The chunks were written without fsync: on disk before the job is.
      if (::fsync(content->fd()) != 0) {
        return Status::Io("cannot sync the upload of " + file.name());
      }
      std::error_code ec;
      fs::create_hard_link(content->path(), staging / file.name(), ec);
      if (ec) PBA_RETURN_IF_ERROR(AtomicWriteText(staging / file.name(), content->bytes()));
    }
    return Status::Ok();  // AtomicWriteDirectory syncs the directory, then its parent
  });
}

void RemoveImportUploads(UploadStore& uploads, const std::string& user,
                         const v1::AtlasImport& request) {
  for (const v1::ImportFile& file : request.files()) {
    const Status removed = uploads.Remove(user, file.upload_id());
    if (!removed.ok()) {
      spdlog::warn("cannot remove upload {}: {}", file.upload_id(), removed.ToString());
    }
  }
}

Status AtlasJobs::Stage(const v1::Job& job, const fs::path& dir, v1::Scene* scene,
                        std::vector<std::string>* input) {
  if (job.has_atlas_import()) return StageImport(job, dir, input);
  if (!job.snapshot().project().empty()) return StageSnapshot(job, dir, scene);
  return Status::Ok();
}

Status WriteStructureSetOf(const std::vector<SnapshotFile>& files, const std::string& project,
                           int64_t snapshot, const fs::path& set_dir) {
  std::error_code ec;
  fs::remove_all(set_dir, ec);
  fs::create_directories(set_dir, ec);
  if (ec) return Status::Io("cannot create " + set_dir.string() + ": " + ec.message());
  // The manifest names the snapshot (the result says what it was built
  // from); the mesh cache keys a set by its structures alone, so two
  // snapshots pinning the same revisions share one mesh.
  StructureSet set;
  set.project = project;
  set.snapshot = snapshot;
  // Two names that map to one file name ("a b" and "a_b", "Foo" and
  // "foo") get a number, and a structure named "manifest" does not take
  // the manifest's name.
  StructureFileNames names;
  std::set<uint32_t> colours;
  for (const SnapshotFile& file : files) {
    const Revision& r = file.revision;
    const std::string name = names.Take(
        FileStemFor(r.structure), StructureFormatExtension(r.format, HasGzipMagic(file.blob)));
    fs::copy_file(file.blob, set_dir / name, fs::copy_options::overwrite_existing, ec);
    if (ec) return Status::Io("cannot copy the geometry of " + r.structure + ": " + ec.message());
    StructureEntry entry;
    entry.name = r.structure;
    entry.file = name;
    entry.format = r.format;
    // A structure set needs a colour per structure, distinct and not black
    // (structure_set.h); the store lets two structures share one, so a
    // repeat is moved to the nearest free colour for the build.
    uint32_t rgb = (static_cast<uint32_t>(r.metadata.colour.r) << 16) |
                   (static_cast<uint32_t>(r.metadata.colour.g) << 8) |
                   static_cast<uint32_t>(r.metadata.colour.b);
    while (rgb == 0 || !colours.insert(rgb).second) rgb = (rgb + 1) & 0xffffff;
    entry.r = static_cast<uint8_t>(rgb >> 16);
    entry.g = static_cast<uint8_t>(rgb >> 8);
    entry.b = static_cast<uint8_t>(rgb);
    entry.sha256 = r.content_sha256;
    entry.revision = r.number;
    entry.group_path = r.metadata.group_path;
    entry.material_json = r.metadata.material_json;
    set.structures.push_back(std::move(entry));
  }
  return WriteStructureSet(set, set_dir);
}

Status AtlasJobs::StageSnapshot(const v1::Job& job, const fs::path& dir, v1::Scene* scene) {
  const v1::SnapshotRef& ref = job.snapshot();
  int64_t id = 0;
  try {
    id = std::stoll(ref.snapshot());
  } catch (const std::exception&) {
    return Status::Internal("job " + job.id() + " names snapshot '" + ref.snapshot() +
                            "', not an id");
  }
  std::vector<SnapshotFile> files;
  PBA_RETURN_IF_ERROR(store_.SnapshotFiles(job.owner(), ref.project(), id, &files));
  if (files.empty()) {
    return Status::FailedPrecondition("snapshot " + ref.snapshot() + " of project " +
                                      ref.project() + " has no structures to build an atlas from");
  }
  const fs::path set_dir = dir / "snapshot";
  PBA_RETURN_IF_ERROR(WriteStructureSetOf(files, ref.project(), id, set_dir));
  scene->mutable_geometry()->mutable_atlas()->set_source(set_dir.string());
  return Status::Ok();
}

Status AtlasJobs::StageImport(const v1::Job& job, const fs::path& dir,
                              std::vector<std::string>* input) {
  const v1::AtlasImport& request = job.atlas_import();
  const fs::path source = dir / "source";
  std::error_code ec;
  if (request.source() != v1::AtlasImport::SYNTHETIC && !fs::is_directory(source, ec)) {
    return Status::FailedPrecondition(
        "the import's source files are missing (the server stopped while taking them in): "
        "submit the import again");
  }
  *input = {"--import-atlas"};
  switch (request.source()) {
    case v1::AtlasImport::SYNTHETIC:
      input->push_back("synthetic");
      break;
    case v1::AtlasImport::PLATES:
      input->insert(input->end(), {"plates", "--import-source", source.string()});
      break;
    case v1::AtlasImport::LABEL_VOLUME:
      input->push_back("labels");
      for (const v1::ImportFile& file : request.files()) {
        if (IsVolumeFile(file.name())) {
          input->insert(input->end(), {"--import-source", (source / file.name()).string()});
        }
      }
      if (!request.colour_table().empty()) {
        input->insert(input->end(), {"--colour-table", (source / request.colour_table()).string()});
      }
      break;
    default:
      return Status::InvalidArgument("atlas_import.source", "unknown");
  }
  for (const std::string& structure : request.structures()) {
    // One argument, so that no name can read as an option.
    input->push_back("--structure=" + structure);
  }
  return Status::Ok();
}

Status AtlasJobs::Complete(const v1::Job& job, const fs::path& result_dir, RunOutcome* outcome) {
  if (!job.has_atlas_import()) return Status::Ok();
  const v1::AtlasImport& request = job.atlas_import();
  const fs::path set_dir = result_dir / "structures";
  StructureSet set;
  PBA_RETURN_IF_ERROR(ReadStructureSet(set_dir, &set));
  std::vector<ImportedStructure> structures;
  std::vector<std::string> base;
  std::vector<DerivedStructure> derived;
  for (size_t i = 0; i < set.structures.size(); ++i) {
    const StructureEntry& entry = set.structures[i];
    ImportedStructure s;
    s.name = entry.name;
    s.file = set_dir / entry.file;
    s.format = entry.format;
    s.metadata.colour = Colour{entry.r, entry.g, entry.b};
    s.metadata.group_path = entry.group_path.empty() ? GroupOf(entry.name) : entry.group_path;
    s.metadata.material_json = entry.material_json.empty() ? "{}" : entry.material_json;
    // Checked as a commit of it would be.
    std::unique_ptr<MappedFile> bytes;
    PBA_RETURN_IF_ERROR(MappedFile::Open(s.file, &bytes));
    PBA_RETURN_IF_ERROR(
        CheckGeometryContent("structure '" + entry.name + "'", s.format, bytes->bytes()));
    if (s.format == StructureFormat::kDerived) {
      PBA_RETURN_IF_ERROR(ParseDerivedStructure(
          bytes->bytes(), entry.name, "structure '" + entry.name + "'", &derived.emplace_back()));
    } else {
      base.push_back(entry.name);
    }
    structures.push_back(std::move(s));
  }
  // What derived structures read is there, as for a commit (derived_check.h).
  PBA_RETURN_IF_ERROR(OrderDerivedStructures(base, &derived));
  const std::string snapshot_name =
      request.snapshot_name().empty() ? "import " + job.id() : request.snapshot_name();
  const std::string message =
      request.message().empty() ? "imported by job " + job.id() : request.message();
  SnapshotInfo snapshot;
  bool replayed = false;
  PBA_RETURN_IF_ERROR(store_.Import(job.owner(), request.project(), job.id(), structures,
                                    snapshot_name, message, &snapshot, &replayed));
  outcome->snapshot.set_project(request.project());
  outcome->snapshot.set_snapshot(std::to_string(snapshot.id));
  outcome->message = "imported " + std::to_string(structures.size()) + " structures into " +
                     request.project() + ", snapshot " + std::to_string(snapshot.id);
  if (replayed) return Status::Ok();
  const auto now = google::protobuf::util::TimeUtil::GetCurrentTime();
  for (const ImportedStructure& s : structures) {
    v1::AtlasEvent event;
    event.set_kind(v1::AtlasEvent::STRUCTURE_CREATED);
    event.set_project(request.project());
    event.set_structure(s.name);
    event.set_revision(1);
    event.set_user(job.owner());
    *event.mutable_time() = now;
    event.set_detail(message);
    atlas_hub_.Publish(event);
  }
  v1::AtlasEvent event;
  event.set_kind(v1::AtlasEvent::SNAPSHOT_CREATED);
  event.set_project(request.project());
  event.set_snapshot(snapshot.id);
  event.set_user(job.owner());
  *event.mutable_time() = now;
  event.set_detail(snapshot_name);
  atlas_hub_.Publish(event);
  return Status::Ok();
}

void AtlasJobs::PublishJobEvent(const v1::JobEvent& event) {
  // Progress is for the job's own watchers; a project's watchers hear of
  // the job once per state.
  if (event.state() == v1::Job::RUNNING && !event.phase().empty()) return;
  v1::Job job;
  bool found = false;
  if (!jobs_.GetJob(event.job_id(), JobView::kBasic, &job, &found).ok() || !found) return;
  std::string project = job.snapshot().project();
  if (job.has_atlas_import()) project = job.atlas_import().project();
  if (project.empty()) return;
  v1::AtlasEvent out;
  out.set_kind(v1::AtlasEvent::JOB_STATE_CHANGED);
  out.set_project(project);
  out.set_user(job.owner());
  *out.mutable_time() = event.time();
  out.set_detail(event.message());
  out.set_job_id(event.job_id());
  out.set_job_state(v1::Job::State_Name(event.state()));
  if (!job.snapshot().snapshot().empty()) {
    try {
      out.set_snapshot(std::stoll(job.snapshot().snapshot()));
    } catch (const std::exception&) {
    }
  }
  atlas_hub_.Publish(out);
}

}  // namespace pba
