// The picture at the end of `pba batch run` when the batch file has a
// `plot:` section (history_plot.h): every succeeded member's history.csv (or
// sensors.csv, as the section's file says) fetched into a folder, and one
// PNG line plot of all of them.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "commands/batch_shared.h"
#include "connection.h"
#include "history_plot.h"

namespace pba::cli {

struct BatchPlotOptions {
  std::filesystem::path histories;  // the folder for <member>.csv
  std::filesystem::path png;        // the picture
  std::string default_title;        // when the plot has none
  bool quiet = false;               // messages to stderr (stdout is JSON)
};

// Fetches the spec.file (history.csv or sensors.csv) of every member that
// succeeded (reusing a file
// already in options.histories whose checksum is the job's), warns about
// each member left out because it did not succeed, and draws one series per
// member and y column into options.png, printing its path. kExitOk (also
// when no member succeeded: then there is nothing to draw, and no picture),
// kExitInvalid when a history or a column is missing (the message names the
// member, the column and the columns it has; no picture is written), or the
// exit code of a failed download or write.
int DrawBatchPlot(Connection& connection, const PlotSpec& spec,
                  const std::vector<RunMember>& members, const BatchPlotOptions& options);

// Whether every member's scene writes `file`: history.csv (QUASI_STATIC,
// EXPLICIT_DYNAMIC, DYNAMIC_RELAXATION) or sensors.csv (EXPLICIT_DYNAMIC
// with outputs.sensors); false with *error naming the first member that
// does not.
bool MembersWritePlotFile(const std::vector<RunMember>& members, const std::string& file,
                          std::string* error);

}  // namespace pba::cli
