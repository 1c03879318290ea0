#pragma once
// Plots of runs, as a reader of the paper would recognise them: PNG, SVG or PDF, each with the
// CSV of what it draws.

#include <string>
#include <vector>

#include "hpa/models/params.h"
#include "hpa/scenarios/plot_canvas.h"
#include "hpa/scenarios/runner.h"

namespace hpa {

/// Writes DIR/tracking.png (payload x, y, z vs reference, slack shaded), DIR/xy_path.png (x-y
/// path coloured by payload speed) and DIR/retaut.png (quadrotor deviation and body rates,
/// re-taut instants marked), in `format`, each with its CSV. Returns the plots' paths.
std::vector<std::string> WriteRunPlots(const RunResult& result, const Params& params,
                                       const std::string& dir,
                                       PlotFormat format = PlotFormat::kPng);

/// The stems WriteRunPlots writes under DIR ("tracking", "xy_path", "retaut").
const std::vector<std::string>& RunPlotStems();

/// One figure comparing controllers on one scenario: payload z, quadrotor z and deviation,
/// body-rate norm, slack shaded. Writes STEM.png|svg|pdf and STEM.csv; returns the plot's path.
/// `labels` name the runs in the legend (default: each run's metrics' controller).
std::string WriteComparisonPlot(const std::vector<RunResult>& results, const Params& params,
                                const std::string& stem, PlotFormat format = PlotFormat::kPng,
                                const std::vector<std::string>& labels = {});

}  // namespace hpa
