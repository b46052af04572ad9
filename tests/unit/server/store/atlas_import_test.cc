// AtlasStore::Import (an atlas import's last step) and SnapshotFiles (what
// a job against a snapshot is built from).
#include "unit/server/store/atlas_store_fixture.h"

namespace pba::store_test {
namespace {

class AtlasImportTest : public AtlasStoreTest {
 protected:
  // Two structures' geometry files in the temporary directory.
  std::vector<ImportedStructure> TwoStructures() {
    std::vector<ImportedStructure> out;
    for (const char* name : {"Putamen", "Thalamus: anterior"}) {
      ImportedStructure s;
      s.name = name;
      s.metadata = Metadata();
      s.metadata.colour.r = out.empty() ? 10 : 20;
      s.format = StructureFormat::kContours;
      s.file = dir_.path() / (std::string(name) + ".json");
      std::ofstream(s.file) << "{\"plates\": \"" << name << "\"}";
      out.push_back(s);
    }
    return out;
  }

  int64_t CountRows(const std::string& table) {
    std::unique_ptr<Database> db;
    EXPECT_TRUE(Database::Open(dir_.path() / "pba.db", &db).ok());
    Statement stmt;
    EXPECT_TRUE(db->Prepare("SELECT COUNT(*) FROM " + table, &stmt).ok());
    bool row = false;
    EXPECT_TRUE(stmt.Step(&row).ok());
    return stmt.ColumnInt(0);
  }
};

TEST_F(AtlasImportTest, CreatesStructuresAndASnapshotOfTheProject) {
  SnapshotInfo snapshot;
  bool replayed = true;
  ASSERT_OK(store_->Import("bob", "atlas", "job1", TwoStructures(), "imported", "from plates",
                           &snapshot, &replayed));
  EXPECT_FALSE(replayed);
  EXPECT_EQ(snapshot.name, "imported");
  EXPECT_EQ(snapshot.author, "bob");
  // The new structures and the one the project had.
  ASSERT_EQ(snapshot.revisions.size(), 3u);
  EXPECT_EQ(snapshot.revisions.at("Putamen"), 1);
  EXPECT_EQ(snapshot.revisions.at("Thalamus: anterior"), 1);
  EXPECT_EQ(snapshot.revisions.at("hippocampus"), 1);
  Revision revision;
  std::string geometry;
  ASSERT_OK(store_->GetRevision("carol", {"atlas", "Putamen"}, 1, &revision, &geometry));
  EXPECT_EQ(geometry, "{\"plates\": \"Putamen\"}");
  EXPECT_EQ(revision.message, "from plates");
  EXPECT_EQ(revision.metadata.colour.r, 10);
  EXPECT_EQ(revision.kind, "create");
}

TEST_F(AtlasImportTest, AgainWithTheSameJobReturnsTheSnapshotAndWritesNothing) {
  SnapshotInfo first, second;
  bool replayed = false;
  ASSERT_OK(
      store_->Import("bob", "atlas", "job1", TwoStructures(), "imported", "m", &first, &replayed));
  const int64_t audit = CountRows("audit_log");
  const int64_t revisions = CountRows("structure_revisions");
  ASSERT_OK(
      store_->Import("bob", "atlas", "job1", TwoStructures(), "imported", "m", &second, &replayed));
  EXPECT_TRUE(replayed);
  EXPECT_EQ(second.id, first.id);
  EXPECT_EQ(CountRows("audit_log"), audit);
  EXPECT_EQ(CountRows("structure_revisions"), revisions);
}

TEST_F(AtlasImportTest, AnExistingStructureRefusesTheWholeImport) {
  std::vector<ImportedStructure> structures = TwoStructures();
  structures[1].name = "hippocampus";
  const int64_t structures_before = CountRows("structures");
  const int64_t snapshots_before = CountRows("snapshots");
  SnapshotInfo snapshot;
  bool replayed = false;
  EXPECT_STATUS(store_->Import("bob", "atlas", "job2", structures, "s", "m", &snapshot, &replayed),
                Status::Code::kFailedPrecondition, "'hippocampus'");
  EXPECT_EQ(CountRows("structures"), structures_before);
  EXPECT_EQ(CountRows("snapshots"), snapshots_before);
}

TEST_F(AtlasImportTest, NeedsTheEditorRole) {
  SnapshotInfo snapshot;
  bool replayed = false;
  EXPECT_STATUS(
      store_->Import("carol", "atlas", "job3", TwoStructures(), "s", "m", &snapshot, &replayed),
      Status::Code::kPermissionDenied, "");
  EXPECT_STATUS(
      store_->Import("dave", "atlas", "job3", TwoStructures(), "s", "m", &snapshot, &replayed),
      Status::Code::kPermissionDenied, "");
}

TEST_F(AtlasImportTest, AMissingFileWritesNothing) {
  std::vector<ImportedStructure> structures = TwoStructures();
  structures[1].file = dir_.path() / "missing.json";
  const int64_t before = CountRows("structures");
  SnapshotInfo snapshot;
  bool replayed = false;
  EXPECT_STATUS(store_->Import("bob", "atlas", "job4", structures, "s", "m", &snapshot, &replayed),
                Status::Code::kIo, "missing.json");
  EXPECT_EQ(CountRows("structures"), before);
}

TEST_F(AtlasImportTest, SnapshotFilesNameVerifiedBlobsOfThePinnedRevisions) {
  SnapshotInfo snapshot;
  bool replayed = false;
  ASSERT_OK(
      store_->Import("bob", "atlas", "job5", TwoStructures(), "s", "m", &snapshot, &replayed));
  std::vector<SnapshotFile> files;
  ASSERT_OK(store_->SnapshotFiles("carol", "atlas", snapshot.id, &files));
  ASSERT_EQ(files.size(), 3u);
  for (const SnapshotFile& file : files) {
    EXPECT_EQ(file.revision.number, 1);
    std::ifstream in(file.blob, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(Hash(bytes), file.revision.content_sha256) << file.revision.structure;
  }
  const fs::path blob = files[0].blob;
  // Outsiders see nothing.
  EXPECT_STATUS(store_->SnapshotFiles("dave", "atlas", snapshot.id, &files),
                Status::Code::kPermissionDenied, "");
  // A damaged blob is an error, not a wrong atlas.
  fs::permissions(blob, fs::perms::owner_write, fs::perm_options::add);
  {
    std::ofstream damage(blob, std::ios::binary | std::ios::trunc);
    damage << "not what was committed";
    ASSERT_TRUE(damage.good());
  }
  EXPECT_STATUS(store_->SnapshotFiles("carol", "atlas", snapshot.id, &files), Status::Code::kIo,
                "damaged");
}

}  // namespace
}  // namespace pba::store_test
