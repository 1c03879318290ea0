// Figure and PlotPanel: the plot formats by name, PNG/SVG/PDF files written with their data CSV,
// the drawn line in the raster and the vector file, and unwritable paths refused.

#include "hpa/scenarios/plot_canvas.h"

#include <gtest/gtest.h>

#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "hpa/models/input_error.h"
#include "models/tests/temp_dir.h"

namespace hpa {
namespace {

std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

int Count(const std::string& text, const std::string& what) {
  int n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

const cv::Scalar kRed(0, 0, 255);  // BGR: a colour neither the axes nor the grid use

// A 400 x 300 figure with one panel, and (if `with_line`) a red parabola named "speed".
Figure MakeFigure(bool with_line) {
  Figure figure(400, 300);
  PlotPanel panel(&figure, cv::Rect(0, 0, 400, 300), "Speed", "t [s]", "v [m/s]");
  panel.SetRange(0.0, 2.0, 0.0, 4.0);
  panel.DrawAxes();
  if (with_line) {
    panel.Line({0.0, 1.0, 2.0}, {0.0, 1.0, 4.0}, kRed, 3);
    panel.Legend({{"speed", kRed}});
  }
  return figure;
}

// Pixels within 40 grey levels (per channel) of pure red: anti-aliasing blends a line's edges,
// its centre stays near the colour.
int RedPixels(const cv::Mat& bgr) {
  cv::Mat mask;
  cv::inRange(bgr, cv::Scalar(0, 0, 215), cv::Scalar(40, 40, 255), mask);
  return cv::countNonZero(mask);
}

TEST(PlotCanvasTest, FormatsByNameAndExtension) {
  for (const char* name : {"png", "svg", "pdf"}) {
    EXPECT_STREQ(PlotExtension(ParsePlotFormat(name)), name);
  }
  EXPECT_NE(ParsePlotFormat("png"), ParsePlotFormat("svg"));
  EXPECT_NE(ParsePlotFormat("svg"), ParsePlotFormat("pdf"));
}

TEST(PlotCanvasTest, UnknownFormatIsRefusedNamingTheOption) {
  try {
    ParsePlotFormat("jpg", "--compare-format");
    FAIL() << "jpg was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "--compare-format");
    EXPECT_NE(std::string(e.what()).find("jpg"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ParsePlotFormat("PNG"), InputError);  // names are lower case
}

TEST(PlotCanvasTest, EachFormatWritesANonEmptyFileOfThatKind) {
  const Figure figure = MakeFigure(true);
  const std::string stem = TestTempDir() + "plot";
  // each format's signature at the start of its file
  const std::vector<std::pair<PlotFormat, std::string>> formats = {
      {PlotFormat::kPng, "\x89PNG"}, {PlotFormat::kSvg, "<?xml"}, {PlotFormat::kPdf, "%PDF"}};
  for (const auto& [format, magic] : formats) {
    const std::string path = figure.Write(stem, format);
    EXPECT_EQ(path, stem + "." + PlotExtension(format));
    const std::string bytes = ReadAll(path);
    ASSERT_GT(bytes.size(), magic.size()) << path;
    EXPECT_EQ(bytes.compare(0, magic.size(), magic), 0) << path;
  }
  EXPECT_NE(ReadAll(stem + ".svg").find("<svg"), std::string::npos);
}

TEST(PlotCanvasTest, PngHoldsTheLineInItsColour) {
  const std::string dir = TestTempDir();
  const cv::Mat with = cv::imread(MakeFigure(true).Write(dir + "with", PlotFormat::kPng));
  const cv::Mat without = cv::imread(MakeFigure(false).Write(dir + "without", PlotFormat::kPng));
  ASSERT_EQ(with.cols, 400);
  ASSERT_EQ(with.rows, 300);
  EXPECT_EQ(RedPixels(without), 0);
  // a 3 px line across most of a ~300 px plot: hundreds of pixels; 100 is a floor that a
  // missing or clipped-away line cannot reach
  EXPECT_GT(RedPixels(with), 100);
}

// The d attributes of the SVG's paths stroked in pure red (cairo writes the colour in percent).
std::vector<std::string> RedPaths(const std::string& svg) {
  std::vector<std::string> d;
  for (size_t at = svg.find("<path"); at != std::string::npos; at = svg.find("<path", at + 1)) {
    const std::string element = svg.substr(at, svg.find('>', at) - at);
    if (element.find("rgb(100%,0%,0%)") == std::string::npos) continue;
    const size_t from = element.find(" d=\"") + 4;
    d.push_back(element.substr(from, element.find('"', from) - from));
  }
  return d;
}

TEST(PlotCanvasTest, SvgHoldsTheLineAsAVectorPath) {
  const std::string dir = TestTempDir();
  const std::string with = ReadAll(MakeFigure(true).Write(dir + "with", PlotFormat::kSvg));
  const std::string without = ReadAll(MakeFigure(false).Write(dir + "without", PlotFormat::kSvg));
  EXPECT_TRUE(RedPaths(without).empty());
  // the three-point line (a move and two line segments) and the legend's two-point sample
  const std::vector<std::string> red = RedPaths(with);
  ASSERT_EQ(red.size(), 2u) << with;
  EXPECT_EQ(Count(red[0], "M"), 1) << red[0];
  EXPECT_EQ(Count(red[0], "L"), 2) << red[0];
  EXPECT_EQ(Count(red[1], "L"), 1) << red[1];
}

TEST(PlotCanvasTest, CsvHoldsEveryPointOfTheSeriesUnderItsLegendName) {
  const std::string stem = TestTempDir() + "plot";
  MakeFigure(true).Write(stem, PlotFormat::kPng);
  EXPECT_EQ(ReadAll(stem + ".csv"),
            "panel,series,x_label,y_label,x,y,low,high,value\n"
            "Speed,speed,t [s],v [m/s],0,0,,,\n"
            "Speed,speed,t [s],v [m/s],1,1,,,\n"
            "Speed,speed,t [s],v [m/s],2,4,,,\n");
  // no series drawn: the header only
  MakeFigure(false).Write(stem, PlotFormat::kPng);
  EXPECT_EQ(ReadAll(stem + ".csv"), "panel,series,x_label,y_label,x,y,low,high,value\n");
}

TEST(PlotCanvasTest, UnwritablePathIsAnOutputError) {
  const std::string stem = TestTempDir() + "no_such_folder/plot";
  const Figure figure = MakeFigure(true);
  for (PlotFormat format : {PlotFormat::kPng, PlotFormat::kSvg, PlotFormat::kPdf}) {
    EXPECT_THROW(figure.Write(stem, format), OutputError) << PlotExtension(format);
  }
}

}  // namespace
}  // namespace hpa
