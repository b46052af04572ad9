// A batch's plot section without a server: history.csv as the solver writes
// it (quoted names with commas, numbers, empty cells), the plot: section's
// keys, and the series one member's history gives.

#include "history_plot.h"

#include <gtest/gtest.h>

#include <cmath>

namespace pba::cli {
namespace {

HistoryTable Parse(const std::string& text) {
  HistoryTable table;
  std::string error;
  EXPECT_TRUE(ParseHistoryCsv(text, &table, &error)) << error;
  return table;
}

std::string ParseError(const std::string& text) {
  HistoryTable table;
  std::string error;
  EXPECT_FALSE(ParseHistoryCsv(text, &table, &error)) << text;
  return error;
}

PlotSpec Spec(const std::string& yaml) {
  PlotSpec spec;
  std::string error;
  EXPECT_TRUE(ParsePlotSpec(YAML::Load(yaml), &spec, &error)) << error;
  return spec;
}

std::string SpecError(const std::string& yaml) {
  PlotSpec spec;
  std::string error;
  EXPECT_FALSE(ParsePlotSpec(YAML::Load(yaml), &spec, &error)) << yaml;
  return error;
}

TEST(HistoryCsvTest, ReadsQuotedNamesNumbersAndEmptyCells) {
  const HistoryTable t = Parse(
      "time_s,amplitude,\"punch, left z [N]\",\"say \"\"hi\"\"\"\r\n"
      "0,0,0,1e-3\r\n"
      "\r\n"
      "0.5, 0.25 ,,-2.5E+2\r\n"
      "1,1,nan,\"7\"\n");
  ASSERT_EQ(t.columns.size(), 4u);
  EXPECT_EQ(t.columns[2], "punch, left z [N]");
  EXPECT_EQ(t.columns[3], "say \"hi\"");
  EXPECT_EQ(t.Column("punch, left z [N]"), 2);
  EXPECT_EQ(t.Column("punch"), -1);
  ASSERT_EQ(t.values[0].size(), 3u);
  EXPECT_EQ(t.values[1][1], 0.25);
  EXPECT_EQ(t.values[3][0], 1e-3);
  EXPECT_EQ(t.values[3][1], -250);
  EXPECT_EQ(t.values[3][2], 7);
  EXPECT_TRUE(std::isnan(t.values[2][1])) << "an empty cell";
  EXPECT_TRUE(std::isnan(t.values[2][2]));
}

TEST(HistoryCsvTest, AHeaderAloneIsATableWithoutRows) {
  const HistoryTable t = Parse("time_s,amplitude");
  ASSERT_EQ(t.columns.size(), 2u);
  EXPECT_TRUE(t.values[0].empty());
  // A quoted field may span lines; the trailing empty field counts.
  const HistoryTable u = Parse("\"a\nb\",c,\n1,2,\n");
  ASSERT_EQ(u.columns.size(), 3u);
  EXPECT_EQ(u.columns[0], "a\nb");
  EXPECT_TRUE(std::isnan(u.values[2][0]));
}

TEST(HistoryCsvTest, NamesTheLineAndColumnThatDoNotFit) {
  EXPECT_EQ(ParseError(""), "no header row");
  EXPECT_EQ(ParseError("a,b\n1,2\n3\n"), "line 3: 1 fields, the header has 2");
  EXPECT_EQ(ParseError("a,b\n1,2\n3,x4\n"), "line 3, column 'b': 'x4' is not a number");
  EXPECT_EQ(ParseError("a,b\n1,\"2\n"), "line 2: a quoted field is not closed");
  EXPECT_EQ(ParseError("a,b\"c\n"), "line 1: a quote inside an unquoted field");
  EXPECT_EQ(ParseError("\"a\"x,b\n"), "line 1: text after a quoted field's closing quote");
  // Line numbers count the breaks inside quoted fields.
  EXPECT_EQ(ParseError("\"a\nb\",c\n1,2,3\n"), "line 3: 3 fields, the header has 2");
}

TEST(PlotSpecTest, ReadsTheSection) {
  const PlotSpec s = Spec(
      "{x: 'contact punch travel [mm]', y: ['contact punch z [N]', amplitude], title: Speeds, "
      "scale_y: -1}");
  EXPECT_TRUE(s.enabled);
  EXPECT_EQ(s.x, "contact punch travel [mm]");
  EXPECT_EQ(s.y, (std::vector<std::string>{"contact punch z [N]", "amplitude"}));
  EXPECT_EQ(s.title, "Speeds");
  EXPECT_EQ(s.scale_y, -1);
  EXPECT_EQ(PlotYLabel(s), "-1 * (contact punch z [N], amplitude)");

  EXPECT_EQ(s.file, "history.csv");

  const PlotSpec one = Spec("{x: time_s, y: amplitude}");
  EXPECT_EQ(one.y, std::vector<std::string>{"amplitude"});
  const PlotSpec sensors = Spec("{file: sensors.csv, x: time_s, y: 'centre pressure [Pa]'}");
  EXPECT_EQ(sensors.file, "sensors.csv");
  EXPECT_EQ(one.scale_y, 1);
  EXPECT_EQ(PlotYLabel(one), "amplitude");
}

TEST(PlotSpecTest, NamesTheKeyThatDoesNotFit) {
  EXPECT_NE(SpecError("[time_s]").find("expected a map"), std::string::npos);
  EXPECT_NE(SpecError("{x: time_s, y: [a], colour: red}").find("unknown key 'colour'"),
            std::string::npos);
  EXPECT_EQ(SpecError("{y: [a]}").rfind("x: ", 0), 0u);
  EXPECT_EQ(SpecError("{x: time_s}").rfind("y: ", 0), 0u);
  EXPECT_EQ(SpecError("{x: time_s, y: []}").rfind("y: ", 0), 0u);
  EXPECT_EQ(SpecError("{x: time_s, y: [[a]]}").rfind("y: ", 0), 0u);
  EXPECT_EQ(SpecError("{x: time_s, y: a, scale_y: 0}").rfind("scale_y: ", 0), 0u);
  EXPECT_EQ(SpecError("{x: time_s, y: a, scale_y: twice}").rfind("scale_y: ", 0), 0u);
  EXPECT_EQ(SpecError("{x: time_s, y: a, title: [a]}").rfind("title: ", 0), 0u);
  EXPECT_EQ(SpecError("{file: result.h5, x: time_s, y: a}").rfind("file: ", 0), 0u);
  EXPECT_EQ(SpecError("{file: [sensors.csv], x: time_s, y: a}").rfind("file: ", 0), 0u);
  EXPECT_NE(SpecError("{file: sensors.csv, y: a}").find("column of sensors.csv"),
            std::string::npos);
}

TEST(HistorySeriesTest, OneSeriesPerMemberAndColumnScaled) {
  const HistoryTable t = Parse("time_s,f [N],g [N]\n0,0,1\n1,-2,3\n");
  LinePlot plot;
  std::string error;
  ASSERT_TRUE(
      AddHistorySeries(Spec("{x: time_s, y: ['f [N]'], scale_y: -1}"), "slow", t, &plot, &error))
      << error;
  ASSERT_TRUE(
      AddHistorySeries(Spec("{x: time_s, y: ['f [N]', 'g [N]']}"), "fast", t, &plot, &error))
      << error;
  ASSERT_EQ(plot.series.size(), 3u);
  EXPECT_EQ(plot.series[0].name, "slow");
  EXPECT_EQ(plot.series[0].y, (std::vector<double>{0, 2}));
  EXPECT_EQ(plot.series[0].x, (std::vector<double>{0, 1}));
  EXPECT_EQ(plot.series[1].name, "fast: f [N]");
  EXPECT_EQ(plot.series[2].name, "fast: g [N]");
  EXPECT_EQ(plot.series[2].y, (std::vector<double>{1, 3}));
  EXPECT_EQ(plot.series[0].colour, SeriesColour(0));
  EXPECT_EQ(plot.series[2].colour, SeriesColour(2));
}

TEST(HistorySeriesTest, AMissingColumnNamesTheMemberTheColumnAndWhatIsThere) {
  const HistoryTable t = Parse("time_s,amplitude\n0,0\n");
  LinePlot plot;
  std::string error;
  EXPECT_FALSE(
      AddHistorySeries(Spec("{x: time_s, y: ['reaction top z [N]']}"), "v=2", t, &plot, &error));
  EXPECT_EQ(error,
            "member 'v=2': its history.csv has no column 'reaction top z [N]'; its columns: "
            "'time_s', 'amplitude'");
  EXPECT_TRUE(plot.series.empty());
  EXPECT_FALSE(AddHistorySeries(Spec("{x: 'travel [mm]', y: amplitude}"), "v=2", t, &plot, &error));
  EXPECT_NE(error.find("no column 'travel [mm]'"), std::string::npos) << error;
}

}  // namespace
}  // namespace pba::cli
