// The built-in tissue libraries: every structure of the built-in atlas has
// a valid material in each, the rat-brain Prony series is the table's, the
// errors are the documented ones, and docs/materials.md prints the code's
// own numbers.

#include "material/tissue_library.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include "atlas/colour_table.h"
#include "material/factory.h"
#include "material/viscoelastic.h"

namespace pba {
namespace {

TEST(TissueLibraryTest, NamesAreKnown) {
  const std::vector<std::string> names = TissueLibraryNames();
  ASSERT_EQ(names.size(), 2u);
  EXPECT_EQ(names[0], "rat-brain-prony");
  EXPECT_EQ(names[1], "brain-ogden-qlv");
  for (const std::string& name : names) EXPECT_TRUE(CheckLibraryName(name).ok()) << name;
}

// The relaxation of a library material as a normalised Prony series, checked.
PronySeries SeriesOf(const MaterialSpec& m) {
  const ViscoelasticSpec& v = m.viscoelastic;
  PronySeries series = v.form == ViscoelasticSpec::Form::kModuli
                           ? FromModuli(v.long_term_modulus_pa, v.moduli_pa, v.tau_s)
                           : PronySeries{v.g, v.tau_s};
  const Status status = series.Validate(m.name);
  EXPECT_TRUE(status.ok()) << status.ToString();
  return series;
}

TEST(TissueLibraryTest, EveryAtlasStructureHasAValidMaterial) {
  const ColourTable& table = ColourTable::Builtin();
  ASSERT_EQ(table.size(), kNumAtlasLabels);
  for (const std::string& library : TissueLibraryNames()) {
    for (const ColourEntry& entry : table.entries()) {
      SCOPED_TRACE(library + " / " + entry.name);
      MaterialSpec material;
      std::string source;
      const Status status = LibraryMaterial(library, entry.name, &material, &source);
      ASSERT_TRUE(status.ok()) << status.ToString();
      const Status valid = ValidateMaterialSpec(material, "material");
      EXPECT_TRUE(valid.ok()) << valid.ToString();
      EXPECT_TRUE(material.hyperelastic());
      EXPECT_FALSE(source.empty());
      EXPECT_EQ(source.find('\n'), std::string::npos);  // one line
      EXPECT_GT(material.density_kg_per_m3, 1000);
      if (entry.label == kVentricles) {
        EXPECT_FALSE(material.viscoelastic.enabled());
        EXPECT_NE(source.find("modelling assumption"), std::string::npos);
      } else {
        ASSERT_TRUE(material.viscoelastic.enabled());
        SeriesOf(material);
      }
    }
  }
}

TEST(TissueLibraryTest, CortexRelaxesAsTheRatBrainTable) {
  MaterialSpec cortex;
  std::string source;
  ASSERT_TRUE(LibraryMaterial("rat-brain-prony", "Cortical areas", &cortex, &source).ok());
  EXPECT_NE(source.find("cortex"), std::string::npos);
  EXPECT_EQ(cortex.kind, MaterialSpec::Kind::kNeoHookean);
  EXPECT_EQ(cortex.neo_hookean.shear_modulus_pa, 2200);  // G0 = 433 + 1113 + 393 + 261 Pa
  EXPECT_EQ(cortex.neo_hookean.bulk_modulus_pa, 1000 * 2200);
  EXPECT_EQ(cortex.density_kg_per_m3, 1040);
  ASSERT_EQ(cortex.viscoelastic.form, ViscoelasticSpec::Form::kModuli);

  const PronySeries series = SeriesOf(cortex);
  const double t = 0.1;  // [s]
  const double expected =
      (433 + 1113 * std::exp(-t / 0.019) + 393 * std::exp(-t / 0.314) + 261 * std::exp(-t / 4.92)) /
      2200;
  EXPECT_NEAR(series.Relaxation(t), expected, 1e-12);
  EXPECT_NEAR(series.LongTermFactor(), 433.0 / 2200, 1e-15);
}

TEST(TissueLibraryTest, StructuresTakeTheirNearestRegion) {
  const auto shear = [](const std::string& structure) {
    MaterialSpec m;
    const Status status = LibraryMaterial("rat-brain-prony", structure, &m, nullptr);
    EXPECT_TRUE(status.ok()) << structure << ": " << status.ToString();
    return m.neo_hookean.shear_modulus_pa;
  };
  EXPECT_EQ(shear("Hippocampus"), 528 + 1897 + 636 + 439);
  EXPECT_EQ(shear("Hippocampal gyrus"), 528 + 1897 + 636 + 439);
  EXPECT_EQ(shear("Thalamus: pulvinar"), 347 + 1533 + 464 + 312);
  EXPECT_EQ(shear("Hypothalamus: VM"), 347 + 1533 + 464 + 312);
  EXPECT_EQ(shear("Corpus callosum"), 208 + 1249 + 381 + 230);
  EXPECT_EQ(shear("White matter"), 208 + 1249 + 381 + 230);
  EXPECT_EQ(shear("Fornix"), 208 + 1249 + 381 + 230);
  EXPECT_EQ(shear("Substantia nigra"), 240 + 1387 + 353 + 217);
  EXPECT_EQ(shear("Middle temporal gyrus"), 2200);

  std::string source;
  ASSERT_TRUE(LibraryMaterial("rat-brain-prony", "Putamen", nullptr, &source).ok());
  EXPECT_NE(source.find("assumed: grey matter"), std::string::npos) << source;
}

TEST(TissueLibraryTest, OgdenLibraryIsTheValidationTissue) {
  MaterialSpec m;
  ASSERT_TRUE(LibraryMaterial("brain-ogden-qlv", "Thalamus: others", &m, nullptr).ok());
  ASSERT_EQ(m.kind, MaterialSpec::Kind::kOgden);
  ASSERT_EQ(m.ogden.terms.size(), 1u);
  EXPECT_EQ(m.ogden.terms[0].mu_pa, 842);
  EXPECT_EQ(m.ogden.terms[0].alpha, -4.7);
  EXPECT_EQ(m.ogden.bulk_modulus_pa, 842000);
  ASSERT_EQ(m.viscoelastic.form, ViscoelasticSpec::Form::kProny);
  EXPECT_EQ(m.viscoelastic.g, (std::vector<double>{0.450, 0.365}));
  EXPECT_EQ(m.viscoelastic.tau_s, (std::vector<double>{0.5, 50}));
}

TEST(TissueLibraryTest, VentriclesAreASoftFluidStandIn) {
  for (const std::string& library : TissueLibraryNames()) {
    MaterialSpec m;
    ASSERT_TRUE(LibraryMaterial(library, "Ventricles", &m, nullptr).ok());
    EXPECT_EQ(m.kind, MaterialSpec::Kind::kNeoHookean);
    EXPECT_EQ(m.neo_hookean.shear_modulus_pa, 10);
    EXPECT_EQ(m.neo_hookean.bulk_modulus_pa, 50);
  }
}

TEST(TissueLibraryTest, UnknownLibraryAndStructure) {
  MaterialSpec m;
  Status status = LibraryMaterial("pig-brain", "Putamen", &m, nullptr);
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(status.field(), "material_library");
  EXPECT_NE(status.message().find("unknown library \"pig-brain\""), std::string::npos);
  EXPECT_NE(status.message().find("known: rat-brain-prony, brain-ogden-qlv"), std::string::npos)
      << status.message();
  EXPECT_EQ(CheckLibraryName("pig-brain").field(), "material_library");
  EXPECT_EQ(CheckLibraryName("").code(), Status::Code::kInvalidArgument);

  status = LibraryMaterial("rat-brain-prony", "Cerebellum", &m, nullptr);
  EXPECT_EQ(status.code(), Status::Code::kNotFound);
  EXPECT_NE(status.message().find("Cerebellum"), std::string::npos);
  // Exact names only: a group name is not a structure.
  EXPECT_EQ(LibraryMaterial("rat-brain-prony", "Thalamus", &m, nullptr).code(),
            Status::Code::kNotFound);
  EXPECT_TRUE(TissueLibraryMarkdown("pig-brain").empty());
}

// docs/materials.md prints each library's table as TissueLibraryMarkdown()
// makes it, so the page's numbers are the code's.
TEST(TissueLibraryTest, DocumentationCarriesTheTables) {
  std::ifstream in(PBA_MATERIALS_DOC);
  ASSERT_TRUE(in) << PBA_MATERIALS_DOC;
  std::stringstream text;
  text << in.rdbuf();
  for (const std::string& library : TissueLibraryNames()) {
    const std::string table = TissueLibraryMarkdown(library);
    ASSERT_FALSE(table.empty());
    EXPECT_NE(text.str().find(table), std::string::npos)
        << "docs/materials.md lacks the table of " << library << ":\n"
        << table;
  }
}

}  // namespace
}  // namespace pba
