// A figure written to its files (Figure::Write): the raster as PNG, or its vector primitives
// replayed on a cairo surface as SVG or PDF, then the CSV of every series it draws and the CSV of
// what it shades.

#include <cairo-pdf.h>
#include <cairo-svg.h>
#include <cairo.h>

#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "hpa/models/file_io.h"
#include "hpa/models/input_error.h"
#include "hpa/scenarios/plot_canvas.h"
#include "media.h"

namespace hpa {
namespace {

// Sets cairo's source colour to a BGR colour with an opacity.
void SetColour(cairo_t* cr, const cv::Scalar& bgr, double alpha = 1.0) {
  cairo_set_source_rgba(cr, bgr[2] / 255.0, bgr[1] / 255.0, bgr[0] / 255.0, alpha);
}

// Replays a figure's primitives on a cairo surface of the figure's size.
void Replay(const Figure& f, cairo_t* cr) {
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  for (const auto& [kind, i] : f.order) {
    cairo_save(cr);
    if (kind == 0) {
      const Figure::Stroke& s = f.strokes[i];
      if (s.clip.area() > 0) {
        cairo_rectangle(cr, s.clip.x, s.clip.y, s.clip.width, s.clip.height);
        cairo_clip(cr);
      }
      const double dashes[2][2] = {{12.0, 8.0}, {2.0, 5.0}};
      if (s.dash > 0) cairo_set_dash(cr, dashes[s.dash - 1], 2, 0.0);
      cairo_set_line_width(cr, s.width_px);
      SetColour(cr, s.colour);
      bool pen_down = false;
      for (const cv::Point2d& p : s.points) {
        if (!std::isfinite(p.x) || !std::isfinite(p.y)) {
          pen_down = false;  // a gap in the data breaks the line
          continue;
        }
        if (pen_down) {
          cairo_line_to(cr, p.x, p.y);
        } else {
          cairo_move_to(cr, p.x, p.y);
        }
        pen_down = true;
      }
      cairo_stroke(cr);
    } else if (kind == 1) {
      const Figure::Fill& r = f.fills[i];
      SetColour(cr, r.colour, r.alpha);
      if (r.radius_px > 0) {
        cairo_arc(cr, r.rect.x + r.rect.width / 2, r.rect.y + r.rect.height / 2, r.radius_px, 0,
                  2 * M_PI);
      } else {
        cairo_rectangle(cr, r.rect.x, r.rect.y, r.rect.width, r.rect.height);
      }
      cairo_fill(cr);
    } else {
      const Figure::Text& t = f.texts[i];
      cairo_set_source_rgb(cr, 0, 0, 0);
      cairo_set_font_size(cr, t.size_px);
      cairo_move_to(cr, t.at.x, t.at.y);
      cairo_show_text(cr, t.text.c_str());
    }
    cairo_restore(cr);
  }
}

// A text as one CSV field: quoted, its quotes doubled, when it holds a comma, quote or newline.
std::string CsvText(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

// v[i] as a CSV field: 10 significant digits, empty when missing or not finite.
std::string CsvNumber(const std::vector<double>& v, size_t i) {
  if (i >= v.size() || !std::isfinite(v[i])) return "";
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.10g", v[i]);
  return buf;
}

}  // namespace

std::string Figure::Write(const std::string& stem, PlotFormat format) const {
  const std::string path = stem + "." + PlotExtension(format);
  if (format == PlotFormat::kPng) {
    if (!WriteImage(path, image_)) throw OutputError(path, "the PNG could not be written");
  } else {
    cairo_surface_t* surface =
        format == PlotFormat::kSvg
            ? cairo_svg_surface_create(PartialPath(path).c_str(), image_.cols, image_.rows)
            : cairo_pdf_surface_create(PartialPath(path).c_str(), image_.cols, image_.rows);
    cairo_t* cr = cairo_create(surface);
    Replay(*this, cr);
    cairo_destroy(cr);
    cairo_surface_finish(surface);
    const cairo_status_t status = cairo_surface_status(surface);
    cairo_surface_destroy(surface);
    if (status != CAIRO_STATUS_SUCCESS) {
      std::remove(PartialPath(path).c_str());
      throw OutputError(path, std::string("cairo: ") + cairo_status_to_string(status));
    }
    CommitPartial(path);
  }
  // the data, one row per point of every series, long format
  const std::string csv = stem + ".csv";
  std::ostringstream out;
  out << "panel,series,x_label,y_label,x,y,low,high,value\n";
  for (size_t k = 0; k < series.size(); ++k) {
    const Series& s = series[k];
    // an unnamed series takes the name of a named one of its colour (a legend in another
    // panel), else "series K"
    std::string name = s.name;
    for (const Series& other : series) {
      if (name.empty() && !other.name.empty() && other.colour == s.colour &&
          other.dotted == s.dotted) {
        name = other.name;
      }
    }
    if (name.empty()) name = "series " + std::to_string(k) + (s.dotted ? " (dotted)" : "");
    const std::string head = CsvText(s.panel) + "," + CsvText(name) + "," + CsvText(s.x_label) +
                             "," + CsvText(s.y_label) + ",";
    for (size_t i = 0; i < s.x.size(); ++i) {
      out << head << CsvNumber(s.x, i) << "," << CsvNumber(s.y, i) << "," << CsvNumber(s.low, i)
          << "," << CsvNumber(s.high, i) << "," << CsvNumber(s.value, i) << "\n";
    }
  }
  WriteFileAtomic(csv, out.str());
  // what the plot shades (slack intervals, re-taut marks), so a redraw shades the same spans
  // without deriving them again; no shade: no file (an older one removed)
  const std::string shading_csv = stem + ".shading.csv";
  if (shades.empty()) {
    std::remove(shading_csv.c_str());
  } else {
    std::ostringstream shading;
    shading << "panel,label,x0,x1,r,g,b\n";
    for (const Shade& sh : shades) {
      // cv::Scalar is BGR; the CSV gives RGB in 0-255
      shading << CsvText(sh.panel) << "," << CsvText(sh.label) << "," << CsvNumber({sh.x0}, 0)
              << "," << CsvNumber({sh.x1}, 0) << "," << sh.colour[2] << "," << sh.colour[1] << ","
              << sh.colour[0] << "\n";
    }
    WriteFileAtomic(shading_csv, shading.str());
  }
  return path;
}

}  // namespace hpa
