// The picture at the end of `pba batch run` when the batch file has a
// `plot:` section (history_plot.h): every succeeded member's history.csv
// fetched into a folder, and one PNG line plot of all of them.
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

// Fetches the history.csv of every member that succeeded (reusing a file
// already in options.histories whose checksum is the job's), warns about
// each member left out because it did not succeed, and draws one series per
// member and y column into options.png, printing its path. kExitOk (also
// when no member succeeded: then there is nothing to draw, and no picture),
// kExitInvalid when a history or a column is missing (the message names the
// member, the column and the columns it has; no picture is written), or the
// exit code of a failed download or write.
int DrawBatchPlot(Connection& connection, const PlotSpec& spec,
                  const std::vector<RunMember>& members, const BatchPlotOptions& options);

// Whether every member's scene writes a history (QUASI_STATIC); false with
// *error naming the first member that does not.
bool MembersWriteHistory(const std::vector<RunMember>& members, std::string* error);

}  // namespace pba::cli
