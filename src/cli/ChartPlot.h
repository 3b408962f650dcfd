#pragma once
// afb chart's picture: a gnuplot script and its data (cost against each of the four errors, log–log, one colour
// per figure, the Pareto front of each panel drawn, points labelled with the method), rendered headless to PNG
// and SVG by running gnuplot.
#include <filesystem>
#include <string>
#include <vector>

#include "afb/sim/Chart.h"
#include "afb/sim/TrackChart.h"

namespace afb::cli {

/// Writes `dir`/front.dat and `dir`/front.gp (which renders front.png and front.svg when gnuplot runs it in
/// `dir`). `subtitle` goes under the title. Returns an error message, or an empty string.
std::string writeChartPlot(const std::filesystem::path& dir, const std::vector<sim::ChartPoint>& points,
                           const sim::ChartOptions& options, const std::string& subtitle);

/// Writes `dir`/track.dat and `dir`/track.gp (which renders track.png and track.svg): tracking error (mm and
/// degrees) against cost, one line per figure and method through its strengths, each point labelled with its
/// strength. Returns an error message, or an empty string.
std::string writeTrackChartPlot(const std::filesystem::path& dir, const std::vector<sim::TrackChartPoint>& points,
                                const std::string& subtitle);

/// Runs `gnuplot SCRIPT` in `dir` (afb chart's front.gp, afb stress's stress.gp). Returns an error message
/// (gnuplot missing, or its exit status), or an empty string.
std::string runGnuplot(const std::filesystem::path& dir, const std::string& script = "front.gp");

} // namespace afb::cli
