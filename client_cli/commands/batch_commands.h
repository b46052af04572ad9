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
//
// A path is the scene's (or the summary's) proto field names joined by dots,
// with [i] for the i-th element of a list (quote such a path inside a
// [...] list: YAML reads its brackets as the list's). Every member's scene is checked
// (the message names the member and the field) before anything is
// submitted.
//
// Resumable: FILE.pba-batch (beside the batch file) records each member's
// job; a rerun keeps the members whose job succeeded and submits the rest
// (a failed or cancelled one only with --retry-failed). Each submit carries
// a request id derived from the member's scene, so a member submitted just
// before an interruption is not submitted twice.
#pragma once

#include <string>

#include "connection.h"

namespace pba::cli {

struct BatchArgs {
  std::string file;
  std::string out;  // the table as CSV; default FILE's stem + ".csv" beside it
  bool retry_failed = false;
  bool dry_run = false;  // check and list the members, submit nothing
  bool no_plot = false;  // skip the plot section's picture
  double poll_s = 0.5;
};

int RunBatch(Connection& connection, const BatchArgs& args);

}  // namespace pba::cli
