// Derived structures in the store through the real service
// (derived_check.h): created and committed like any structure, refused
// when what they read is not there at their turn (naming it), never
// checked for overlap with locked neighbours, and compared by recipe only.
#include "unit/server/service/atlas_service_fixture.h"

namespace pba::service_test {
namespace {

class DerivedStructureServiceTest : public AtlasServiceTest {
 protected:
  void SetUp() override {
    AtlasServiceTest::SetUp();
    ASSERT_RPC(Create("bob", "left", Square(0, 10)));
    ASSERT_RPC(Create("bob", "right", Square(20, 30)));
  }
  grpc::Status Derive(const std::string& name, const std::string& recipe,
                      v1::Revision* revision = nullptr) {
    return Create("bob", name, recipe, revision, v1::DERIVED);
  }
};

TEST_F(DerivedStructureServiceTest, ARecipeIsCheckedAgainstTheProjectsStructures) {
  v1::Revision revision;
  ASSERT_RPC(Derive("both", "merge: [left, right]", &revision));
  EXPECT_EQ(revision.format(), v1::DERIVED);
  // What it reads must be there...
  EXPECT_CODE(Derive("bad", "merge: [left, nowhere]"), grpc::StatusCode::INVALID_ARGUMENT,
              "derived structure 'bad' reads 'nowhere', which is not among the structures");
  // ... and not taken by a merge before it.
  EXPECT_CODE(Derive("cavity", "cut: {around: {structures: [left], margin_mm: 2}}"),
              grpc::StatusCode::INVALID_ARGUMENT, "which the merge 'both' takes before it");
  // Cuts come after merges: one may read a merge.
  ASSERT_RPC(Derive("cavity", "cut: {around: {structures: [both], margin_mm: 2}}"));
  // A recipe that does not parse names the key.
  EXPECT_CODE(Derive("worse", "merge: {structures: [left], colour: red}"),
              grpc::StatusCode::INVALID_ARGUMENT, "upload_id.merge.colour");
  EXPECT_CODE(Derive("worst", "cut: {mask: /etc/passwd}"), grpc::StatusCode::INVALID_ARGUMENT,
              "reads no mask file");
  for (const char* refused : {"bad", "worse", "worst"}) {
    v1::GetStructureRequest request;
    request.set_project("atlas");
    request.set_structure(refused);
    v1::Structure structure;
    EXPECT_EQ(
        Call("carol", &v1::AtlasService::Stub::GetStructure, request, &structure).error_code(),
        grpc::StatusCode::NOT_FOUND)
        << refused;
  }
}

TEST_F(DerivedStructureServiceTest, CommitsOfRecipesAreCheckedAndDiffedByRecipeOnly) {
  ASSERT_RPC(Derive("both", "merge: [left, right]"));
  ASSERT_RPC(Derive("cavity", "cut: {around: {structures: [both]}}"));
  v1::Lock lock;
  ASSERT_RPC(Acquire("bob", &lock, "both"));
  // Merging "cavity" into "both" would read a structure made after it.
  EXPECT_CODE(
      Commit("bob", lock.lock_id(), 1, "merge: [left, cavity]", nullptr, "both", v1::DERIVED),
      grpc::StatusCode::INVALID_ARGUMENT, "a derived structure made after it");
  v1::Revision revision;
  ASSERT_RPC(Commit("bob", lock.lock_id(), 1, "merge: [left]", &revision, "both", v1::DERIVED));
  EXPECT_EQ(revision.number(), 2);

  v1::DiffRevisionsRequest request;
  request.set_project("atlas");
  request.set_structure("both");
  v1::RevisionDiff diff;
  ASSERT_RPC(Call("carol", &v1::AtlasService::Stub::DiffRevisions, request, &diff));
  EXPECT_TRUE(diff.geometry_changed());
  EXPECT_FALSE(diff.has_shape());
  EXPECT_FALSE(diff.has_contours());
}

// A derived structure has no geometry of its own: a commit is not checked
// against it when someone holds it, nor is a recipe checked against
// neighbours others hold.
TEST_F(DerivedStructureServiceTest, LockedDerivedStructuresAreNoNeighbours) {
  ASSERT_RPC(Derive("both", "merge: [left, right]"));
  v1::Lock admins_both, admins_right, bobs_left, bobs_both;
  ASSERT_RPC(Acquire("admin", &admins_both, "both"));
  ASSERT_RPC(Acquire("bob", &bobs_left, "left"));
  ASSERT_RPC(Commit("bob", bobs_left.lock_id(), 1, Square(0, 15), nullptr, "left"));
  ASSERT_RPC(Release("admin", admins_both.lock_id()));
  ASSERT_RPC(Acquire("admin", &admins_right, "right"));
  ASSERT_RPC(Acquire("bob", &bobs_both, "both"));
  ASSERT_RPC(Commit("bob", bobs_both.lock_id(), 1, "merge: [right]", nullptr, "both", v1::DERIVED));
  // The contours rule still holds between real shapes.
  EXPECT_CODE(Commit("bob", bobs_left.lock_id(), 2, Square(0, 25), nullptr, "left"),
              grpc::StatusCode::FAILED_PRECONDITION, "overlaps 'right'");
}

}  // namespace
}  // namespace pba::service_test
