// `pba batch run FILE.yaml`: a scripted batch. A base scene plus parameter
// sweeps, one job per member, submitted with bounded parallelism, ending in
// one table (CSV, or JSON with --json) of the chosen outputs per member.
//
//   name: mooney-ratios               # names the jobs and the state file
//   scene: uniaxial.yaml              # the base scene, relative to this file
//   parallel: 2                       # jobs in flight at most (default 2)
//   sweep:                            # every combination (cartesian product)
//     material.mooney_rivlin.c10_pa: [100, 200]
//     mesh.element_size_mm: [4, 2]
//   # or members: a list of {name: ..., set: {path: value, ...}}
//   outputs:                          # paths into each job's summary
//     - results.max_displacement_mm
//     - results.reactions[0].force_n[2]
//     - performance.wall_time_s
//   plot:                             # optional: every member's history
//     file: history.csv               # or sensors.csv (default history.csv)
//     x: time_s                       # a column of that file
//     y: ["reaction top z [N]"]       # one or more columns
//     title: "Three speeds"           # default: the batch's name
//     scale_y: -1                     # every y value times this (default 1)
//
// A path is the scene's (or the summary's) proto field names joined by dots,
// with [i] for the i-th element of a list (quote such a path inside a
// [...] list: YAML reads its brackets as the list's). Every member's scene is checked
// (the message names the member and the field) before anything is
// submitted.
//
// With plot, every member must write the file drawn (checked before anything
// is submitted, unless --no-plot): history.csv is written by QUASI_STATIC,
// EXPLICIT_DYNAMIC and DYNAMIC_RELAXATION, sensors.csv by EXPLICIT_DYNAMIC
// with outputs.sensors. After the members have ended, each succeeded
// member's file is fetched into FILE-stem_histories/MEMBER.csv (sensors.csv:
// FILE-stem_sensors/MEMBER.csv) beside the batch file (the member's name
// with characters other than letters, digits and "._-=,+" made "_"; a file
// already there with the job's checksum is kept, so a rerun of a finished
// batch downloads nothing new), and
// FILE-stem.png beside the table gets one series per member and y column,
// named by the member (and the column when there are several). A member
// that did not succeed is left out with a warning; a missing history or
// column names the member, the column and the columns there are, and no
// picture is written. --no-plot skips all of it.
//
// Resumable: FILE.pba-batch (beside the batch file) records each member's
// job; a rerun keeps the members whose job succeeded and submits the rest
// (a failed or cancelled one only with --retry-failed). Each submit carries
// a request id derived from the member's scene, so a member submitted just
// before an interruption is not submitted twice.
#pragma once

#include <string>

#include "connection.h"

namespace CLI {
class App;
}

namespace pba::cli {

class CommandContext;

struct BatchArgs {
  std::string file;
  std::string out;  // the table as CSV; default FILE's stem + ".csv" beside it
  bool retry_failed = false;
  int ranks = 0;         // MPI processes per member's job
  bool dry_run = false;  // check and list the members, submit nothing
  bool no_plot = false;  // skip the plot section's picture
  double poll_s = 0.5;
};

int RunBatch(Connection& connection, const BatchArgs& args);

// Adds `pba batch run` to `app`.
void RegisterBatchCommands(CLI::App& app, CommandContext& context);

}  // namespace pba::cli
