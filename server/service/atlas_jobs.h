// AtlasJobs: the server's part of jobs on the atlas store (JobPreparation).
//
// A scene run against a snapshot: before pba-solve starts, the snapshot's
// geometry files are copied from the blob store into <job>/snapshot/ with a
// structure-set manifest (solver/atlas/structure_set.h), and the scene's
// atlas source is pointed there, so pba-solve builds the atlas from exactly
// the revisions the snapshot pins (and anyone can rerun it from an export
// of the same snapshot).
//
// An atlas import: its source files were placed in <job>/source/ when it
// was submitted (StageImportSource); pba-solve splits them into a structure
// set (--import-atlas); when it succeeded, every file is checked as a
// commit would check it and AtlasStore::Import creates the structures and
// a snapshot in one transaction, which a rerun after a crash finds instead
// of importing twice. The snapshot's id goes into the job.
//
// Job state changes of jobs on a project are announced to the project's
// atlas watchers (PublishJobEvent).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "jobs/job_executor.h"
#include "pba/v1/atlas.pb.h"
#include "service/atlas_event_hub.h"
#include "store/atlas_store.h"
#include "store/job_store.h"
#include "store/upload_store.h"

namespace pba {

class AtlasJobs : public JobPreparation {
 public:
  AtlasJobs(AtlasStore& store, AtlasEventHub& atlas_hub, JobStore& jobs)
      : store_(store), atlas_hub_(atlas_hub), jobs_(jobs) {}

  Status Stage(const v1::Job& job, const std::filesystem::path& dir, v1::Scene* scene,
               std::vector<std::string>* input) override;
  Status Complete(const v1::Job& job, const std::filesystem::path& result_dir,
                  RunOutcome* outcome) override;

  // Announces a state change of a job on a project (one against a snapshot
  // or an import) to the project's watchers; progress events are not.
  void PublishJobEvent(const v1::JobEvent& event);

 private:
  Status StageSnapshot(const v1::Job& job, const std::filesystem::path& dir, v1::Scene* scene);
  Status StageImport(const v1::Job& job, const std::filesystem::path& dir,
                     std::vector<std::string>* input);

  AtlasStore& store_;
  AtlasEventHub& atlas_hub_;
  JobStore& jobs_;
};

// Writes `files` (a snapshot's members, or the heads) into `set_dir` as a
// structure set (solver/atlas/structure_set.h) whose manifest names
// `project` and `snapshot` (0: none): what pba-solve builds an atlas from.
// `set_dir` is emptied first.
Status WriteStructureSetOf(const std::vector<SnapshotFile>& files, const std::string& project,
                           int64_t snapshot, const std::filesystem::path& set_dir);

// Checks an import request (names the field in its errors): a project, a
// source kind, plain file names, the files the kind needs.
Status CheckAtlasImport(const v1::AtlasImport& request);

// Takes the import's uploads (each checked against its announced hash) into
// `dir`/<file name>, which must not exist, as second names of their files
// (synced); on any error nothing is left there. The uploads stay until
// RemoveImportUploads, so a submit that fails later can be retried.
Status StageImportSource(UploadStore& uploads, const std::string& user,
                         const v1::AtlasImport& request, const std::filesystem::path& dir);

// Removes the import's uploads once its job is stored.
void RemoveImportUploads(UploadStore& uploads, const std::string& user,
                         const v1::AtlasImport& request);

}  // namespace pba
