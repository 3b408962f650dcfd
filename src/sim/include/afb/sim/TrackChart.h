#pragma once
// The tracking panel of `afb chart --track` (docs/cli.md): how closely a powered figure follows an animation against
// what its steps cost, one point per method and motor strength. Tools library (src/sim), like the chart of drops.
#include <optional>
#include <string>
#include <vector>

#include "afb/decl/Md5Anim.h"
#include "afb/figure/Figure.h"
#include "afb/sim/Chart.h"
#include "afb/sim/Track.h"

namespace afb::sim {

/// What a tracking chart runs: every figure × method × strength × rate × repeat, one runTrack each.
struct TrackChartOptions {
    std::vector<ChartMethod> methods;                     ///< rigid backend, not raw (runTrack's demand)
    std::vector<double> strengths = {0.25, 0.5, 1, 2, 4}; ///< motor strengths (TrackOptions::strength), ≥ 0
    std::vector<double> hz = {60.0};                      ///< frame rates
    int repeats = 3;                                      ///< runs of each, for the cost's spread
    /// The rest of each run: seconds, root, warm-up (its hz, strength and method are the matrix's).
    TrackOptions track;
};

/// One method at one strength on one figure, over the rates.
struct TrackChartPoint {
    std::string figure; ///< the figure's name
    std::string label;  ///< the method's label
    double strength = 1;
    /// CPU µs per awake body-step (TrackResult::cpuUsPerAwakeBodyStep, weighted by the awake body-steps over the
    /// rates of one repeat): the median of the repeats and their min and max.
    double costUs = 0, costMinUs = 0, costMaxUs = 0;
    double trackingRmsMm = 0;  ///< the worst tracking_rms_m over the rates, in mm
    double trackingRmsDeg = 0; ///< the worst tracking_rms_deg over the rates
    bool exploded = false;     ///< some run exploded
};

/// Runs the matrix, one run after the other, and folds it into points: figures in order, then methods, then
/// strengths. Returns nullopt with an error in `diagnostics` when the animation does not fit a figure. Throws
/// std::invalid_argument for a raw or multibody method (runTrack).
std::optional<std::vector<TrackChartPoint>> runTrackChart(const std::vector<figure::Figure>& figures,
                                                          const decl::Md5Anim& anim, const TrackChartOptions& options,
                                                          text::Diagnostics& diagnostics);

/// track.md: the setup and one table per figure (method, strength, cost, tracking errors).
std::string trackChartMarkdown(const std::vector<TrackChartPoint>& points, const TrackChartOptions& options);

} // namespace afb::sim
