// Built-in tissue libraries: a material for every structure of the built-in
// atlas (atlas/colour_table.h), each with a one-line source, so a scene can
// say `material_library: rat-brain-prony` instead of listing
// region_materials for 44 structures (docs/materials.md).
//
//   "rat-brain-prony": the rat-brain Prony table of DOMAIN.md section 2,
//     G(t) = G_inf + sum_i G_i exp(-t/tau_i) per region, on a neo-Hookean
//     base with mu = G0 = G_inf + sum_i G_i; each structure takes the
//     region nearest to it.
//   "brain-ogden-qlv": one brain tissue everywhere, the Ogden fit mu =
//     842 Pa, alpha = -4.7 with the two-term QLV relaxation of VALIDATION.md.
// In both, the ventricles are a very soft, compressible stand-in for
// cerebrospinal fluid: a modelling assumption, not data.
#pragma once

#include <string>
#include <vector>

#include "pba/scene.h"
#include "pba/status.h"

namespace pba {

// The libraries' names, in a fixed order.
std::vector<std::string> TissueLibraryNames();

// Ok when `library` is one of TissueLibraryNames(); else kInvalidArgument
// on "material_library" listing the known names.
Status CheckLibraryName(const std::string& library);

// The material of the structure named `structure` (exactly as in the
// built-in colour table, e.g. "Thalamus: pulvinar") in `library`, and a
// one-line citation of where its numbers come from (either output may be
// null). kInvalidArgument as CheckLibraryName for an unknown library;
// kNotFound when the library has no entry of that name.
Status LibraryMaterial(const std::string& library, const std::string& structure,
                       MaterialSpec* material, std::string* source);

// The library as a Markdown table, one row per group of structures sharing
// a material: structure group, model, parameters, source. docs/materials.md
// carries this text verbatim (a unit test compares them). Empty for an
// unknown library.
std::string TissueLibraryMarkdown(const std::string& library);

}  // namespace pba
