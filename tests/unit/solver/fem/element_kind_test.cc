// The element-kind table (fem/element_kind.h): one row per element type,
// consistent with the mesh shapes and with what the analyses accept.
#include "fem/element_kind.h"

#include <gtest/gtest.h>

#include <set>
#include <string>

#include "common/scene_builders.h"
#include "pba/solve.h"

namespace pba {
namespace {

constexpr ElementType kAll[] = {ElementType::kTet4, ElementType::kTet4Anp,  ElementType::kTet10,
                                ElementType::kHex8, ElementType::kHex8Full, ElementType::kTet10Md};

TEST(ElementKindTest, EveryTypeHasOneRowWithItsOwnName) {
  EXPECT_EQ(ElementKinds().size(), std::size(kAll));
  std::set<std::string> names;
  for (ElementType type : kAll) {
    const ElementKind& kind = KindOf(type);
    EXPECT_EQ(kind.type, type);
    EXPECT_EQ(std::string(ElementName(type)), kind.name);
    EXPECT_TRUE(names.insert(kind.name).second) << kind.name;
  }
  EXPECT_STREQ(ElementName(ElementType::kDefault), "DEFAULT");
}

TEST(ElementKindTest, NodesAgreeWithTheMeshShapes) {
  for (ElementType type : kAll) {
    const ElementKind& kind = KindOf(type);
    EXPECT_EQ(kind.nodes == 10, IsQuadratic(type)) << kind.name;
    EXPECT_EQ(kind.nodes == 8, IsHexahedral(type)) << kind.name;
    // The peer element has the same nodes.
    EXPECT_EQ(std::string(kind.abaqus_type), "C3D" + std::to_string(kind.nodes)) << kind.name;
    // Only the explicit engine's elements have a form there.
    EXPECT_EQ(std::string(kind.explicit_form).empty(), !kind.explicit_engine) << kind.name;
  }
}

TEST(ElementKindTest, TheDefaultsAreTheOnesTheDocsName) {
  EXPECT_EQ(ResolveElement(ElementType::kDefault, AnalysisSpec::Type::kLinearStatic),
            ElementType::kTet4);
  EXPECT_EQ(ResolveElement(ElementType::kDefault, AnalysisSpec::Type::kNonlinearStatic),
            ElementType::kTet4Anp);
  EXPECT_EQ(ResolveElement(ElementType::kHex8, AnalysisSpec::Type::kLinearStatic),
            ElementType::kHex8);
  // Every default serves its analysis.
  EXPECT_TRUE(KindOf(ElementType::kTet4).linear_static);
  EXPECT_TRUE(KindOf(ElementType::kTet4Anp).finite_strain);
  EXPECT_TRUE(KindOf(ElementType::kTet4Anp).explicit_engine);
}

TEST(ElementKindTest, LockingIsTheVolumetricTreatmentPerPoint) {
  std::set<std::string> locking;
  for (const ElementKind& kind : ElementKinds()) {
    if (Locks(kind)) locking.insert(kind.name);
  }
  EXPECT_EQ(locking, (std::set<std::string>{"TET4", "TET10", "HEX8_FULL"}));
}

// What the table says each analysis takes is what validation accepts.
TEST(ElementKindTest, ValidationFollowsTheTable) {
  for (ElementType type : kAll) {
    const ElementKind& kind = KindOf(type);
    for (AnalysisSpec::Type analysis :
         {AnalysisSpec::Type::kLinearStatic, AnalysisSpec::Type::kNonlinearStatic,
          AnalysisSpec::Type::kExplicitDynamic}) {
      SceneSpec scene;
      scene.geometry.kind = GeometrySpec::Kind::kBox;
      scene.geometry.box.size_mm = {10, 10, 20};
      scene.mesh.element = type;
      if (analysis == AnalysisSpec::Type::kLinearStatic) {
        scene.material.kind = MaterialSpec::Kind::kLinearElastic;
        scene.material.linear_elastic = {3000, 0.45};
      } else {
        scene.material.kind = MaterialSpec::Kind::kNeoHookean;
        scene.material.neo_hookean = {1000, 100000};
        scene.material.density_kg_per_m3 = 1040;
      }
      scene.boundary_conditions = {
          testing::Condition("bottom", BoundaryConditionSpec::Kind::kFixed),
          testing::Condition("top", BoundaryConditionSpec::Kind::kDisplacement,
                             {std::nullopt, std::nullopt, -1.0})};
      scene.analysis.type = analysis;
      if (analysis == AnalysisSpec::Type::kExplicitDynamic) {
        scene.analysis.time.end_time_s = 1e-3;
      }
      const Status status = ValidateScene(scene);
      const bool taken = analysis == AnalysisSpec::Type::kLinearStatic      ? kind.linear_static
                         : analysis == AnalysisSpec::Type::kNonlinearStatic ? kind.finite_strain
                                                                            : kind.explicit_engine;
      if (taken) {
        EXPECT_NE(status.field(), "mesh.element") << kind.name << ": " << status.ToString();
      } else {
        EXPECT_EQ(status.field(), "mesh.element") << kind.name << ": " << status.ToString();
      }
    }
  }
}

}  // namespace
}  // namespace pba
