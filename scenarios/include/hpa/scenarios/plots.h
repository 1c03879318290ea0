#pragma once
// PNG plots of runs, as a reader of the paper would recognise them.

#include <string>
#include <vector>

#include "hpa/models/params.h"
#include "hpa/scenarios/runner.h"

namespace hpa {

/// Writes DIR/tracking.png (payload x, y, z vs reference, slack shaded), DIR/xy_path.png (x-y
/// path coloured by payload speed) and DIR/retaut.png (quadrotor deviation and body rates,
/// re-taut instants marked). Returns the paths written.
std::vector<std::string> WriteRunPlots(const RunResult& result, const Params& params,
                                       const std::string& dir);

/// One figure comparing controllers on one scenario: payload z, quadrotor z and deviation,
/// body-rate norm, slack shaded. Writes `png`.
void WriteComparisonPlot(const std::vector<RunResult>& results, const Params& params,
                         const std::string& png);

}  // namespace hpa
