#include "material/tissue_library.h"

#include <cmath>
#include <cstddef>

#include "core/format.h"
#include "core/number_format.h"

namespace pba {
namespace {

constexpr char kRatBrainProny[] = "rat-brain-prony";
constexpr char kBrainOgdenQlv[] = "brain-ogden-qlv";

// Brain tissue density [kg/m^3] (DOMAIN.md section 2, rabbit parameters;
// the usual figure for brain).
constexpr double kTissueDensity = 1040;

// Bulk over shear modulus of the tissue entries [-]. DOMAIN.md puts brain
// tissue at K / mu = 1e3..1e6 (nearly incompressible, measured K about
// 2.1 GPa); the low end keeps meshes of 4-node tetrahedra usable (a
// stiffer volumetric response locks them) while Poisson's ratio is still
// 0.4995. Scenes wanting more override the structure with region_materials.
constexpr double kBulkOverShear = 1000;

// One row of the rat-brain Prony table of DOMAIN.md section 2:
// G(t) = G_inf + sum_i G_i exp(-t/tau_i) [Pa, s].
struct PronyRow {
  const char* region;
  double g_inf_pa;
  double g_pa[3];
  double tau_s[3];
};

// clang-format off
constexpr PronyRow kBrainstem      = {"brainstem & spine",         240, {1387, 353, 217}, {0.012, 0.160, 2.75}};
constexpr PronyRow kCorpusCallosum = {"corpus callosum",           208, {1249, 381, 230}, {0.015, 0.239, 4.52}};
constexpr PronyRow kHippocampus    = {"hippocampus",               528, {1897, 636, 439}, {0.017, 0.244, 4.72}};
constexpr PronyRow kCortex         = {"cortex",                    433, {1113, 393, 261}, {0.019, 0.314, 4.92}};
constexpr PronyRow kThalamus       = {"thalamus & olfactory bulb", 347, {1533, 464, 312}, {0.017, 0.318, 6.66}};
// The table's cerebellum rows (grey 189 Pa ..., white 169 Pa ...) have no
// structure in the built-in atlas, which has no cerebellum.
// clang-format on

// The brain Ogden fit of DOMAIN.md section 2 and VALIDATION.md (uniaxial
// tension and compression).
constexpr double kOgdenMu = 842;      // [Pa]
constexpr double kOgdenAlpha = -4.7;  // [-]
// Its QLV relaxation, the Prony series of VALIDATION.md "Viscoelastic ramp".
constexpr double kQlvG[2] = {0.450, 0.365};  // g_k [-]
constexpr double kQlvTau[2] = {0.5, 50};     // tau_k [s]

// The ventricles' stand-in for cerebrospinal fluid (a modelling assumption,
// not data): a solid so soft that it barely resists the tissue around it
// and, compressible (nu about 0.41), lets a ventricle shrink as fluid
// would drain from it; elastic, as the fluid has no relaxing network.
constexpr double kCsfShear = 10;      // mu [Pa]
constexpr double kCsfBulk = 50;       // K [Pa]
constexpr double kCsfDensity = 1007;  // [kg/m^3], cerebrospinal fluid

struct Group {
  std::string title;                    // e.g. "cortex"
  std::vector<std::string> structures;  // exact names of the built-in colour table
  std::string listing;                  // the structures in the docs' table; empty: their names
  MaterialSpec material;
  std::string source;
};

struct Library {
  std::string name;
  std::vector<Group> groups;
};

// A number as the tables print it: integers without a decimal point or an
// exponent, the rest in %g.
std::string Num(double v) {
  if (v == std::floor(v) && std::fabs(v) < 1e12) return Format("%.0f", v);
  return ShortNumber(v);
}

std::string Join(const double* v, std::size_t n, const char* separator) {
  std::string out;
  for (std::size_t i = 0; i < n; ++i) out += (i ? separator : "") + Num(v[i]);
  return out;
}

double InstantaneousModulus(const PronyRow& row) {
  return row.g_inf_pa + row.g_pa[0] + row.g_pa[1] + row.g_pa[2];
}

MaterialSpec RatBrainMaterial(const PronyRow& row, const std::string& title) {
  MaterialSpec m;
  m.name = std::string(kRatBrainProny) + ": " + title;
  m.kind = MaterialSpec::Kind::kNeoHookean;
  m.density_kg_per_m3 = kTissueDensity;
  m.neo_hookean.shear_modulus_pa = InstantaneousModulus(row);
  m.neo_hookean.bulk_modulus_pa = kBulkOverShear * InstantaneousModulus(row);
  m.viscoelastic.form = ViscoelasticSpec::Form::kModuli;
  m.viscoelastic.long_term_modulus_pa = row.g_inf_pa;
  m.viscoelastic.moduli_pa.assign(row.g_pa, row.g_pa + 3);
  m.viscoelastic.tau_s.assign(row.tau_s, row.tau_s + 3);
  return m;
}

std::string RatBrainSource(const PronyRow& row, const std::string& note) {
  return Format("rat brain, %s: DOMAIN.md section 2 Prony table (G_inf %s Pa; G_i %s Pa; ",
                row.region, Num(row.g_inf_pa).c_str(), Join(row.g_pa, 3, ", ").c_str()) +
         "tau_i " + Join(row.tau_s, 3, ", ") + " s)" + note;
}

Group RatBrainGroup(const PronyRow& row, const std::string& title,
                    std::vector<std::string> structures, const std::string& note = "") {
  return {title, std::move(structures), "", RatBrainMaterial(row, title),
          RatBrainSource(row, note)};
}

Group VentricleGroup(const std::string& library) {
  MaterialSpec m;
  m.name = library + ": cerebrospinal fluid stand-in";
  m.kind = MaterialSpec::Kind::kNeoHookean;
  m.density_kg_per_m3 = kCsfDensity;
  m.neo_hookean.shear_modulus_pa = kCsfShear;
  m.neo_hookean.bulk_modulus_pa = kCsfBulk;
  return {"cerebrospinal fluid stand-in",
          {"Ventricles"},
          "",
          m,
          "modelling assumption, not data: a very soft, compressible solid in place of the "
          "fluid, nearly free to collapse, not relaxing; density of cerebrospinal fluid"};
}

// Structures of the built-in atlas by the region of the rat-brain table
// nearest to them.
const std::vector<std::string> kCortexStructures = {
    "Cortical areas",          "Cuneus",
    "Inferior frontal gyrus",  "Inferior occipital gyrus",
    "Inferior temporal gyrus", "Insula",
    "Lingual gyrus",           "Medial frontal gyrus",
    "Middle frontal gyrus",    "Middle occipital gyrus",
    "Middle temporal gyrus"};
const std::vector<std::string> kBasalGangliaStructures = {
    "Globus pallidus lateralis", "Globus pallidus medialis", "Nucleus accumbens septi",
    "Nucleus caudatus",          "Nucleus subthalamicus",    "Putamen"};
const std::vector<std::string> kHippocampusStructures = {"Hippocampal gyrus", "Hippocampus"};
const std::vector<std::string> kDiencephalonStructures = {"Corpus geniculatum laterale",
                                                          "Corpus geniculatum mediale",
                                                          "Corpus mamillare",
                                                          "Hypothalamus: LAT",
                                                          "Hypothalamus: POL",
                                                          "Hypothalamus: SO",
                                                          "Hypothalamus: VM",
                                                          "Thalamus: anterior",
                                                          "Thalamus: centromedianum",
                                                          "Thalamus: dorsomedial",
                                                          "Thalamus: lateral dorsal",
                                                          "Thalamus: lateral posterior",
                                                          "Thalamus: others",
                                                          "Thalamus: pulvinar",
                                                          "Thalamus: ventral anterior",
                                                          "Thalamus: ventral lateral",
                                                          "Thalamus: ventral posterolateral",
                                                          "Thalamus: ventral posteromedial"};
const std::vector<std::string> kWhiteMatterStructures = {"Corpus callosum", "Fornix",
                                                         "White matter"};
const std::vector<std::string> kMidbrainStructures = {"Nucleus ruber (bottom)",
                                                      "Nucleus ruber (top)", "Substantia nigra"};

Library RatBrainLibrary() {
  Library lib{kRatBrainProny, {}};
  lib.groups.push_back(RatBrainGroup(kCortex, "cortex", kCortexStructures));
  lib.groups.push_back(
      RatBrainGroup(kCortex, "basal ganglia", kBasalGangliaStructures,
                    "; assumed: grey matter (the table has no basal-ganglia region; cortex row)"));
  lib.groups.push_back(RatBrainGroup(kHippocampus, "hippocampus", kHippocampusStructures));
  lib.groups.push_back(RatBrainGroup(kThalamus, "thalamus and hypothalamus",
                                     kDiencephalonStructures,
                                     "; geniculate and mamillary bodies as diencephalon"));
  lib.groups.push_back(RatBrainGroup(kCorpusCallosum, "white matter", kWhiteMatterStructures,
                                     "; fornix and white matter as callosal white matter"));
  lib.groups.push_back(
      RatBrainGroup(kBrainstem, "midbrain", kMidbrainStructures, "; midbrain nuclei as brainstem"));
  lib.groups.push_back(VentricleGroup(kRatBrainProny));
  return lib;
}

Library BrainOgdenLibrary() {
  MaterialSpec m;
  m.name = std::string(kBrainOgdenQlv) + ": brain tissue";
  m.kind = MaterialSpec::Kind::kOgden;
  m.density_kg_per_m3 = kTissueDensity;
  m.ogden.terms = {{kOgdenMu, kOgdenAlpha}};
  m.ogden.bulk_modulus_pa = kBulkOverShear * kOgdenMu;
  m.viscoelastic.form = ViscoelasticSpec::Form::kProny;
  m.viscoelastic.g.assign(kQlvG, kQlvG + 2);
  m.viscoelastic.tau_s.assign(kQlvTau, kQlvTau + 2);
  std::vector<std::string> all;
  for (const auto* list :
       {&kCortexStructures, &kBasalGangliaStructures, &kHippocampusStructures,
        &kDiencephalonStructures, &kWhiteMatterStructures, &kMidbrainStructures}) {
    all.insert(all.end(), list->begin(), list->end());
  }
  const std::string source =
      "brain, Ogden fit mu " + Num(kOgdenMu) + " Pa, alpha " + Num(kOgdenAlpha) +
      " (DOMAIN.md section 2, VALIDATION.md uniaxial table); QLV g_k " + Join(kQlvG, 2, ", ") +
      ", tau_k " + Join(kQlvTau, 2, ", ") + " s (VALIDATION.md viscoelastic ramp)";
  Library lib{kBrainOgdenQlv, {}};
  const std::string listing = Format("every structure but the ventricles (%zu)", all.size());
  lib.groups.push_back({"brain tissue", std::move(all), listing, m, source});
  lib.groups.push_back(VentricleGroup(kBrainOgdenQlv));
  return lib;
}

const std::vector<Library>& Libraries() {
  static const std::vector<Library> libraries = {RatBrainLibrary(), BrainOgdenLibrary()};
  return libraries;
}

const Library* FindLibrary(const std::string& name) {
  for (const Library& lib : Libraries()) {
    if (lib.name == name) return &lib;
  }
  return nullptr;
}

std::string ModelText(const MaterialSpec& m) {
  std::string model = m.kind == MaterialSpec::Kind::kOgden ? "Ogden" : "neo-Hookean";
  switch (m.viscoelastic.form) {
    case ViscoelasticSpec::Form::kModuli:
      return model + ", Prony moduli";
    case ViscoelasticSpec::Form::kProny:
      return model + ", QLV Prony";
    default:
      return model + ", elastic";
  }
}

std::string ParametersText(const MaterialSpec& m) {
  std::string text;
  if (m.kind == MaterialSpec::Kind::kOgden) {
    text = "mu = " + Num(m.ogden.terms[0].mu_pa) + " Pa, alpha = " + Num(m.ogden.terms[0].alpha) +
           ", K = " + Num(m.ogden.bulk_modulus_pa) + " Pa";
  } else {
    text = "mu = " + Num(m.neo_hookean.shear_modulus_pa) +
           " Pa, K = " + Num(m.neo_hookean.bulk_modulus_pa) + " Pa";
  }
  text += ", rho = " + Num(m.density_kg_per_m3) + " kg/m^3";
  const ViscoelasticSpec& v = m.viscoelastic;
  if (v.form == ViscoelasticSpec::Form::kModuli) {
    text += "; G_inf = " + Num(v.long_term_modulus_pa) +
            " Pa, G_i = " + Join(v.moduli_pa.data(), v.moduli_pa.size(), ", ") + " Pa";
  } else if (v.form == ViscoelasticSpec::Form::kProny) {
    text += "; g_k = " + Join(v.g.data(), v.g.size(), ", ");
  }
  if (!v.tau_s.empty()) text += ", tau = " + Join(v.tau_s.data(), v.tau_s.size(), ", ") + " s";
  return text;
}

}  // namespace

std::vector<std::string> TissueLibraryNames() {
  std::vector<std::string> names;
  for (const Library& lib : Libraries()) names.push_back(lib.name);
  return names;
}

Status CheckLibraryName(const std::string& library) {
  if (FindLibrary(library)) return Status::Ok();
  std::string known;
  for (const std::string& name : TissueLibraryNames()) known += (known.empty() ? "" : ", ") + name;
  return Status::InvalidArgument("material_library",
                                 "unknown library \"" + library + "\"; known: " + known);
}

Status LibraryMaterial(const std::string& library, const std::string& structure,
                       MaterialSpec* material, std::string* source) {
  PBA_RETURN_IF_ERROR(CheckLibraryName(library));
  for (const Group& group : FindLibrary(library)->groups) {
    for (const std::string& name : group.structures) {
      if (name != structure) continue;
      if (material) *material = group.material;
      if (source) *source = group.source;
      return Status::Ok();
    }
  }
  return Status::NotFound("tissue library \"" + library + "\" has no structure \"" + structure +
                          "\"");
}

std::string TissueLibraryMarkdown(const std::string& library) {
  const Library* lib = FindLibrary(library);
  if (!lib) return "";
  std::string text = "| structure group | model | parameters | source |\n|---|---|---|---|\n";
  for (const Group& group : lib->groups) {
    std::string structures = group.listing;
    if (structures.empty()) {
      for (const std::string& s : group.structures) {
        structures += (structures.empty() ? "" : ", ") + s;
      }
    }
    text += "| " + group.title + ": " + structures + " | " + ModelText(group.material) + " | " +
            ParametersText(group.material) + " | " + group.source + " |\n";
  }
  return text;
}

}  // namespace pba
