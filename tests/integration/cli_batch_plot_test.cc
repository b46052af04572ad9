// `pba batch run` with a plot: section end to end: the real pba-server on
// loopback, the real pba client, the real pba-solve, on a tiny QUASI_STATIC
// box; the picture read back with the solver's PNG reader.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "common/subprocess.h"
#include "integration/server_fixture.h"
#include "io/line_plot.h"
#include "io/png_io.h"

namespace pba::testing {
namespace {
namespace fs = std::filesystem;

constexpr int kInvalid = 5;    // client_cli/exit_codes.h
constexpr int kJobFailed = 6;  // client_cli/exit_codes.h

// A 10 mm box of neo-Hookean tissue in 5 mm elements, its bottom fixed and
// its top moved down 1 mm along the default ramp over end_time_s.
constexpr const char* kScene = R"(name: plot-box
geometry: {box: {size_mm: [10, 10, 10]}}
mesh: {element_size_mm: 5}
material: {neo_hookean: {shear_modulus_pa: 1000, bulk_modulus_pa: 1.0e5}}
boundary_conditions:
  - {set: bottom, fixed: {}}
  - {set: top, displacement: {x_mm: 0, y_mm: 0, z_mm: -1}}
analysis:
  type: QUASI_STATIC
  time: {end_time_s: 1}
outputs:
  reaction_sets: [top]
)";

// The box struck: EXPLICIT_DYNAMIC with two sensors (its solve needs the
// explicit engine; the tests below only check it before submitting).
constexpr const char* kExplicitScene = R"(name: struck-box
geometry: {box: {size_mm: [10, 10, 10]}}
mesh: {element_size_mm: 5}
material: {density_kg_per_m3: 1040, neo_hookean: {shear_modulus_pa: 1000, bulk_modulus_pa: 1.0e5}}
boundary_conditions:
  - {set: bottom, fixed: {}}
  - {set: top, velocity: {z_m_per_s: -1}}
analysis:
  type: EXPLICIT_DYNAMIC
  time: {end_time_s: 0.001}
outputs:
  sensors:
    - {name: centre, position_mm: [5, 5, 5]}
    - {name: low, position_mm: [5, 5, 2]}
)";

// How many pixels of `image` have exactly `colour`.
long CountColour(const RgbImage& image, const std::array<uint8_t, 3>& colour) {
  long n = 0;
  for (size_t i = 0; i + 2 < image.rgb.size(); i += 3) {
    n +=
        image.rgb[i] == colour[0] && image.rgb[i + 1] == colour[1] && image.rgb[i + 2] == colour[2];
  }
  return n;
}

class CliBatchPlotTest : public ServerTest {
 protected:
  void SetUp() override {
    ServerTest::SetUp();
    std::ofstream(dir_.path() / "box.yaml") << kScene;
    std::ofstream(dir_.path() / "struck_scene.yaml") << kExplicitScene;
  }

  // A batch file `stem`.yaml of the box with the given members and plot.
  fs::path Batch(const std::string& stem, const std::string& members, const std::string& plot,
                 const std::string& scene = "box.yaml") {
    const fs::path file = dir_.path() / (stem + ".yaml");
    std::ofstream(file) << "name: box-speeds\nscene: " << scene << "\n"
                        << members << "outputs: [results.max_displacement_mm]\n"
                        << plot;
    return file;
  }
};

const std::string kTwoSpeeds = "sweep:\n  analysis.time.end_time_s: [1, 2]\n";
const std::string kTopForce =
    "plot: {x: time_s, y: [\"reaction top z [N]\"], scale_y: -1, title: Two speeds}\n";

// Two members, one series each: the picture has the plot's size and both
// series' colours; each history is kept beside the batch file. A rerun
// takes both jobs from the state file, keeps the histories (unchanged) and
// draws the picture again; --no-plot draws none.
TEST_F(CliBatchPlotTest, OnePictureOfEveryMembersHistory) {
  const fs::path file = Batch("speeds", kTwoSpeeds, kTopForce);
  const fs::path png = dir_.path() / "speeds.png";
  const RunResult run = Pba({"batch", "run", file.string()});
  std::cout << run.out << run.err;
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  EXPECT_NE(run.out.find("Plot written to " + png.string() + " (2 series)"), std::string::npos)
      << run.out;
  EXPECT_NE(run.out.find("(2 fetched, 0 unchanged"), std::string::npos) << run.out;

  RgbImage image;
  const Status read = ReadRgbPng(png, &image);
  ASSERT_TRUE(read.ok()) << read.ToString();
  const LinePlot defaults;
  EXPECT_EQ(image.width, defaults.width);
  EXPECT_EQ(image.height, defaults.height);
  EXPECT_GT(CountColour(image, SeriesColour(0)), 50) << "the first member's line";
  EXPECT_GT(CountColour(image, SeriesColour(1)), 50) << "the second member's line";
  EXPECT_EQ(CountColour(image, SeriesColour(2)), 0) << "two series only";
  bool titled = false;
  for (const auto& [key, text] : image.text)
    titled = titled || (key == "Title" && text == "Two speeds");
  EXPECT_TRUE(titled);

  // Each history: a header with the plotted columns, a row per step, the
  // force on the top growing to its end (negative: compression).
  for (const char* member : {"end_time_s=1", "end_time_s=2"}) {
    const std::string history =
        ReadFile(dir_.path() / "speeds_histories" / (std::string(member) + ".csv"));
    EXPECT_EQ(history.rfind("time_s,amplitude,reaction top x [N],", 0), 0u) << history;
    EXPECT_GT(std::count(history.begin(), history.end(), '\n'), 3) << history;
  }
  EXPECT_EQ(JobCount(), 2u);

  fs::remove(png);
  const RunResult again = Pba({"batch", "run", file.string()});
  ASSERT_EQ(again.exit_code, 0) << again.out << again.err;
  EXPECT_NE(again.out.find("2 from an earlier run, 0 to submit"), std::string::npos) << again.out;
  EXPECT_NE(again.out.find("(0 fetched, 2 unchanged"), std::string::npos) << again.out;
  EXPECT_TRUE(fs::exists(png));
  EXPECT_EQ(JobCount(), 2u);

  fs::remove(png);
  const RunResult none = Pba({"batch", "run", file.string(), "--no-plot"});
  ASSERT_EQ(none.exit_code, 0) << none.out << none.err;
  EXPECT_EQ(none.out.find("Plot written"), std::string::npos) << none.out;
  EXPECT_FALSE(fs::exists(png));
}

// A column the histories do not have: the error names it, the member and
// the columns there are, and no picture is written. The batch's name and
// members are those of a finished batch, so its jobs are the same.
TEST_F(CliBatchPlotTest, AMissingColumnIsNamedAndNoPictureWritten) {
  const RunResult first =
      Pba({"batch", "run", Batch("speeds", kTwoSpeeds, "").string(), "--no-plot"});
  ASSERT_EQ(first.exit_code, 0) << first.out << first.err;
  const RunResult run =
      Pba({"batch", "run",
           Batch("bottom", kTwoSpeeds, "plot: {x: time_s, y: [\"reaction bottom z [N]\"]}\n")
               .string()});
  EXPECT_EQ(run.exit_code, kInvalid) << run.out << run.err;
  EXPECT_NE(run.err.find("member 'end_time_s=1': its history.csv has no column 'reaction bottom z "
                         "[N]'; its columns: 'time_s', 'amplitude', 'reaction top x [N]'"),
            std::string::npos)
      << run.err;
  EXPECT_FALSE(fs::exists(dir_.path() / "bottom.png"));
  EXPECT_EQ(JobCount(), 2u) << "the same members, the same jobs";
}

// A plot needs every member to write a history: a static analysis (the
// quick-start block's LINEAR_STATIC) is refused before anything is
// submitted, unless the plot is skipped.
TEST_F(CliBatchPlotTest, AStaticMemberIsRefusedBeforeSubmitting) {
  const RunResult run =
      Pba({"batch", "run",
           Batch("static", "members:\n  - {name: static, set: {mesh.element_size_mm: 4}}\n",
                 kTopForce, std::string(PBA_EXAMPLES_DIR) + "/quickstart.yaml")
               .string()});
  EXPECT_EQ(run.exit_code, kInvalid) << run.out << run.err;
  EXPECT_NE(run.err.find("member 'static': plot: only a QUASI_STATIC, EXPLICIT_DYNAMIC or "
                         "DYNAMIC_RELAXATION analysis"),
            std::string::npos)
      << run.err;
  EXPECT_EQ(JobCount(), 0u);
  // Without the picture the same batch is fine.
  const RunResult checked =
      Pba({"batch", "run", (dir_.path() / "static.yaml").string(), "--no-plot", "--dry-run"});
  EXPECT_EQ(checked.exit_code, 0) << checked.out << checked.err;
}

// plot: {file: sensors.csv} draws the sensors' samples: every member must be
// EXPLICIT_DYNAMIC with sensors, checked before anything is submitted; such
// members pass the checks (--dry-run: the explicit engine is not needed),
// and their history.csv may be drawn as well.
TEST_F(CliBatchPlotTest, ASensorPlotNeedsExplicitMembersWithSensors) {
  const std::string members = "members:\n  - {name: one, set: {mesh.element_size_mm: 5}}\n";
  const std::string sensors =
      "plot: {file: sensors.csv, x: time_s, y: [\"centre pressure [Pa]\"]}\n";
  RunResult run = Pba({"batch", "run", Batch("quasi", members, sensors).string(), "--dry-run"});
  EXPECT_EQ(run.exit_code, kInvalid) << run.out << run.err;
  EXPECT_NE(run.err.find("member 'one': plot: only an EXPLICIT_DYNAMIC analysis writes the "
                         "sensors.csv"),
            std::string::npos)
      << run.err;

  run = Pba({"batch", "run", Batch("struck", members, sensors, "struck_scene.yaml").string(),
             "--dry-run"});
  EXPECT_EQ(run.exit_code, 0) << run.out << run.err;
  EXPECT_NE(run.out.find("1 members; nothing submitted"), std::string::npos) << run.out;

  const std::string energy = "plot: {x: time_s, y: [kinetic_j]}\n";
  run = Pba({"batch", "run", Batch("energy", members, energy, "struck_scene.yaml").string(),
             "--dry-run"});
  EXPECT_EQ(run.exit_code, 0) << run.out << run.err;

  // A member whose sensors are taken away writes no sensors.csv.
  const std::string bare = "members:\n  - {name: bare, set: {outputs.sensors: []}}\n";
  run = Pba(
      {"batch", "run", Batch("bare", bare, sensors, "struck_scene.yaml").string(), "--dry-run"});
  EXPECT_EQ(run.exit_code, kInvalid) << run.out << run.err;
  EXPECT_NE(run.err.find("member 'bare': plot: its scene has no outputs.sensors"),
            std::string::npos)
      << run.err;

  run = Pba({"batch", "run",
             Batch("odd", members, "plot: {file: result.h5, x: time_s, y: [a]}\n").string(),
             "--dry-run"});
  EXPECT_EQ(run.exit_code, kInvalid) << run.out << run.err;
  EXPECT_NE(run.err.find("plot: file: expected history.csv (the default) or sensors.csv"),
            std::string::npos)
      << run.err;
  EXPECT_EQ(JobCount(), 0u);
}

// A member that fails is left out with a warning; the others are drawn and
// the batch's exit code says one failed.
TEST_F(CliBatchPlotTest, AFailedMemberIsLeftOut) {
  const fs::path file =
      Batch("crush",
            "members:\n"
            "  - {name: gentle, set: {analysis.time.end_time_s: 1}}\n"
            "  - {name: crushed, set: {\"boundary_conditions[1].displacement.z_mm\": "
            "-30}}\n",
            kTopForce);
  const RunResult run = Pba({"batch", "run", file.string()});
  std::cout << run.out << run.err;
  EXPECT_EQ(run.exit_code, kJobFailed) << run.out << run.err;
  EXPECT_NE(run.err.find("warning: member 'crushed'"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("left out of the plot"), std::string::npos) << run.err;
  EXPECT_NE(run.out.find("(1 series, 1 member(s) left out)"), std::string::npos) << run.out;
  RgbImage image;
  ASSERT_TRUE(ReadRgbPng(dir_.path() / "crush.png", &image).ok());
  EXPECT_GT(CountColour(image, SeriesColour(0)), 50);
  EXPECT_EQ(CountColour(image, SeriesColour(1)), 0);
}

}  // namespace
}  // namespace pba::testing
