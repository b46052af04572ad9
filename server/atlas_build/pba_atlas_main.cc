// pba-atlas: builds a physics-based atlas locally from files - the built-in
// synthetic atlas, a plate stack, a label volume, or a structure set - into
// one conforming multi-material tetrahedral mesh, with its quality report
// and, when the source has plates, its geometric validation against them;
// and splits an atlas into a structure set.
//
//   pba-atlas plates -o DIR          the synthetic atlas's 27 plates
//   pba-atlas build -o DIR [--plates DIR | --labels FILE | --structures DIR] ...
//   pba-atlas split -o DIR [--plates DIR | --labels FILE] [--structure NAME]...
//                                    the atlas as a structure set, one file
//                                    per structure (structure_split.h)
//   pba-atlas labels -o DIR --labels FILE --colour-table FILE [--fill NAME]
//                    [--merge NEW=A,B] [--over VOLUME,TABLE] [--cut-sphere ...] ...
//                                    label algebra (label_algebra.h) on a
//                                    label volume; build takes the same
//                                    steps and meshes the result
//
// The output directory appears whole or not at all (StagingDir; SplitAtlas
// for split, which refuses a directory that is there and not empty). plates
// and build refuse a non-empty one too, and with --force replace only an
// earlier result of theirs (CheckOutput): never a file, a link, or a
// directory holding anything they do not write.
// Exit codes: the table pba, pba-solve and pba-atlas share (core/exit_codes.h,
// docs/cli.md "Exit codes"): 0 success; 2 bad command line; 5 invalid input;
// 12 the input cannot be meshed as given; 13 I/O error; 1 internal error.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "atlas/atlas_build.h"
#include "atlas/atlas_pictures.h"
#include "atlas/contours.h"
#include "atlas/label_algebra.h"
#include "atlas/label_volume_io.h"
#include "atlas/structure_split.h"
#include "atlas/synthetic_atlas.h"
#include "core/atomic_write.h"
#include "core/exit_codes.h"
#include "core/format.h"
#include "core/yaml_guard.h"
#include "io/mesh_export.h"
#include "solve/staging_dir.h"

namespace pba {
namespace {

int Fail(const Status& status) {
  std::fprintf(stderr, "pba-atlas: error: %s\n", status.ToString().c_str());
  return ExitCodeForStatus(status.code(), kExitMesh);
}

bool EndsWith(const std::string& text, const std::string& end) {
  return text.size() >= end.size() && text.compare(text.size() - end.size(), end.size(), end) == 0;
}

// Whether `entry` of an output directory is something `plates` or `build`
// writes there (an earlier result): its mesh, reports and label volume, the
// plates/ and pictures/ folders holding nothing but their kinds of file.
bool WrittenByPbaAtlas(const std::filesystem::directory_entry& entry) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const std::string name = entry.path().filename().string();
  if (entry.is_symlink(ec)) return false;
  if (entry.is_regular_file(ec)) {
    for (const char* known :
         {"labels.nii.gz", "labels.csv", "structures.csv", "quality.txt", "quality.csv",
          "quality.json", "validation.txt", "validation.csv", "validation.json"}) {
      if (name == known) return true;
    }
    return name.rfind("atlas.", 0) == 0;
  }
  if (!entry.is_directory(ec) || (name != "plates" && name != "pictures")) return false;
  for (const fs::directory_entry& inner : fs::directory_iterator(entry.path(), ec)) {
    const std::string file = inner.path().filename().string();
    if (inner.is_symlink(ec) || !inner.is_regular_file(ec)) return false;
    if (!EndsWith(file, ".png") &&
        (name == "pictures" || (!EndsWith(file, ".csv") && !EndsWith(file, ".json")))) {
      return false;
    }
  }
  return !ec;
}

// Whether a result may go to `out` (CheckOutputDir with WrittenByPbaAtlas).
Status CheckOutput(const std::filesystem::path& out, bool force) {
  return CheckOutputDir(out, force, "pba-atlas", WrittenByPbaAtlas);
}

// A report in its three forms, <stem>.txt, .csv and .json.
Status WriteReport(const std::filesystem::path& dir, const std::string& stem,
                   const ReportTable& table) {
  PBA_RETURN_IF_ERROR(
      AtomicWriteText(dir / (stem + ".txt"), FormatReportTable(table, TableFormat::kText)));
  PBA_RETURN_IF_ERROR(
      AtomicWriteText(dir / (stem + ".csv"), FormatReportTable(table, TableFormat::kCsv)));
  return AtomicWriteText(dir / (stem + ".json"), FormatReportTable(table, TableFormat::kJson));
}

int RunPlates(const std::string& out_dir, double voxel_mm, bool force) {
  SyntheticAtlasOptions options;
  options.voxel_size_mm = voxel_mm;
  if (Status s = options.Validate(); !s.ok()) return Fail(s);
  if (Status s = CheckOutput(out_dir, force); !s.ok()) return Fail(s);
  const LabelVolume atlas = MakeSyntheticAtlas(options);
  StagingDir staging;
  if (Status s = StagingDir::Create(out_dir, &staging); !s.ok()) return Fail(s);
  if (Status s =
          WritePlates(atlas, ColourTable::Builtin(), PlateOptions(), staging.path() / "plates");
      !s.ok()) {
    return Fail(s);
  }
  if (Status s = WriteNifti(atlas, staging.path() / "labels.nii.gz"); !s.ok()) return Fail(s);
  if (Status s = staging.Commit(); !s.ok()) return Fail(s);
  std::printf("wrote %s/plates (27 plates, colour_table.csv, plates.json) and labels.nii.gz\n",
              out_dir.c_str());
  return kExitOk;
}

// The size of a split structure as read back from its file: plates of a
// contours file, voxels of a mask.
Status DescribeStructure(const std::filesystem::path& dir, const StructureEntry& entry,
                         std::string* size) {
  const std::filesystem::path file = dir / entry.file;
  if (entry.format == StructureFormat::kNifti) {
    LabelVolume mask;
    PBA_RETURN_IF_ERROR(ReadNifti(file, &mask));
    int64_t voxels = 0;
    for (uint16_t value : mask.labels()) voxels += value != 0;
    *size = std::to_string(voxels) + " voxels";
    return Status::Ok();
  }
  std::ifstream in(file, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in) return Status::Io("cannot read " + file.string());
  Contours contours;
  PBA_RETURN_IF_ERROR(ParseContoursJson(text.str(), entry.file, &contours));
  const size_t plates = contours.plates.size();
  *size = std::to_string(plates) + (plates == 1 ? " plate" : " plates");
  return Status::Ok();
}

int RunSplit(const SplitOptions& options, const std::string& out_dir) {
  SplitResult result;
  if (Status s = SplitAtlas(options, out_dir, &result); !s.ok()) return Fail(s);
  size_t width = 0;
  for (const StructureEntry& entry : result.set.structures) {
    width = std::max(width, entry.name.size());
  }
  for (const StructureEntry& entry : result.set.structures) {
    std::string size;
    if (Status s = DescribeStructure(out_dir, entry, &size); !s.ok()) return Fail(s);
    std::printf("%-*s  %-13s  %s  %s\n", static_cast<int>(width), entry.name.c_str(),
                StructureFormatName(entry.format), entry.file.c_str(), size.c_str());
  }
  if (!result.absent.empty()) {
    std::string names;
    for (const std::string& n : result.absent) names += (names.empty() ? "" : ", ") + n;
    std::printf(
        "absent (no %s): %s\n",
        options.source.source == AtlasBuildOptions::Source::kLabelVolume ? "voxel" : "pixel",
        names.c_str());
  }
  std::printf("wrote %s (%zu structures, %s)\n", out_dir.c_str(), result.set.structures.size(),
              kStructureSetManifest);
  return kExitOk;
}

// What to draw into pictures/ (atlas_pictures.h); nullopt: nothing.
using Pictures = std::optional<AtlasPictureOptions>;

int RunBuild(AtlasBuildOptions options, const Pictures& pictures, const std::string& out_dir,
             TableFormat format, bool force) {
  if (pictures) {
    if (Status s = pictures->Validate(); !s.ok()) return Fail(s);
  }
  if (Status s = CheckOutput(out_dir, force); !s.ok()) return Fail(s);
  StagingDir staging;
  if (Status s = StagingDir::Create(out_dir, &staging); !s.ok()) return Fail(s);
  if (options.source == AtlasBuildOptions::Source::kSynthetic) {
    options.plates_dir = staging.path() / "plates";
  }
  AtlasBuildResult result;
  if (Status s = BuildAtlas(options, &result); !s.ok()) return Fail(s);

  if (Status s = WriteNifti(result.volume, staging.path() / "labels.nii.gz"); !s.ok()) {
    return Fail(s);
  }
  if (Status s = WriteColourTableCsv(result.colours, staging.path() / "labels.csv"); !s.ok()) {
    return Fail(s);
  }
  // The mesh in the forms people open it with: ParaView (.vtu, .xdmf +
  // .h5), Gmsh (.msh) and Abaqus / CalculiX (.inp); millimetres, regions
  // named after the structures.
  MeshExportOptions export_options;
  export_options.title = result.synthetic ? std::string("PBA atlas mesh - ") + kSyntheticAtlasNotice
                                          : std::string("PBA atlas mesh");
  for (const char* name : {"atlas.vtu", "atlas.xdmf", "atlas.msh", "atlas.inp"}) {
    if (Status s = ExportMesh(result.mesh, staging.path() / name, export_options); !s.ok()) {
      return Fail(s);
    }
  }
  const ReportTable quality = QualityReportTable(result);
  if (Status s = WriteReport(staging.path(), "quality", quality); !s.ok()) return Fail(s);
  std::optional<ReportTable> validation;
  if (result.validation) {
    validation = ValidationReportTable(*result.validation);
    if (Status s = WriteReport(staging.path(), "validation", *validation); !s.ok()) return Fail(s);
  }
  double pictures_s = 0;
  if (pictures) {
    const auto start = std::chrono::steady_clock::now();
    if (Status s = WriteAtlasPictures(result, staging.path() / "pictures", *pictures); !s.ok()) {
      return Fail(s);
    }
    pictures_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  if (Status s = staging.Commit(); !s.ok()) return Fail(s);

  std::printf("%s", FormatReportTable(quality, format).c_str());
  if (validation) std::printf("\n%s", FormatReportTable(*validation, format).c_str());
  if (format == TableFormat::kText) {
    if (!result.notes.empty()) std::printf("\n");
    for (const std::string& note : result.notes) std::printf("note: %s\n", note.c_str());
    if (!result.merged.empty()) {
      std::printf("\n%zu structures merged into \"%s\" (not asked for)\n", result.merged.size(),
                  kSurroundingTissue);
    }
    if (!result.dropped.empty()) {
      std::printf("\n%zu structures dropped (not asked for)\n", result.dropped.size());
    }
    if (!result.absent.empty()) {
      std::string names;
      for (const std::string& n : result.absent) names += (names.empty() ? "" : ", ") + n;
      std::printf("\nnote: %zu structure%s of the colour table %s not in the %s: %s\n",
                  result.absent.size(), result.absent.size() == 1 ? "" : "s",
                  result.absent.size() == 1 ? "is" : "are",
                  result.plates ? "volume lofted from the plates" : "label volume", names.c_str());
    }
    const AtlasBuildTimes& t = result.times;
    const LabelMeshReport& m = result.mesher;
    const bool ten_node = result.mesh.shape() == ElementShape::kTet10;
    std::printf(
        "\n%d structures, %d tetrahedra, %d nodes%s; source %.2f s, loft %.2f s, mesh %.2f s "
        "(seeds %.2f, refinement %.2f, ODT %.2f, perturbation %.2f, exudation %.2f), "
        "improvement %.2f s, quality %.2f s, validation %.2f s, pictures %.2f s\n",
        static_cast<int>(result.region_labels.size()), result.mesh.num_elements(),
        result.mesh.num_nodes(), ten_node ? " (10-node)" : "", t.source_s, t.loft_s,
        t.mesh_s + t.quadratic_s, m.seed_s, m.refine_s, m.odt_s, m.perturb_s, m.exude_s,
        t.improve_s, t.quality_s, t.validation_s, pictures_s);
    const ImproveStats& i = result.improvement;
    if (i.min_dihedral_before_deg > 0) {
      std::printf(
          "improvement: smallest dihedral angle %.2f -> %.2f deg, largest aspect ratio %.3g -> "
          "%.3g, %d -> %d tetrahedra below the target; %d edge removals, %d 2-3 flips, %d node "
          "moves, %d nodes inserted, %d slivers moved across an interface (%.3g mm^3), %d short "
          "edges collapsed (%d tetrahedra; longest %.3g mm, on a surface %.3g mm)\n",
          i.min_dihedral_before_deg, i.min_dihedral_after_deg, i.max_aspect_ratio_before,
          i.max_aspect_ratio_after, i.below_target_before, i.below_target_after,
          i.flips_32 + i.flips_44 + i.edge_removals, i.flips_23, i.smoothed_nodes, i.inserted_nodes,
          result.relabelled.tetrahedra, result.relabelled.volume_m3 * 1e9, result.collapsed.edges,
          result.collapsed.removed_tetrahedra, result.collapsed.longest_m * 1e3,
          result.collapsed.longest_surface_m * 1e3);
    }
    if (const std::optional<MidsideProjectionReport>& p = result.projection) {
      std::printf(
          "10-node: of %lld mid-edge nodes on surfaces and interfaces, %lld moved onto the "
          "loft's surfaces and %lld part of the way (largest move %.3f mm, mean %.3f mm), %lld "
          "put back at their midpoints (Jacobian ratio over %g or inverted), %lld left there "
          "(no convergence within a quarter of the edge); distance from the surfaces: median "
          "%.3f mm, 90th percentile %.3f mm (at the midpoints %.3f and %.3f mm); %.2f s\n",
          static_cast<long long>(p->boundary_nodes), static_cast<long long>(p->projected),
          static_cast<long long>(p->shortened), p->max_move_mm, p->mean_move_mm,
          static_cast<long long>(p->reset), MidsideProjectionOptions().max_jacobian_ratio,
          static_cast<long long>(p->unprojected), p->gap_mm.median_mm, p->gap_mm.p90_mm,
          p->gap_midpoints_mm.median_mm, p->gap_midpoints_mm.p90_mm, t.quadratic_s);
    } else if (ten_node) {
      std::printf(
          "10-node: every mid-edge node at its edge's midpoint (a label volume gives no smooth "
          "surface to move them to)\n");
    }
    for (const std::string& step : m.time_limit_reached) {
      std::printf(
          "note: the mesher's %s step stopped at its time limit; the mesh depends on "
          "this machine's speed and load\n",
          step.c_str());
    }
    std::printf("wrote %s\n", out_dir.c_str());
  }
  return kExitOk;
}

// Label algebra given as flags (label_algebra.h), applied in the order
// the flags come on the command line; --steps splices a YAML file's steps
// in at its place.
struct LabelFlags {
  std::vector<std::string> keep, drop, merge, rename, fill, over, under, resample, sphere, cylinder,
      mask, islands, steps;
  double closing_mm = 0;
  double min_piece_mm3 = LabelStep().min_piece_mm3;
  // Each step flag's option, with its values in the order given.
  std::vector<std::pair<const CLI::Option*, const std::vector<std::string>*>> options;
};

// "A=B" at its first '='; false without one or with an empty side.
bool SplitAtEquals(const std::string& text, std::string* left, std::string* right) {
  const std::size_t at = text.find('=');
  if (at == std::string::npos || at == 0 || at + 1 == text.size()) return false;
  *left = text.substr(0, at);
  *right = text.substr(at + 1);
  return true;
}

// Comma-separated names (a name with a comma in double quotes).
Status FlagNames(const std::string& flag, const std::string& text,
                 std::vector<std::string>* names) {
  if (!SplitDelimited(text, ',', names) ||
      std::any_of(names->begin(), names->end(), [](const std::string& n) { return n.empty(); })) {
    return Status::InvalidArgument(
        flag, "expected comma-separated structure names, got \"" + text + "\"");
  }
  return Status::Ok();
}

// `count` comma-separated numbers.
Status FlagNumbers(const std::string& flag, const std::string& text, std::size_t count,
                   std::vector<double>* numbers) {
  std::vector<std::string> fields;
  numbers->clear();
  if (SplitDelimited(text, ',', &fields) && fields.size() == count) {
    for (const std::string& f : fields) {
      char* end = nullptr;
      const double x = std::strtod(f.c_str(), &end);
      if (f.empty() || *end != '\0' || !std::isfinite(x)) break;
      numbers->push_back(x);
    }
  }
  if (numbers->size() != count) {
    return Status::InvalidArgument(
        flag, Format("expected %zu comma-separated numbers, got \"%s\"", count, text.c_str()));
  }
  return Status::Ok();
}

// A cut flag's value: the region's text, and after '=' what the cut
// becomes.
void CutInto(const std::string& value, std::string* region, LabelStep* step) {
  std::string name;
  if (!SplitAtEquals(value, region, &name)) {
    *region = value;
    return;
  }
  step->name = name;
}

// One step flag's value as steps (one, or a --steps file's).
Status FlagStep(const LabelFlags& flags, const std::string& flag, const std::string& value,
                std::vector<LabelStep>* steps) {
  LabelStep step;
  std::string a, b;
  std::vector<double> x;
  if (flag == "--keep" || flag == "--drop") {
    step.kind = flag == "--keep" ? LabelStep::Kind::kKeep : LabelStep::Kind::kDrop;
    PBA_RETURN_IF_ERROR(FlagNames(flag, value, &step.structures));
  } else if (flag == "--merge") {
    step.kind = LabelStep::Kind::kMerge;
    if (!SplitAtEquals(value, &step.name, &a)) {
      return Status::InvalidArgument(flag, "expected NEW=A,B,..., got \"" + value + "\"");
    }
    PBA_RETURN_IF_ERROR(FlagNames(flag, a, &step.structures));
  } else if (flag == "--rename") {
    step.kind = LabelStep::Kind::kRename;
    if (!SplitAtEquals(value, &step.from, &step.name)) {
      return Status::InvalidArgument(flag, "expected OLD=NEW, got \"" + value + "\"");
    }
  } else if (flag == "--fill") {
    step.kind = LabelStep::Kind::kFill;
    step.name = value;
    step.closing_mm = flags.closing_mm;
    step.min_piece_mm3 = flags.min_piece_mm3;
  } else if (flag == "--over" || flag == "--under") {
    step.kind = LabelStep::Kind::kOverlay;
    step.under = flag == "--under";
    std::vector<std::string> files;
    if (!SplitDelimited(value, ',', &files) || files.size() != 2) {
      return Status::InvalidArgument(flag, "expected VOLUME,TABLE, got \"" + value + "\"");
    }
    step.volume = files[0];
    step.table = files[1];
  } else if (flag == "--drop-islands") {
    step.kind = LabelStep::Kind::kIslands;
    PBA_RETURN_IF_ERROR(FlagNumbers(flag, value, 1, &x));
    step.min_piece_mm3 = x[0];
  } else if (flag == "--resample") {
    step.kind = LabelStep::Kind::kResample;
    PBA_RETURN_IF_ERROR(FlagNumbers(flag, value, 1, &x));
    step.voxel_mm = x[0];
  } else if (flag == "--cut-sphere" || flag == "--cut-cylinder") {
    step.kind = LabelStep::Kind::kCut;
    CutInto(value, &a, &step);
    const bool sphere = flag == "--cut-sphere";
    PBA_RETURN_IF_ERROR(FlagNumbers(flag, a, sphere ? 4 : 7, &x));
    step.region.kind = sphere ? LabelRegion::Kind::kSphere : LabelRegion::Kind::kCylinder;
    step.region.centre_mm = {x[0], x[1], x[2]};
    if (!sphere) step.region.end_mm = {x[3], x[4], x[5]};
    step.region.radius_mm = x.back();
  } else if (flag == "--cut-mask") {
    step.kind = LabelStep::Kind::kCut;
    CutInto(value, &a, &step);
    step.region.kind = LabelRegion::Kind::kMask;
    step.region.mask = a;
  } else {  // --steps
    std::string text;
    PBA_RETURN_IF_ERROR(ReadYamlFileText(value, flag, &text));
    std::vector<LabelStep> read;
    PBA_RETURN_IF_ERROR(ParseLabelSteps(text, std::filesystem::path(value).filename().string(),
                                        std::filesystem::path(value).parent_path(), &read));
    steps->insert(steps->end(), read.begin(), read.end());
    return Status::Ok();
  }
  steps->push_back(std::move(step));
  return Status::Ok();
}

// The steps the flags of `app` give, in their order on the command line.
Status CollectLabelSteps(const CLI::App& app, const LabelFlags& flags,
                         std::vector<LabelStep>* steps) {
  std::map<const CLI::Option*, std::size_t> used;
  for (const CLI::Option* option : app.parse_order()) {
    for (const auto& [known, values] : flags.options) {
      if (known != option) continue;
      const std::size_t n = used[option]++;
      if (n >= values->size()) return Status::Internal("label step flags out of step");
      PBA_RETURN_IF_ERROR(FlagStep(flags, "--" + option->get_single_name(), (*values)[n], steps));
    }
  }
  return Status::Ok();
}

// The label algebra's flags, on build and labels alike.
void AddLabelFlags(CLI::App* app, LabelFlags& flags) {
  const auto step = [&](const char* name, std::vector<std::string>& values, const char* help) {
    CLI::Option* option = app->add_option(name, values, help)->take_all()->expected(1);
    option->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
    flags.options.emplace_back(option, &values);
  };
  step("--keep", flags.keep,
       "Label algebra, in the order given: keep only these structures (A,B,...)");
  step("--drop", flags.drop, "Make these structures background (A,B,...)");
  step("--merge", flags.merge, "One structure NEW, the union of A, B, ... (NEW=A,B,...)");
  step("--rename", flags.rename, "Rename a structure (OLD=NEW)");
  step("--fill", flags.fill,
       "The background the atlas encloses becomes this structure (AAL: \"White matter\")");
  step("--over", flags.over,
       "Lay a second atlas's structures over this one's (VOLUME,TABLE; resampled to this grid)");
  step("--under", flags.under,
       "Lay a second atlas's structures into this one's background only "
       "(VOLUME,TABLE)");
  step("--resample", flags.resample, "Resample to voxels of this edge [mm] (majority label)");
  step("--cut-sphere", flags.sphere,
       "Cut a sphere out of every structure (X,Y,Z,R [mm]; =NAME: the cut becomes NAME)");
  step("--cut-cylinder", flags.cylinder,
       "Cut a cylinder (X0,Y0,Z0,X1,Y1,Z1,R [mm]: axis ends and radius; =NAME as above)");
  step("--cut-mask", flags.mask, "Cut the nonzero voxels of a mask volume (FILE; =NAME as above)");
  step("--drop-islands", flags.islands,
       "Make background every piece of the atlas (voxels joined by faces) under this volume "
       "[mm^3], the largest kept");
  step("--steps", flags.steps,
       "Label algebra steps from a YAML file (keep, drop, merge, rename, fill, overlay, resample, "
       "cut: docs/atlas.md)");
  app->add_option("--closing-mm", flags.closing_mm,
                  "--fill: close gaps in the atlas up to twice this [mm] before finding what it "
                  "encloses")
      ->capture_default_str();
  app->add_option("--min-piece-mm3", flags.min_piece_mm3,
                  "--fill: enclosed pieces smaller than this [mm^3] stay background (the largest "
                  "is always filled)")
      ->capture_default_str();
}

// The command line as CLI11 fills it. The subcommands share -o and --force:
// only one of them runs.
struct CommandLine {
  std::string out_dir;
  bool force = false;
  double voxel_mm = 1.0;  // plates

  AtlasBuildOptions build;
  std::string plates_dir, labels_file, structures_dir, colour_table, format_name = "text";
  std::vector<std::string> structures;
  std::vector<double> roi;  // X,Y,Z,R or empty
  int threads = 0;          // 0: every core
  bool no_pictures = false;
  AtlasPictureOptions pictures;

  SplitOptions split;
  std::string split_plates, split_labels, split_colour_table;

  LabelFlags build_steps, label_steps;  // build's and labels' label algebra
  bool keep_islands = false;
  std::string steps_labels, steps_colour_table;
};

constexpr char kOutHelp[] =
    "Output directory (created; must not exist or be empty, or with --force hold an earlier "
    "result)";
constexpr char kForceHelp[] =
    "Replace an earlier result at --out (never a directory with other files)";

CLI::App* AddPlatesCommand(CLI::App& app, CommandLine& line) {
  CLI::App* plates = app.add_subcommand(
      "plates",
      "Write the built-in synthetic atlas (not anatomy, not for clinical use) as 27 "
      "colour-coded axial plates and a NIfTI label volume");
  plates->add_option("-o,--out", line.out_dir, kOutHelp)->required();
  plates->add_flag("--force", line.force, kForceHelp);
  plates->add_option("--voxel-mm", line.voxel_mm, "Voxel edge of the painted atlas [mm]");
  return plates;
}

// build's cuts through the mesh into pictures/ (atlas_pictures.h).
void AddPictureOptions(CLI::App* build, CommandLine& line) {
  auto* no_pictures_flag = build->add_flag(
      "--no-pictures", line.no_pictures,
      "Do not write pictures/ (the plates' contact sheet and cuts through the mesh)");
  build
      ->add_option("--cut-z", line.pictures.axial_z_mm,
                   "Axial cut at this z [mm] into pictures/ (repeatable; any --cut-* replaces "
                   "the default cuts)")
      ->excludes(no_pictures_flag);
  build
      ->add_option("--cut-y", line.pictures.coronal_y_mm, "Coronal cut at this y [mm] (repeatable)")
      ->excludes(no_pictures_flag);
  build
      ->add_option("--cut-x", line.pictures.sagittal_x_mm,
                   "Sagittal cut at this x [mm] (repeatable)")
      ->excludes(no_pictures_flag);
  build->add_option("--picture-mm", line.pictures.pixel_mm, "Pixel edge of the cuts [mm]")
      ->excludes(no_pictures_flag);
}

// build's element sizes and mesh improvement (AtlasBuildOptions).
void AddMeshOptions(CLI::App* build, AtlasBuildOptions& options) {
  build->add_option("--synthetic-voxel-mm", options.synthetic_voxel_mm,
                    "Voxel edge of the painted synthetic atlas [mm]");
  build->add_option("--loft-voxel-mm", options.loft_voxel_mm,
                    "Voxel edge of the volume lofted from plates [mm]");
  build
      ->add_option("--cell-mm", options.cell_size_mm, "Tetrahedron size inside the structures [mm]")
      ->capture_default_str();
  build
      ->add_option("--facet-mm", options.facet_size_mm,
                   "Triangle size on surfaces and interfaces [mm]")
      ->capture_default_str();
  build
      ->add_option("--facets-per-section", options.facets_per_section,
                   "Smaller facets on small structures: at most a structure's mean section "
                   "perimeter over this [-]; 0: --facet-mm everywhere")
      ->capture_default_str();
  build
      ->add_option("--improve-deg", options.improve_target_deg,
                   "Flips and smoothing on tetrahedra whose smallest dihedral angle is below "
                   "this [deg]; 0: none")
      ->capture_default_str();
  build
      ->add_option("--improve-aspect", options.improve_aspect_ratio,
                   "With --improve-deg, also on tetrahedra whose aspect ratio is above this "
                   "(>= 1.5; 0: the angle alone)")
      ->capture_default_str();
  build
      ->add_option("--quality-rounds", options.quality_rounds,
                   "Mesh again, up to this many times (0-5), while structures miss the quality "
                   "bounds, those structures' cells and facets 0.7 times smaller each time; a "
                   "note gives the sizes each met the bounds at, or did not")
      ->capture_default_str();
  build
      ->add_option("--odt", options.odt_iterations,
                   "Passes of ODT smoothing before sliver removal; 0: none")
      ->capture_default_str();
  build->add_option("--facet-distance-mm", options.facet_distance_mm,
                    "How far surface triangles may stray from the true surface [mm]; 0: a quarter "
                    "of the facet size");
}

CLI::App* AddBuildCommand(CLI::App& app, CommandLine& line) {
  CLI::App* build = app.add_subcommand(
      "build",
      "Mesh an atlas: the synthetic one (default), a plate directory or a label volume; writes "
      "atlas.{vtu,xdmf,msh,inp}, labels.nii.gz, quality.{txt,csv,json}, pictures/ (PNG cuts "
      "through the mesh) and, from plates, validation.{txt,csv,json}");
  build->add_option("-o,--out", line.out_dir, kOutHelp)->required();
  build->add_flag("--force", line.force, kForceHelp);
  auto* plates_option = build->add_option("--plates", line.plates_dir,
                                          "Plate directory (plates.json, PNGs, colour table)");
  auto* labels_option =
      build->add_option("--labels", line.labels_file, "Label volume (.nii, .nii.gz or .nrrd)")
          ->excludes(plates_option);
  build
      ->add_option("--structures", line.structures_dir,
                   "Structure set (manifest.json and one file per structure: contours, "
                   "NIfTI masks, closed STL/OBJ/VTK surfaces)")
      ->excludes(plates_option)
      ->excludes(labels_option);
  build->add_option("--colour-table", line.colour_table,
                    "Label table for --labels (PBA CSV, MRIcron .txt with its .lut, FSL .xml, "
                    "Slicer .ctbl/.csv/.tsv, ITK-SNAP .txt); default the built-in one");
  AddMeshOptions(build, line.build);
  build
      ->add_option("--roi", line.roi,
                   "Region of interest X,Y,Z,R [mm]: finer elements within R of (X, Y, Z), "
                   "coarsening over one radius outside")
      ->delimiter(',')
      ->expected(4);
  build->add_option("--roi-mm", line.build.roi_size_mm,
                    "Element size in the region of interest [mm]; default half of --facet-mm");
  build->add_flag("--quadratic", line.build.quadratic, "10-node tetrahedra");
  build
      ->add_option("--threads", line.threads,
                   "Threads the geometric validation may use (the mesher runs on one); 0 uses "
                   "every core")
      ->check(CLI::NonNegativeNumber);
  build->add_option("--structure", line.structures,
                    "Keep only this structure (colour-table name; repeat for several)");
  build->add_flag(
      "--keep-islands", line.keep_islands,
      "Keep every piece of a label volume and of its mesh; by default pieces under 0.1 % of the "
      "largest piece's volume (fragments that would touch nothing, or hang on an edge) become "
      "background, and are taken out of the mesh");
  build->add_flag("--merge-rest", line.build.merge_rest,
                  "With --structure: mesh every other structure as one region, \"Surrounding "
                  "tissue\", instead of dropping it");
  AddPictureOptions(build, line);
  AddLabelFlags(build, line.build_steps);
  build->add_option("--format", line.format_name, "Report form on stdout")
      ->check(CLI::IsMember({"text", "csv", "json"}));
  return build;
}

CLI::App* AddSplitCommand(CLI::App& app, CommandLine& line) {
  CLI::App* split = app.add_subcommand(
      "split",
      "Write an atlas as a structure set: the synthetic one (default) or a plate directory as "
      "each structure's plate contours (<name>.json), a label volume as each structure's mask "
      "(<name>.nii.gz); with manifest.json");
  split
      ->add_option("-o,--out", line.out_dir,
                   "Output directory (created; must not exist or be empty)")
      ->required();
  auto* split_plates_option = split->add_option(
      "--plates", line.split_plates, "Plate directory (plates.json, PNGs, colour table)");
  auto* split_labels_option =
      split->add_option("--labels", line.split_labels, "Label volume (.nii, .nii.gz or .nrrd)")
          ->excludes(split_plates_option);
  split
      ->add_option("--colour-table", line.split_colour_table,
                   "Label table for --labels (PBA CSV, MRIcron .txt with its .lut, FSL .xml, "
                   "Slicer .ctbl/.csv/.tsv, ITK-SNAP .txt); default the built-in one")
      ->needs(split_labels_option);
  split->add_option("--synthetic-voxel-mm", line.split.source.synthetic_voxel_mm,
                    "Voxel edge of the painted synthetic atlas [mm]");
  split->add_option(
      "--structure", line.split.structures,
      "Only this structure (repeatable; a colour-table name, or a group such as Thalamus)");
  return split;
}

CLI::App* AddLabelsCommand(CLI::App& app, CommandLine& line) {
  CLI::App* labels = app.add_subcommand(
      "labels",
      "Label algebra on a label volume and its table: keep, drop, merge, rename, fill enclosed "
      "background, lay a second atlas over or under, resample, cut a region out; writes "
      "labels.nii.gz, labels.csv (its table) and structures.csv, which build --labels reads");
  labels->add_option("-o,--out", line.out_dir, kOutHelp)->required();
  labels->add_flag("--force", line.force, kForceHelp);
  labels->add_option("--labels", line.steps_labels, "Label volume (.nii, .nii.gz or .nrrd)")
      ->required();
  labels->add_option("--colour-table", line.steps_colour_table,
                     "Its label table (PBA CSV, MRIcron .txt with its .lut, FSL .xml, Slicer "
                     ".ctbl/.csv/.tsv, ITK-SNAP .txt)");
  AddLabelFlags(labels, line.label_steps);
  return labels;
}

// Each structure's label, voxels and volume.
std::string StructuresCsv(const LabelAtlas& atlas) {
  const std::vector<int64_t> counts = CountLabels(atlas.volume);
  std::string text = "label,name,voxels,volume_cm3\n";
  for (const ColourEntry& e : atlas.table.entries()) {
    text += Format("%d,%s,%lld,%.3f\n", e.label, CsvQuoted(e.name).c_str(),
                   static_cast<long long>(counts[e.label]),
                   counts[e.label] * atlas.volume.voxel_volume_mm3() / 1000);
  }
  return text;
}

int RunLabels(const CLI::App& app, CommandLine& line) {
  std::vector<LabelStep> steps;
  if (Status s = CollectLabelSteps(app, line.label_steps, &steps); !s.ok()) return Fail(s);
  if (steps.empty()) {
    return Fail(Status::InvalidArgument("labels", "no step given (--fill, --merge, --over, ...)"));
  }
  if (Status s = CheckOutput(line.out_dir, line.force); !s.ok()) return Fail(s);
  LabelAtlas atlas;
  std::vector<std::string> notes;
  if (Status s = ReadLabelAtlas(line.steps_labels, line.steps_colour_table, "labels",
                                "colour_table", &atlas, &notes);
      !s.ok()) {
    return Fail(s);
  }
  if (Status s = ApplyLabelSteps(steps, &atlas, &notes); !s.ok()) return Fail(s);
  StagingDir staging;
  if (Status s = StagingDir::Create(line.out_dir, &staging); !s.ok()) return Fail(s);
  for (Status s : {WriteNifti(atlas.volume, staging.path() / "labels.nii.gz"),
                   WriteColourTableCsv(atlas.table, staging.path() / "labels.csv"),
                   AtomicWriteText(staging.path() / "structures.csv", StructuresCsv(atlas)),
                   staging.Commit()}) {
    if (!s.ok()) return Fail(s);
  }
  for (const std::string& note : notes) std::printf("%s\n", note.c_str());
  std::printf(
      "%d structures on %d x %d x %d voxels of %g x %g x %g mm; wrote %s "
      "(labels.nii.gz, labels.csv, structures.csv)\n",
      atlas.table.size(), atlas.volume.nx(), atlas.volume.ny(), atlas.volume.nz(),
      atlas.volume.spacing_mm().x(), atlas.volume.spacing_mm().y(), atlas.volume.spacing_mm().z(),
      line.out_dir.c_str());
  return kExitOk;
}

// split with its source from the flags: plates, a label volume, else the
// synthetic atlas.
int RunSplitCommand(CommandLine& line) {
  if (!line.split_plates.empty()) {
    line.split.source.source = AtlasBuildOptions::Source::kPlates;
    line.split.source.input = line.split_plates;
  } else if (!line.split_labels.empty()) {
    line.split.source.source = AtlasBuildOptions::Source::kLabelVolume;
    line.split.source.input = line.split_labels;
    line.split.source.colour_table = line.split_colour_table;
  }
  return RunSplit(line.split, line.out_dir);
}

// build with its options completed from the flags: the source, the
// structures, the region of interest, the report form and the pictures.
int RunBuildCommand(const CLI::App& app, CommandLine& line) {
  AtlasBuildOptions& options = line.build;
  if (Status s = CollectLabelSteps(app, line.build_steps, &options.label_steps); !s.ok()) {
    return Fail(s);
  }
  if (!line.plates_dir.empty()) {
    options.source = AtlasBuildOptions::Source::kPlates;
    options.input = line.plates_dir;
  } else if (!line.labels_file.empty()) {
    options.source = AtlasBuildOptions::Source::kLabelVolume;
    options.input = line.labels_file;
    options.colour_table = line.colour_table;
  } else if (!line.structures_dir.empty()) {
    options.source = AtlasBuildOptions::Source::kStructures;
    options.input = line.structures_dir;
  }
  options.structures = line.structures;
  if (line.keep_islands) options.island_share = 0;
  options.threads = ThreadContext(line.threads);
  if (!line.roi.empty()) {
    options.roi_centre_mm = {line.roi[0], line.roi[1], line.roi[2]};
    options.roi_radius_mm = line.roi[3];
    if (options.roi_size_mm == 0) options.roi_size_mm = options.facet_size_mm / 2;
  }
  const TableFormat format = line.format_name == "csv"    ? TableFormat::kCsv
                             : line.format_name == "json" ? TableFormat::kJson
                                                          : TableFormat::kText;
  Pictures pictures;
  if (!line.no_pictures) pictures = line.pictures;
  return RunBuild(options, pictures, line.out_dir, format, line.force);
}

}  // namespace
}  // namespace pba

int main(int argc, char** argv) {
  CLI::App app{"pba-atlas: build a physics-based brain atlas mesh from plates or labels"};
  app.require_subcommand(1);
  pba::CommandLine line;
  CLI::App* plates = pba::AddPlatesCommand(app, line);
  CLI::App* build = pba::AddBuildCommand(app, line);
  CLI::App* split = pba::AddSplitCommand(app, line);
  CLI::App* labels = pba::AddLabelsCommand(app, line);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? pba::kExitOk : pba::kExitUsage;
  }
  try {
    if (plates->parsed()) return pba::RunPlates(line.out_dir, line.voxel_mm, line.force);
    if (split->parsed()) return pba::RunSplitCommand(line);
    if (labels->parsed()) return pba::RunLabels(*labels, line);
    return pba::RunBuildCommand(*build, line);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pba-atlas: internal error: %s\n", e.what());
    return pba::kExitError;
  }
}
