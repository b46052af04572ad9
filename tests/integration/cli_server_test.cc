// End to end: the real pba-server on an ephemeral loopback port with a fresh
// data directory, driven by the real pba binary, running the real pba-solve.

#include <gtest/gtest.h>
#include <hdf5.h>
#include <signal.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <thread>

#include "common/subprocess.h"
#include "common/yaml_bombs.h"
#include "integration/block_scene.h"
#include "integration/server_fixture.h"

namespace pba::testing {
namespace {
namespace fs = std::filesystem;
using std::chrono::seconds;

// Exit codes of pba (client_cli/exit_codes.h, docs/cli.md).
constexpr int kUnavailable = 3;
constexpr int kNotFound = 4;
constexpr int kInvalid = 5;
constexpr int kJobFailed = 6;
constexpr int kJobCancelled = 7;

// A solve that runs for many seconds, so there is time to cancel it or
// kill its process.
const std::string kLongScene = BlockSceneYaml("long-running", 50);

class CliServerTest : public ServerTest {
 protected:
  std::string SubmitLongJob() {
    const RunResult submitted =
        Pba({"job", "submit", WriteScene("long.yaml", kLongScene).string()});
    EXPECT_EQ(submitted.exit_code, 0) << submitted.err;
    const std::string id = JobId(submitted);
    EXPECT_TRUE(WaitForState(id, "RUNNING", seconds(30)));
    return id;
  }
};

// A finite-strain job travels the same way and its summary shows the Newton
// path and the nonlinear fields.
TEST_F(CliServerTest, NonlinearJobReportsItsNewtonPath) {
  const RunResult submitted =
      Pba({"job", "submit", std::string(PBA_EXAMPLES_DIR) + "/brain_sample_compression.yaml",
           "--wait"});
  ASSERT_EQ(submitted.exit_code, 0) << submitted.out << submitted.err;
  EXPECT_NE(submitted.out.find("SUCCEEDED"), std::string::npos) << submitted.out;
  EXPECT_NE(submitted.out.find("Ogden"), std::string::npos) << submitted.out;
  EXPECT_NE(submitted.out.find("Newton "), std::string::npos) << submitted.out;
  EXPECT_NE(submitted.out.find("nonlinear static"), std::string::npos) << submitted.out;

  const RunResult json = Pba({"--json", "job", "status", JobId(submitted)});
  ASSERT_EQ(json.exit_code, 0) << json.err;
  EXPECT_NE(json.out.find("\"convergence\""), std::string::npos) << json.out;
  EXPECT_NE(json.out.find("\"newton_iterations\""), std::string::npos) << json.out;
}

TEST_F(CliServerTest, SubmitWaitFetchRoundTrip) {
  const RunResult submitted =
      Pba({"job", "submit", std::string(PBA_EXAMPLES_DIR) + "/quickstart.yaml", "--wait"});
  ASSERT_EQ(submitted.exit_code, 0) << submitted.out << submitted.err;
  const std::string id = JobId(submitted);
  ASSERT_FALSE(id.empty()) << submitted.out;
  EXPECT_NE(submitted.out.find("SUCCEEDED"), std::string::npos) << submitted.out;
  EXPECT_NE(submitted.out.find("max von Mises"), std::string::npos) << submitted.out;

  const RunResult list = Pba({"job", "list"});
  ASSERT_EQ(list.exit_code, 0) << list.err;
  EXPECT_NE(list.out.find(id), std::string::npos);
  EXPECT_NE(list.out.find("quickstart-block-compression"), std::string::npos);

  const RunResult status = Pba({"job", "status", id});
  ASSERT_EQ(status.exit_code, 0) << status.err;
  EXPECT_NE(status.out.find("SUCCEEDED"), std::string::npos);
  EXPECT_NE(status.out.find("Wall time"), std::string::npos);
  EXPECT_NE(status.out.find("Error"), std::string::npos);

  // The watch of a finished job replays its events as plain lines (no terminal).
  const RunResult watch = Pba({"job", "watch", id});
  EXPECT_EQ(watch.exit_code, 0) << watch.err;
  EXPECT_NE(watch.out.find("RUNNING"), std::string::npos) << watch.out;
  EXPECT_NE(watch.out.find("SUCCEEDED"), std::string::npos) << watch.out;
  EXPECT_EQ(watch.out.find('\r'), std::string::npos) << "no bar redraws outside a terminal";

  const fs::path out = dir_.path() / "fetched";
  const RunResult fetch = Pba({"job", "fetch", id, "-o", out.string()});
  ASSERT_EQ(fetch.exit_code, 0) << fetch.err;
  EXPECT_NE(fetch.out.find("result.xdmf"), std::string::npos);
  for (const char* name : {"result.h5", "result.xdmf", "summary.json"}) {
    EXPECT_TRUE(fs::exists(out / name)) << name;
    EXPECT_FALSE(fs::exists(out / (std::string(name) + ".part"))) << name;
  }
  // The downloaded result.h5 is a real HDF5 file with the displacement field.
  const hid_t file = H5Fopen((out / "result.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  const hid_t nodes = H5Dopen2(file, "/mesh/nodes", H5P_DEFAULT);
  const hid_t displacement = H5Dopen2(file, "/fields/displacement", H5P_DEFAULT);
  ASSERT_GE(nodes, 0);
  ASSERT_GE(displacement, 0);
  hsize_t node_dims[2] = {0, 0}, disp_dims[2] = {0, 0};
  const hid_t node_space = H5Dget_space(nodes);
  const hid_t disp_space = H5Dget_space(displacement);
  H5Sget_simple_extent_dims(node_space, node_dims, nullptr);
  H5Sget_simple_extent_dims(disp_space, disp_dims, nullptr);
  EXPECT_GT(node_dims[0], 100u);
  EXPECT_EQ(node_dims[0], disp_dims[0]);
  EXPECT_EQ(disp_dims[1], 3u);
  H5Sclose(node_space);
  H5Sclose(disp_space);
  H5Dclose(nodes);
  H5Dclose(displacement);
  H5Fclose(file);
  const std::string summary = ReadFile(out / "summary.json");
  EXPECT_NE(summary.find("\"wall_time_s\""), std::string::npos);
  EXPECT_NE(summary.find("\"error_estimate\""), std::string::npos);

  // A repeated fetch does not overwrite them (exit 9) unless --force says so.
  EXPECT_EQ(Pba({"job", "fetch", id, "-o", out.string()}).exit_code, 9);
  EXPECT_EQ(Pba({"job", "fetch", id, "-o", out.string(), "--force"}).exit_code, 0);
}

TEST_F(CliServerTest, JsonOutputIsParseableAndPaginates) {
  const std::string scene = std::string(PBA_EXAMPLES_DIR) + "/quickstart.yaml";
  for (int i = 0; i < 3; ++i) ASSERT_EQ(Pba({"job", "submit", scene}).exit_code, 0);
  const RunResult page = Pba({"--json", "job", "list", "--page-size", "2"});
  ASSERT_EQ(page.exit_code, 0) << page.err;
  EXPECT_NE(page.out.find("\"next_page_token\""), std::string::npos) << page.out;
  const RunResult all = Pba({"--json", "job", "list", "--page-size", "2", "--all"});
  ASSERT_EQ(all.exit_code, 0) << all.err;
  EXPECT_EQ(CountOf(all.out, "\"id\""), 3u) << all.out;
}

TEST_F(CliServerTest, IdempotentSubmitWithRequestId) {
  const std::string scene = std::string(PBA_EXAMPLES_DIR) + "/quickstart.yaml";
  const RunResult first = Pba({"job", "submit", scene, "--request-id", "same-key"});
  const RunResult second = Pba({"job", "submit", scene, "--request-id", "same-key"});
  ASSERT_EQ(first.exit_code, 0) << first.err;
  ASSERT_EQ(second.exit_code, 0) << second.err;
  EXPECT_EQ(JobId(first), JobId(second));
}

TEST_F(CliServerTest, BadScenesAreRejectedAndNothingIsStored) {
  struct Case {
    const char* yaml;
    const char* field;
  };
  const Case cases[] = {
      {"name: a\ngeometry: {box: {size_mm: [1, 1, 1]}}\nmaterial: {linear_elastic: "
       "{youngs_modulus_pa: 1, poissons_ratio: 0.3}}\ncolour: red\n",
       "colour"},
      {"material:\n  linear_elastic:\n    youngs_modulus_pa: soft\n",
       "material.linear_elastic.youngs_modulus_pa"},
      {"geometry: {box: {size_mm: [10, 10, 10]}}\nmaterial: {linear_elastic: {youngs_modulus_pa: "
       "-5, poissons_ratio: 0.3}}\nboundary_conditions: [{set: bottom, fixed: {}}]\n",
       "material.linear_elastic.youngs_modulus_pa"},
      {"geometry: {box: {size_mm: [10, 10, 10]}}\nmaterial: {linear_elastic: {youngs_modulus_pa: "
       "3000, poissons_ratio: 0.5}}\nboundary_conditions: [{set: bottom, fixed: {}}]\n",
       "material.linear_elastic.poissons_ratio"},
      {"geometry: {box: {size_mm: [10, 10, 10]}}\nmaterial: {linear_elastic: {youngs_modulus_pa: "
       "3000, poissons_ratio: 0.3}}\nboundary_conditions: [{set: floor, fixed: {}}]\n",
       "boundary_conditions[0].set"},
  };
  int i = 0;
  for (const Case& c : cases) {
    const fs::path file = WriteScene("bad" + std::to_string(i++) + ".yaml", c.yaml);
    const RunResult result = Pba({"job", "submit", file.string()});
    EXPECT_EQ(result.exit_code, kInvalid) << c.field << "\n" << result.err;
    EXPECT_NE(result.err.find(c.field), std::string::npos) << result.err;
  }
  const RunResult list = Pba({"--json", "job", "list"});
  ASSERT_EQ(list.exit_code, 0) << list.err;
  EXPECT_EQ(list.out.find("\"id\""), std::string::npos) << "a rejected scene was stored:\n"
                                                        << list.out;
}

// A scene of nine levels of ten aliases once aborted the client with
// std::bad_alloc; it is refused as invalid input naming the alias.
TEST_F(CliServerTest, AliasBombSceneIsRefusedAsInvalid) {
  const std::string yaml = "name: bomb\n" + yaml_bombs::BillionLaughs();
  const auto start = std::chrono::steady_clock::now();
  const RunResult result = Pba({"job", "submit", WriteScene("bomb.yaml", yaml).string()});
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 10);
  EXPECT_EQ(result.exit_code, kInvalid) << result.err;
  EXPECT_NE(result.err.find("bomb.yaml:3: YAML aliases (*l0) are not accepted"), std::string::npos)
      << result.err;
  const RunResult list = Pba({"--json", "job", "list"});
  ASSERT_EQ(list.exit_code, 0) << list.err;
  EXPECT_EQ(list.out.find("\"id\""), std::string::npos) << list.out;
}

// A scene over the guard's size cap (an error with no line and no field)
// is still the user's input at fault: exit 5, not a plain error; only a
// file that cannot be read at all is.
TEST_F(CliServerTest, OversizedSceneIsRefusedAsInvalid) {
  const std::string yaml = "name: big\n# " + std::string(size_t{17} << 20, 'x') + "\n";
  const RunResult result = Pba({"job", "submit", WriteScene("big.yaml", yaml).string()});
  EXPECT_EQ(result.exit_code, kInvalid) << result.err;
  EXPECT_NE(result.err.find("bytes; at most"), std::string::npos) << result.err;
  const RunResult missing = Pba({"job", "submit", (dir_.path() / "no-such.yaml").string()});
  EXPECT_NE(missing.exit_code, kInvalid) << missing.err;
  EXPECT_NE(missing.exit_code, 0) << missing.err;
}

// A scripted batch: a base scene over a sweep, two jobs at a time, one table
// of outputs per member; a rerun submits nothing, and even without its state
// file the members' request ids find the jobs already made.
TEST_F(CliServerTest, BatchRunsASweepOnceAndResumes) {
  const fs::path base = WriteScene("base.yaml", R"(
name: batch-block
geometry: {box: {size_mm: [10, 10, 10]}}
mesh: {element_size_mm: 5}
material: {linear_elastic: {youngs_modulus_pa: 3000, poissons_ratio: 0.45}}
boundary_conditions:
  - {set: bottom, fixed: {}}
  - {set: top, displacement: {x_mm: 0, y_mm: 0, z_mm: -1}}
)");
  const fs::path batch = WriteScene("sweep.yaml", R"(
name: stiffness
scene: base.yaml
parallel: 2
sweep:
  material.linear_elastic.youngs_modulus_pa: [3000, 6000]
  material.linear_elastic.poissons_ratio: [0.3, 0.45]
outputs:
  - results.reactions[1].force_n[2]
  - results.max_displacement_mm
)");
  const RunResult run = Pba({"batch", "run", batch.string()});
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  const std::string csv = ReadFile(dir_.path() / "sweep.csv");
  std::vector<std::string> lines;
  std::stringstream stream(csv);
  for (std::string line; std::getline(stream, line);) lines.push_back(line);
  ASSERT_EQ(lines.size(), 5u) << csv;
  EXPECT_EQ(lines[0],
            "member,material.linear_elastic.youngs_modulus_pa,"
            "material.linear_elastic.poissons_ratio,job,state,results.reactions[1].force_n[2],"
            "results.max_displacement_mm");
  // The reaction on the top (the second set) is linear in the modulus.
  std::map<std::string, double> force;
  for (size_t i = 1; i < lines.size(); ++i) {
    EXPECT_NE(lines[i].find("SUCCEEDED"), std::string::npos) << lines[i];
    std::vector<std::string> cells;
    std::string cell;
    std::stringstream row(lines[i].substr(lines[i].rfind('"') + 2));
    while (std::getline(row, cell, ',')) cells.push_back(cell);
    ASSERT_EQ(cells.size(), 6u) << lines[i];
    force[cells[0] + "/" + cells[1]] = std::stod(cells[4]);
  }
  EXPECT_NEAR(force["6000/0.3"], 2 * force["3000/0.3"], 1e-9 * std::abs(force["3000/0.3"]));
  EXPECT_NEAR(force["6000/0.45"], 2 * force["3000/0.45"], 1e-9 * std::abs(force["3000/0.45"]));
  EXPECT_NE(force["3000/0.3"], force["3000/0.45"]);

  const RunResult again = Pba({"batch", "run", batch.string()});
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_NE(again.out.find("4 from an earlier run, 0 to submit"), std::string::npos) << again.out;
  fs::remove(batch.string() + ".pba-batch");
  const RunResult lost = Pba({"batch", "run", batch.string()});
  ASSERT_EQ(lost.exit_code, 0) << lost.err;
  EXPECT_EQ(ReadFile(dir_.path() / "sweep.csv"), csv);
  EXPECT_EQ(JobCount(), 4u);
}

// A server that takes at most two open jobs from one user (pba-server
// --max-open-jobs 2).
class CliBoundedServerTest : public CliServerTest {
 protected:
  std::vector<std::string> ServerArgs() const override { return {"--max-open-jobs", "2"}; }
};

// `pba server` says how the server runs jobs; a batch handed over all at
// once meets the server's bound of open jobs per user and waits for room
// instead of failing, whether its own jobs or the user's others hold it; a batch that does not say
// how many at a time goes two at a time to a server that runs jobs itself.
TEST_F(CliBoundedServerTest, ABatchOverTheServersBoundWaitsForItsJobsToEnd) {
  const RunResult info = Pba({"server"});
  ASSERT_EQ(info.exit_code, 0) << info.out << info.err;
  EXPECT_NE(info.out.find("executor: local"), std::string::npos) << info.out;
  EXPECT_NE(info.out.find("jobs queued or running per user: 2\n"), std::string::npos) << info.out;
  const RunResult json = Pba({"--json", "server"});
  EXPECT_NE(json.out.find("\"max_open_jobs\": 2"), std::string::npos) << json.out;

  // Each member runs about a second: the third submit finds two open.
  WriteScene("hold.yaml", HoldSceneYaml(4));
  const fs::path all = WriteScene("all.yaml", R"(
name: all-at-once
scene: hold.yaml
parallel: all
sweep:
  material.neo_hookean.shear_modulus_pa: [1000, 2000, 3000, 4000, 5000]
outputs:
  - results.reactions[0].force_n[2]
)");
  const RunResult run = Pba({"batch", "run", all.string()});
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  EXPECT_NE(run.out.find("5 to submit, all at once"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("the server takes no more open jobs from you now (its bound counts all "
                         "your queued and running jobs; 2 are this batch's); waiting for room"),
            std::string::npos)
      << run.out;
  const std::string csv = ReadFile(dir_.path() / "all.csv");
  EXPECT_EQ(CountOf(csv, "SUCCEEDED"), 5u) << csv;
  EXPECT_EQ(JobCount(), 5u);

  // The user's other jobs fill the bound: the batch waits for room, none
  // of its own open, and goes on once they end.
  for (int i = 0; i < 2; ++i) {
    const RunResult other = Pba({"job", "submit", (dir_.path() / "hold.yaml").string()});
    ASSERT_EQ(other.exit_code, 0) << other.out << other.err;
  }
  const fs::path after = WriteScene("after.yaml", R"(
name: after-others
scene: hold.yaml
parallel: all
members:
  - {name: soft, set: {material.neo_hookean.shear_modulus_pa: 1000}}
)");
  const RunResult waited = Pba({"batch", "run", after.string()});
  ASSERT_EQ(waited.exit_code, 0) << waited.out << waited.err;
  EXPECT_NE(waited.out.find("0 are this batch's); waiting for room"), std::string::npos)
      << waited.out;
  EXPECT_EQ(CountOf(ReadFile(dir_.path() / "after.csv"), "SUCCEEDED"), 1u);
  EXPECT_EQ(JobCount(), 8u);

  const fs::path unsaid = WriteScene("unsaid.yaml", R"(
scene: hold.yaml
members:
  - {name: soft, set: {material.neo_hookean.shear_modulus_pa: 1000}}
)");
  const RunResult local = Pba({"batch", "run", unsaid.string()});
  ASSERT_EQ(local.exit_code, 0) << local.out << local.err;
  EXPECT_NE(local.out.find("1 to submit, 2 at a time"), std::string::npos) << local.out;

  const fs::path wrong = WriteScene("wrong.yaml",
                                    "scene: hold.yaml\nparallel: most\n"
                                    "members: [{name: a, set: {}}]\n");
  const RunResult refused = Pba({"batch", "run", wrong.string()});
  EXPECT_EQ(refused.exit_code, kInvalid) << refused.out << refused.err;
  EXPECT_NE(refused.err.find("parallel: expected a whole number from 1 to 64, or all"),
            std::string::npos)
      << refused.err;
}

// The example batch runs as shipped (copied with its base scene, so that its
// state file is written in the test's directory).
TEST_F(CliServerTest, ExampleBatchRuns) {
  fs::create_directories(dir_.path() / "batches");
  fs::copy_file(std::string(PBA_EXAMPLES_DIR) + "/quickstart.yaml",
                dir_.path() / "quickstart.yaml");
  const fs::path batch = dir_.path() / "batches" / "quickstart_sweep.yaml";
  fs::copy_file(std::string(PBA_EXAMPLES_DIR) + "/batches/quickstart_sweep.yaml", batch);
  const RunResult run = Pba({"batch", "run", batch.string()});
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  const std::string csv = ReadFile(dir_.path() / "batches" / "quickstart_sweep.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 7) << csv;
  EXPECT_EQ(csv.find("FAILED"), std::string::npos) << csv;
}

// A member whose change does not fit the scene is named, with the field,
// before anything is submitted.
TEST_F(CliServerTest, BatchWithABadMemberSubmitsNothing) {
  WriteScene("base.yaml", kLongScene);
  const fs::path batch = WriteScene("bad.yaml", R"(
scene: base.yaml
members:
  - {name: soft, set: {material.linear_elastic.youngs_modulus_pa: 1000}}
  - {name: typo, set: {material.linear_elastic.youngs_modulus: 2000}}
)");
  const RunResult run = Pba({"batch", "run", batch.string()});
  EXPECT_EQ(run.exit_code, kInvalid) << run.out << run.err;
  EXPECT_NE(run.err.find("member 'typo'"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("youngs_modulus"), std::string::npos) << run.err;
  const RunResult list = Pba({"job", "list"});
  EXPECT_NE(list.out.find("No jobs."), std::string::npos) << list.out;
  EXPECT_FALSE(fs::exists(batch.string() + ".pba-batch"));
}

TEST_F(CliServerTest, UnknownJobIsNotFound) {
  const RunResult status = Pba({"job", "status", "jdoesnotexist"});
  EXPECT_EQ(status.exit_code, kNotFound);
  EXPECT_NE(status.err.find("jdoesnotexist"), std::string::npos) << status.err;
  const RunResult fetch =
      Pba({"job", "fetch", "jdoesnotexist", "-o", (dir_.path() / "x").string()});
  EXPECT_EQ(fetch.exit_code, kNotFound);
  EXPECT_FALSE(fs::exists(dir_.path() / "x"));
}

TEST_F(CliServerTest, CancelLongJob) {
  const std::string id = SubmitLongJob();
  const RunResult cancel = Pba({"job", "cancel", id});
  EXPECT_EQ(cancel.exit_code, 0) << cancel.err;
  const RunResult watch = Pba({"job", "watch", id}, seconds(60));
  EXPECT_EQ(watch.exit_code, kJobCancelled) << watch.out << watch.err;
  EXPECT_TRUE(WaitForState(id, "CANCELLED", seconds(5)));
  EXPECT_TRUE(ChildrenNamed(server_->pid(), "pba-solve").empty());
  const RunResult fetch = Pba({"job", "fetch", id, "-o", (dir_.path() / "x").string()});
  EXPECT_EQ(fetch.exit_code, kJobCancelled);
  EXPECT_NE(fetch.err.find("cancelled"), std::string::npos) << fetch.err;
}

TEST_F(CliServerTest, KilledSolverFailsTheJobAndServerKeepsServing) {
  const std::string id = SubmitLongJob();
  std::vector<pid_t> solvers;
  for (int i = 0; i < 100 && solvers.empty(); ++i) {
    solvers = ChildrenNamed(server_->pid(), "pba-solve");
    if (solvers.empty()) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ASSERT_EQ(solvers.size(), 1u);
  ::kill(solvers[0], SIGKILL);
  ASSERT_TRUE(WaitForState(id, "FAILED", seconds(30)));
  const RunResult status = Pba({"job", "status", id});
  EXPECT_NE(status.out.find("signal 9"), std::string::npos) << status.out;

  const RunResult fetch = Pba({"job", "fetch", id, "-o", (dir_.path() / "x").string()});
  EXPECT_EQ(fetch.exit_code, kJobFailed);
  EXPECT_NE(fetch.err.find("failed"), std::string::npos) << fetch.err;

  const RunResult next =
      Pba({"job", "submit", std::string(PBA_EXAMPLES_DIR) + "/quickstart.yaml", "--wait"});
  EXPECT_EQ(next.exit_code, 0) << next.out << next.err;
}

TEST_F(CliServerTest, RunningJobIsRequeuedAfterServerCrash) {
  const std::string id = SubmitLongJob();
  server_->Kill();
  // The solver dies with its server (it is the server's child).
  std::string log;
  ASSERT_TRUE(server_->Start(&log)) << log;
  const RunResult status = Pba({"--json", "job", "status", id});
  ASSERT_EQ(status.exit_code, 0) << status.err;
  EXPECT_TRUE(status.out.find("\"state\": \"QUEUED\"") != std::string::npos ||
              status.out.find("\"state\": \"RUNNING\"") != std::string::npos)
      << status.out;
  ASSERT_TRUE(WaitForState(id, "RUNNING", seconds(30)));
  const RunResult watch = Pba({"job", "watch", id}, seconds(2));  // cut short: it is still running
  EXPECT_NE(watch.out.find("re-queued"), std::string::npos) << watch.out;
  EXPECT_EQ(Pba({"job", "cancel", id}).exit_code, 0);
  EXPECT_TRUE(WaitForState(id, "CANCELLED", seconds(30)));
}

TEST_F(CliServerTest, GracefulStopWithRunningJob) {
  const std::string id = SubmitLongJob();
  EXPECT_EQ(server_->Stop(seconds(30)), 0);
  EXPECT_FALSE(fs::exists(dir_.path() / "data" / "server.json"));
  std::string log;
  ASSERT_TRUE(server_->Start(&log)) << log;
  const RunResult status = Pba({"--json", "job", "status", id});
  ASSERT_EQ(status.exit_code, 0) << status.err;
  EXPECT_EQ(status.out.find("\"state\": \"FAILED\""), std::string::npos) << status.out;
  EXPECT_EQ(Pba({"job", "cancel", id}).exit_code, 0);
  EXPECT_TRUE(WaitForState(id, "CANCELLED", seconds(30)));
}

TEST(CliWithoutServerTest, UnreachableServerIsNamed) {
  // Port 1 on loopback: nothing listens there.
  const RunResult result = RunProcess({PBA_CLI_BIN, "--server", "127.0.0.1:1", "job", "list"});
  EXPECT_EQ(result.exit_code, kUnavailable);
  EXPECT_NE(result.err.find("127.0.0.1:1"), std::string::npos) << result.err;
  EXPECT_EQ(result.err.find("terminate"), std::string::npos) << result.err;
}

TEST(CliWithoutServerTest, UsageErrorsExitTwo) {
  EXPECT_EQ(RunProcess({PBA_CLI_BIN, "job", "frobnicate"}).exit_code, 2);
  EXPECT_EQ(RunProcess({PBA_CLI_BIN, "job", "submit", "/nonexistent.yaml"}).exit_code, 2);
}

}  // namespace
}  // namespace pba::testing
