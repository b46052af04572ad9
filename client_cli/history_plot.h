// The pure part of a batch's `plot:` section: reading a job's history.csv
// or sensors.csv (one header row of column names, one row of numbers per
// time step or sample), the section itself, and turning one member's
// history into line-plot series. No I/O beyond the caller's text, no
// server.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "io/line_plot.h"

namespace pba::cli {

// A history.csv as columns of numbers.
struct HistoryTable {
  std::vector<std::string> columns;           // the header's names, in order
  std::vector<std::vector<double>> values;    // values[c][row]; an empty cell is NaN
  int Column(const std::string& name) const;  // its index, or -1
};

// Reads CSV text: fields separated by commas, a field in double quotes may
// hold commas, line breaks and doubled quotes (""), lines end in LF or CRLF,
// blank lines are skipped. The first record is the header; every later one
// has as many fields as it, each a number as strtod reads it (surrounding
// spaces allowed; "nan" and "inf" too) or empty (NaN). False with *error
// naming the line (and the column) that does not fit.
bool ParseHistoryCsv(const std::string& text, HistoryTable* table, std::string* error);

// A batch's `plot:` section.
struct PlotSpec {
  bool enabled = false;              // the batch has one
  std::string file = "history.csv";  // the result file drawn: history.csv or sensors.csv
  std::string x;                     // a column of that file
  std::vector<std::string> y;        // one or more columns of it
  std::string title;                 // "" -> the batch's name
  double scale_y = 1;                // every y value is multiplied by it
};

// Reads {file: history.csv or sensors.csv, x: COLUMN, y: COLUMN or [COLUMN,
// ...], title: TEXT, scale_y: NUMBER}; file is optional (history.csv).
// False with *error naming the key that does not fit (without the "plot"
// prefix, e.g. "y: expected ...").
bool ParsePlotSpec(const YAML::Node& node, PlotSpec* spec, std::string* error);

// The y axis' label: the y column (several joined by ", "), with the factor
// in front when it is not 1 ("-1 * reaction top z [N]").
std::string PlotYLabel(const PlotSpec& spec);

// Adds one series per y column of `member`'s history to `plot`, named by
// the member (and the column when there are several), coloured by its
// place in the plot. False with *error naming the member, the missing
// column and the columns the history has; nothing is added then.
bool AddHistorySeries(const PlotSpec& spec, const std::string& member, const HistoryTable& table,
                      LinePlot* plot, std::string* error);

}  // namespace pba::cli
