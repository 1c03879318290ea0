#include "hpa/scenarios/plots.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>

#include "hpa/models/cooperative_model.h"
#include "hpa/models/input_error.h"
#include "hpa/scenarios/plot_canvas.h"

namespace hpa {
// The run plots' file stems (RunPlotStems lists them for the tools that clear old outputs).
constexpr const char* kTrackingStem = "tracking";
constexpr const char* kXyPathStem = "xy_path";
constexpr const char* kRetautStem = "retaut";
constexpr const char* kTeamCablesStem = "team_cables";

namespace {

const cv::Scalar kSlackShade(0, 165, 255);  // orange (BGR)
const cv::Scalar kReference(90, 90, 90);

// A column of a log (a single vehicle's or a team's rows) as a vector.
template <typename Row, typename F>
std::vector<double> Column(const std::vector<Row>& rows, F f) {
  std::vector<double> out;
  out.reserve(rows.size());
  for (const Row& r : rows) out.push_back(f(r));
  return out;
}

void ShadeSlack(PlotPanel* panel, const std::vector<LogRow>& rows) {
  for (const auto& [a, b] : TrueSlackIntervals(rows)) panel->ShadeX(a, b, kSlackShade, "slack");
}

// Slack shading plus a red mark at each re-taut instant (the end of a slack interval).
void ShadeSlackMarkRetaut(PlotPanel* panel, const std::vector<LogRow>& rows) {
  ShadeSlack(panel, rows);
  const double span_s = rows.back().time_s - rows.front().time_s;
  for (const auto& [a, b] : TrueSlackIntervals(rows)) {
    if (b < rows.back().time_s) {
      panel->ShadeX(b, b + 0.004 * span_s, cv::Scalar(0, 0, 220), "re-taut");
    }
  }
}

// Payload x, y and z against the reference with the estimate, slack shaded: how well the
// payload tracked, and where the cable was slack.
std::string WriteTrackingPlot(const std::vector<LogRow>& rows, const std::vector<double>& t,
                              const std::string& title_suffix, const std::string& dir,
                              PlotFormat format) {
  Figure fig(1200, 900);
  static const char* kAxis[3] = {"x", "y", "z"};
  for (int i = 0; i < 3; ++i) {
    PlotPanel p(&fig, cv::Rect(0, i * 300, 1200, 300),
                std::string("payload ") + kAxis[i] + (i == 0 ? title_suffix : ""), "t [s]",
                std::string(kAxis[i]) + "_L [m]");
    const auto actual = Column(rows, [i](const LogRow& r) { return r.truth.p_WL_W(i); });
    const auto estimate = Column(rows, [i](const LogRow& r) { return r.estimate.p_WL_W(i); });
    const auto ref = Column(rows, [i](const LogRow& r) { return r.reference.p_WL_W(i); });
    p.FitRange({t}, {actual, ref});
    ShadeSlack(&p, rows);
    p.DrawAxes();
    p.Line(t, ref, kReference, 2, true);
    p.Line(t, estimate, SeriesColour(1), 1);
    p.Line(t, actual, SeriesColour(0), 2);
    if (i == 0) {
      p.Legend({{"true", SeriesColour(0)},
                {"estimate", SeriesColour(1)},
                {"reference", kReference},
                {"slack (shaded)", kSlackShade}});
    }
  }
  return fig.Write(dir + "/" + kTrackingStem, format);
}

// The payload's x-y path coloured by its speed over the reference path, on equal axis scales
// so the path's shape is not distorted.
std::string WriteXyPathPlot(const RunResult& result, const std::string& title_suffix,
                            const std::string& dir, PlotFormat format) {
  const auto& rows = result.rows;
  Figure fig(900, 800);
  PlotPanel p(&fig, cv::Rect(0, 0, 900, 800), "payload x-y path" + title_suffix, "x [m]", "y [m]");
  const auto x = Column(rows, [](const LogRow& r) { return r.truth.p_WL_W.x(); });
  const auto y = Column(rows, [](const LogRow& r) { return r.truth.p_WL_W.y(); });
  const auto xr = Column(rows, [](const LogRow& r) { return r.reference.p_WL_W.x(); });
  const auto yr = Column(rows, [](const LogRow& r) { return r.reference.p_WL_W.y(); });
  const auto speed = Column(rows, [](const LogRow& r) { return r.truth.v_WL_W.norm(); });
  // equal scales on both axes
  double x0 = 1e9, x1 = -1e9, y0 = 1e9, y1 = -1e9;
  for (size_t i = 0; i < x.size(); ++i) {
    x0 = std::min({x0, x[i], xr[i]}), x1 = std::max({x1, x[i], xr[i]});
    y0 = std::min({y0, y[i], yr[i]}), y1 = std::max({y1, y[i], yr[i]});
  }
  const double half = 0.55 * std::max({x1 - x0, y1 - y0, 0.2});
  const double cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
  p.SetRange(cx - half * 1.1, cx + half * 1.1, cy - half, cy + half);
  p.DrawAxes();
  p.Line(xr, yr, kReference, 1, true);
  const double v_max = std::max(1e-3, result.metrics.payload_max_speed_mps);
  p.ColouredPath(x, y, speed, 0.0, v_max);
  p.ColourBar(0.0, v_max, "|v_L| m/s");
  return fig.Write(dir + "/" + kXyPathStem, format);
}

// Quadrotor deviation, vertical velocity and body rates with slack shaded and each re-taut
// marked: what the vehicle went through when the cable snapped taut.
std::string WriteRetautPlot(const std::vector<LogRow>& rows, const std::vector<double>& t,
                            const std::string& title_suffix, const std::string& dir,
                            PlotFormat format) {
  Figure fig(1200, 900);
  const auto dev =
      Column(rows, [](const LogRow& r) { return (r.truth.p_WQ_W - r.reference.p_WQ_W).norm(); });
  const auto vz = Column(rows, [](const LogRow& r) { return r.truth.v_WQ_W.z(); });
  PlotPanel p0(&fig, cv::Rect(0, 0, 1200, 300),
               "quadrotor deviation |p_Q - p_Q,ref|" + title_suffix, "t [s]", "[m]");
  p0.FitRange({t}, {dev});
  ShadeSlackMarkRetaut(&p0, rows);
  p0.DrawAxes();
  p0.Line(t, dev, SeriesColour(0));
  PlotPanel p1(&fig, cv::Rect(0, 300, 1200, 300), "quadrotor vertical velocity", "t [s]",
               "v_z [m/s]");
  p1.FitRange({t}, {vz});
  ShadeSlackMarkRetaut(&p1, rows);
  p1.DrawAxes();
  p1.Line(t, vz, SeriesColour(0));
  PlotPanel p2(&fig, cv::Rect(0, 600, 1200, 300), "body rates", "t [s]", "[rad/s]");
  std::vector<std::vector<double>> rates;
  for (int i = 0; i < 3; ++i) {
    rates.push_back(Column(rows, [i](const LogRow& r) { return r.truth.w_B(i); }));
  }
  p2.FitRange({t}, rates);
  ShadeSlackMarkRetaut(&p2, rows);
  p2.DrawAxes();
  for (int i = 0; i < 3; ++i) p2.Line(t, rates[i], SeriesColour(i));
  p2.Legend({{"w_x", SeriesColour(0)},
             {"w_y", SeriesColour(1)},
             {"w_z", SeriesColour(2)},
             {"re-taut", cv::Scalar(0, 0, 220)}});
  return fig.Write(dir + "/" + kRetautStem, format);
}

// The legend entry of one run of a comparison: its label (the controller's name unless given),
// marked when it crashed.
std::pair<std::string, cv::Scalar> RunLegend(const std::vector<RunResult>& results,
                                             const std::vector<std::string>& labels, size_t i) {
  const Metrics& m = results[i].metrics;
  const std::string& label = i < labels.size() ? labels[i] : m.controller;
  return {label + (m.crashed ? " (CRASHED)" : ""), SeriesColour(static_cast<int>(i))};
}

// A vehicle's tilt (deg) in a team's log row.
double VehicleTiltDeg(const TeamLogRow& row, int vehicle) {
  return TiltDeg(row.x_true.segment<4>(CooperativeStateIndex::Vehicle(vehicle) +
                                       CooperativeStateIndex::kVehicleQuat));
}

// A team's payload x, y and z against the reference, the time any cable was slack shaded.
std::string WriteTeamTrackingPlot(const std::vector<TeamLogRow>& rows, const std::vector<double>& t,
                                  const std::string& title_suffix, const std::string& dir,
                                  PlotFormat format) {
  Figure fig(1200, 900);
  static const char* kAxis[3] = {"x", "y", "z"};
  std::vector<CableMode> any_slack;
  for (const TeamLogRow& r : rows) {
    bool slack = false;
    for (const TeamLogRow::Vehicle& v : r.vehicles) slack = slack || v.mode == CableMode::kSlack;
    any_slack.push_back(slack ? CableMode::kSlack : CableMode::kTaut);
  }
  for (int i = 0; i < 3; ++i) {
    PlotPanel p(&fig, cv::Rect(0, i * 300, 1200, 300),
                std::string("payload ") + kAxis[i] + (i == 0 ? title_suffix : ""), "t [s]",
                std::string(kAxis[i]) + "_L [m]");
    const auto actual = Column(rows, [i](const TeamLogRow& r) {
      return r.x_true(CooperativeStateIndex::kPayloadPos + i);
    });
    const auto ref = Column(rows, [i](const TeamLogRow& r) { return r.reference.p_WL_W(i); });
    p.FitRange({t}, {actual, ref});
    for (const auto& [a, b] : SlackIntervals(t, any_slack)) {
      p.ShadeX(a, b, kSlackShade, "a cable slack");
    }
    p.DrawAxes();
    p.Line(t, ref, kReference, 2, true);
    p.Line(t, actual, SeriesColour(0), 2);
    if (i == 0) {
      p.Legend({{"true", SeriesColour(0)},
                {"reference", kReference},
                {"a cable slack (shaded)", kSlackShade}});
    }
  }
  return fig.Write(dir + "/" + kTrackingStem, format);
}

// Each vehicle's cable tension and tilt: how the team shares the load, and which cable went
// slack when.
std::string WriteTeamCablesPlot(const std::vector<TeamLogRow>& rows, const std::vector<double>& t,
                                const std::string& title_suffix, const std::string& dir,
                                PlotFormat format) {
  Figure fig(1200, 600);
  const int n = static_cast<int>(rows.front().vehicles.size());
  PlotPanel p0(&fig, cv::Rect(0, 0, 1200, 300), "cable tension" + title_suffix, "t [s]", "[N]");
  PlotPanel p1(&fig, cv::Rect(0, 300, 1200, 300), "vehicle tilt", "t [s]", "[deg]");
  std::vector<std::vector<double>> tension, tilt;
  for (int i = 0; i < n; ++i) {
    tension.push_back(Column(rows, [i](const TeamLogRow& r) {
      return r.vehicles[static_cast<size_t>(i)].cable_tension_N;
    }));
    tilt.push_back(Column(rows, [i](const TeamLogRow& r) { return VehicleTiltDeg(r, i); }));
  }
  p0.FitRange({t}, tension);
  p0.DrawAxes();
  p1.FitRange({t}, tilt);
  p1.DrawAxes();
  std::vector<std::pair<std::string, cv::Scalar>> legend;
  for (int i = 0; i < n; ++i) {
    p0.Line(t, tension[static_cast<size_t>(i)], SeriesColour(i), 2);
    p1.Line(t, tilt[static_cast<size_t>(i)], SeriesColour(i), 2);
    legend.emplace_back("vehicle " + std::to_string(i), SeriesColour(i));
  }
  p0.Legend(legend);
  return fig.Write(dir + "/" + kTeamCablesStem, format);
}

}  // namespace

const std::vector<std::string>& RunPlotStems() {
  static const std::vector<std::string> stems{kTrackingStem, kXyPathStem, kRetautStem,
                                              kTeamCablesStem};
  return stems;
}

std::vector<std::string> WriteRunPlots(const RunResult& result, const Params& params,
                                       const std::string& dir, PlotFormat format) {
  const auto& rows = result.rows;
  std::vector<std::string> written;
  if (!result.team_rows.empty()) {
    const auto t = Column(result.team_rows, [](const TeamLogRow& r) { return r.time_s; });
    const std::string title_suffix =
        " - " + result.metrics.scenario + " (" + result.metrics.controller + ")";
    written.push_back(WriteTeamTrackingPlot(result.team_rows, t, title_suffix, dir, format));
    written.push_back(WriteTeamCablesPlot(result.team_rows, t, title_suffix, dir, format));
    return written;
  }
  if (rows.empty()) return written;
  const auto t = Column(rows, [](const LogRow& r) { return r.time_s; });
  const std::string title_suffix =
      " - " + result.metrics.scenario + " (" + result.metrics.controller + ")";
  written.push_back(WriteTrackingPlot(rows, t, title_suffix, dir, format));
  written.push_back(WriteXyPathPlot(result, title_suffix, dir, format));
  written.push_back(WriteRetautPlot(rows, t, title_suffix, dir, format));
  return written;
}

namespace {

// A team comparison: each run's payload x, y and z against the reference (dotted) and its worst
// vehicle's tilt, one colour per run.
std::string WriteTeamComparisonPlot(const std::vector<RunResult>& results, const std::string& stem,
                                    PlotFormat format, const std::vector<std::string>& labels) {
  Figure fig(1400, 1000);
  const std::string name = results.front().metrics.scenario;
  static const char* kTitles[4] = {"payload x (dotted: reference)", "payload y (dotted: reference)",
                                   "payload z (dotted: reference)", "largest vehicle tilt"};
  static const char* kUnits[4] = {"x_L [m]", "y_L [m]", "z_L [m]", "[deg]"};
  for (int k = 0; k < 4; ++k) {
    PlotPanel p(&fig, cv::Rect(0, k * 250, 1400, 250),
                std::string(kTitles[k]) + (k == 0 ? " - " + name : ""), "t [s]", kUnits[k]);
    std::vector<std::vector<double>> ts, ys;
    for (const RunResult& r : results) {
      ts.push_back(Column(r.team_rows, [](const TeamLogRow& row) { return row.time_s; }));
      ys.push_back(Column(r.team_rows, [k](const TeamLogRow& row) {
        if (k < 3) return row.x_true(CooperativeStateIndex::kPayloadPos + k);
        double tilt_deg = 0.0;
        for (size_t i = 0; i < row.vehicles.size(); ++i) {
          tilt_deg = std::max(tilt_deg, VehicleTiltDeg(row, static_cast<int>(i)));
        }
        return tilt_deg;
      }));
    }
    p.FitRange(ts, ys);
    p.DrawAxes();
    std::vector<std::pair<std::string, cv::Scalar>> legend;
    for (size_t i = 0; i < results.size(); ++i) {
      if (k < 3) {
        const auto ref = Column(results[i].team_rows,
                                [k](const TeamLogRow& r) { return r.reference.p_WL_W(k); });
        p.Line(ts[i], ref, SeriesColour(static_cast<int>(i)), 1, true);
      }
      p.Line(ts[i], ys[i], SeriesColour(static_cast<int>(i)), 2);
      legend.push_back(RunLegend(results, labels, i));
    }
    p.Legend(legend);
  }
  return fig.Write(stem, format);
}

}  // namespace

std::string WriteComparisonPlot(const std::vector<RunResult>& results, const Params& params,
                                const std::string& stem, PlotFormat format,
                                const std::vector<std::string>& labels) {
  if (!results.empty() && results.front().metrics.team) {
    return WriteTeamComparisonPlot(results, stem, format, labels);
  }
  Figure fig(1400, 1000);
  const std::string name = results.empty() ? "" : results.front().metrics.scenario;
  struct Panel {
    const char* title;
    const char* unit;
    double (*value)(const LogRow&);
  };
  const Panel panels[4] = {
      {"payload z (dotted: reference)", "z_L [m]",
       [](const LogRow& r) { return r.truth.p_WL_W.z(); }},
      {"quadrotor z (dotted: reference)", "z_Q [m]",
       [](const LogRow& r) { return r.truth.p_WQ_W.z(); }},
      {"quadrotor deviation |p_Q - p_Q,ref|", "[m]",
       [](const LogRow& r) { return (r.truth.p_WQ_W - r.reference.p_WQ_W).norm(); }},
      {"body-rate norm", "|w_B| [rad/s]", [](const LogRow& r) { return r.truth.w_B.norm(); }}};
  for (int k = 0; k < 4; ++k) {
    PlotPanel p(&fig, cv::Rect(0, k * 250, 1400, 250),
                std::string(panels[k].title) + (k == 0 ? " - " + name : ""), "t [s]",
                panels[k].unit);
    std::vector<std::vector<double>> ts, ys;
    for (const RunResult& r : results) {
      ts.push_back(Column(r.rows, [](const LogRow& row) { return row.time_s; }));
      ys.push_back(Column(r.rows, panels[k].value));
    }
    p.FitRange(ts, ys);
    // slack shading from the first run (its colour is the first series')
    for (size_t i = 0; i < results.size(); ++i) {
      for (const auto& [a, b] : TrueSlackIntervals(results[i].rows)) {
        p.ShadeX(a, b, i == 0 ? cv::Scalar(0, 200, 255) : cv::Scalar(255, 200, 150),
                 "slack, " + (i < labels.size() ? labels[i] : results[i].metrics.controller));
      }
    }
    p.DrawAxes();
    std::vector<std::pair<std::string, cv::Scalar>> legend;
    for (size_t i = 0; i < results.size(); ++i) {
      if (k <= 1) {
        const auto ref = Column(results[i].rows, [k](const LogRow& r) {
          return k == 0 ? r.reference.p_WL_W.z() : r.reference.p_WQ_W.z();
        });
        p.Line(ts[i], ref, SeriesColour(static_cast<int>(i)), 1, true);
      }
      p.Line(ts[i], ys[i], SeriesColour(static_cast<int>(i)), 2);
      legend.push_back(RunLegend(results, labels, i));
    }
    if (k == 0) legend.emplace_back("slack (shaded per run)", cv::Scalar(0, 200, 255));
    p.Legend(legend);
  }
  return fig.Write(stem, format);
}

}  // namespace hpa
