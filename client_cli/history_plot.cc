#include "history_plot.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace pba::cli {
namespace {

// One CSV record and the line it starts on (1-based).
struct Record {
  std::vector<std::string> fields;
  int line = 0;
};

// Splits `text` into records; false with *error when a quoted field is not
// closed or a quote stands inside an unquoted field.
bool SplitRecords(const std::string& text, std::vector<Record>* records, std::string* error) {
  int line = 1;
  size_t i = 0;
  const size_t n = text.size();
  while (i < n) {
    // A blank line (LF or CRLF) is no record.
    if (text[i] == '\n' || (text[i] == '\r' && i + 1 < n && text[i + 1] == '\n')) {
      i += text[i] == '\r' ? 2 : 1;
      ++line;
      continue;
    }
    Record record;
    record.line = line;
    while (true) {
      std::string field;
      if (i < n && text[i] == '"') {
        const int opened = line;
        ++i;
        while (true) {
          if (i >= n) {
            *error = "line " + std::to_string(opened) + ": a quoted field is not closed";
            return false;
          }
          if (text[i] == '"') {
            if (i + 1 < n && text[i + 1] == '"') {
              field += '"';
              i += 2;
              continue;
            }
            ++i;
            break;
          }
          if (text[i] == '\n') ++line;
          field += text[i++];
        }
        if (i < n && text[i] != ',' && text[i] != '\n' && text[i] != '\r') {
          *error = "line " + std::to_string(line) + ": text after a quoted field's closing quote";
          return false;
        }
      } else {
        while (i < n && text[i] != ',' && text[i] != '\n' &&
               !(text[i] == '\r' && i + 1 < n && text[i + 1] == '\n')) {
          if (text[i] == '"') {
            *error = "line " + std::to_string(line) + ": a quote inside an unquoted field";
            return false;
          }
          field += text[i++];
        }
      }
      record.fields.push_back(std::move(field));
      if (i < n && text[i] == ',') {
        ++i;
        continue;
      }
      // The end of the record: a line break or the end of the text.
      if (i < n && text[i] == '\r') ++i;
      if (i < n && text[i] == '\n') {
        ++i;
        ++line;
      }
      break;
    }
    records->push_back(std::move(record));
  }
  return true;
}

// A cell as a number: empty (or blank) is NaN; false when it is not one.
bool ParseNumber(const std::string& cell, double* value) {
  const char* begin = cell.c_str();
  while (*begin == ' ' || *begin == '\t') ++begin;
  if (*begin == '\0') {
    *value = NAN;
    return true;
  }
  char* end = nullptr;
  *value = std::strtod(begin, &end);
  if (end == begin) return false;
  while (*end == ' ' || *end == '\t') ++end;
  return *end == '\0';
}

std::string Quoted(const std::string& text) { return "'" + text + "'"; }

}  // namespace

int HistoryTable::Column(const std::string& name) const {
  for (size_t c = 0; c < columns.size(); ++c) {
    if (columns[c] == name) return static_cast<int>(c);
  }
  return -1;
}

bool ParseHistoryCsv(const std::string& text, HistoryTable* table, std::string* error) {
  *table = HistoryTable();
  std::vector<Record> records;
  if (!SplitRecords(text, &records, error)) return false;
  if (records.empty()) {
    *error = "no header row";
    return false;
  }
  table->columns = records[0].fields;
  table->values.assign(table->columns.size(), {});
  for (size_t r = 1; r < records.size(); ++r) {
    const Record& record = records[r];
    const std::string where = "line " + std::to_string(record.line);
    if (record.fields.size() != table->columns.size()) {
      *error = where + ": " + std::to_string(record.fields.size()) + " fields, the header has " +
               std::to_string(table->columns.size());
      return false;
    }
    for (size_t c = 0; c < record.fields.size(); ++c) {
      double value = 0;
      if (!ParseNumber(record.fields[c], &value)) {
        *error = where + ", column " + Quoted(table->columns[c]) + ": " + Quoted(record.fields[c]) +
                 " is not a number";
        return false;
      }
      table->values[c].push_back(value);
    }
  }
  return true;
}

bool ParsePlotSpec(const YAML::Node& node, PlotSpec* spec, std::string* error) {
  *spec = PlotSpec();
  if (!node.IsMap()) {
    *error =
        "expected a map {file: FILE, x: COLUMN, y: [COLUMN, ...], title: TEXT, scale_y: NUMBER}";
    return false;
  }
  for (const auto& entry : node) {
    const std::string key = entry.first.Scalar();
    if (key != "file" && key != "x" && key != "y" && key != "title" && key != "scale_y") {
      *error = "unknown key '" + key + "' (a plot has file, x, y, title, scale_y)";
      return false;
    }
  }
  if (node["file"]) {
    const std::string file = node["file"].IsScalar() ? node["file"].Scalar() : "";
    if (file != "history.csv" && file != "sensors.csv") {
      *error = "file: expected history.csv (the default) or sensors.csv";
      return false;
    }
    spec->file = file;
  }
  if (!node["x"] || !node["x"].IsScalar() || node["x"].Scalar().empty()) {
    *error = "x: the column of " + spec->file + " on the x axis is required (e.g. time_s)";
    return false;
  }
  spec->x = node["x"].Scalar();
  const YAML::Node y = node["y"];
  if (y && y.IsScalar() && !y.Scalar().empty()) {
    spec->y.push_back(y.Scalar());
  } else if (y && y.IsSequence()) {
    for (const auto& column : y) {
      if (!column.IsScalar() || column.Scalar().empty()) {
        *error = "y: expected column names of " + spec->file;
        return false;
      }
      spec->y.push_back(column.Scalar());
    }
  }
  if (spec->y.empty()) {
    *error =
        "y: one or more columns of " + spec->file + " are required (e.g. [\"reaction top z [N]\"])";
    return false;
  }
  if (node["title"]) {
    if (!node["title"].IsScalar()) {
      *error = "title: expected text";
      return false;
    }
    spec->title = node["title"].Scalar();
  }
  if (node["scale_y"]) {
    double scale = NAN;
    if (!node["scale_y"].IsScalar() || !ParseNumber(node["scale_y"].Scalar(), &scale) ||
        !std::isfinite(scale) || scale == 0) {
      *error = "scale_y: expected a finite number other than 0";
      return false;
    }
    spec->scale_y = scale;
  }
  spec->enabled = true;
  return true;
}

std::string PlotYLabel(const PlotSpec& spec) {
  std::string label;
  for (size_t i = 0; i < spec.y.size(); ++i) label += (i ? ", " : "") + spec.y[i];
  if (spec.scale_y == 1) return label;
  char factor[32];
  std::snprintf(factor, sizeof factor, "%g", spec.scale_y);
  return std::string(factor) + " * " + (spec.y.size() > 1 ? "(" + label + ")" : label);
}

bool AddHistorySeries(const PlotSpec& spec, const std::string& member, const HistoryTable& table,
                      LinePlot* plot, std::string* error) {
  std::vector<std::string> wanted = {spec.x};
  wanted.insert(wanted.end(), spec.y.begin(), spec.y.end());
  for (const std::string& column : wanted) {
    if (table.Column(column) >= 0) continue;
    std::string has;
    for (size_t c = 0; c < table.columns.size(); ++c) {
      has += (c ? ", " : "") + Quoted(table.columns[c]);
    }
    *error = "member " + Quoted(member) + ": its " + spec.file + " has no column " +
             Quoted(column) + "; its columns: " + (has.empty() ? "none" : has);
    return false;
  }
  const std::vector<double>& x = table.values[table.Column(spec.x)];
  for (const std::string& column : spec.y) {
    LineSeries series;
    series.name = spec.y.size() > 1 ? member + ": " + column : member;
    series.x = x;
    series.y = table.values[table.Column(column)];
    for (double& v : series.y) v *= spec.scale_y;
    series.colour = SeriesColour(static_cast<int>(plot->series.size()));
    plot->series.push_back(std::move(series));
  }
  return true;
}

}  // namespace pba::cli
