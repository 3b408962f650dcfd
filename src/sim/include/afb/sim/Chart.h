#pragma once
// Speed against accuracy (`afb chart`): a matrix of drops, methods × figures × scenarios × repeats, spread over
// worker threads, folded into one point per method and figure, and the methods worth choosing: the Pareto front
// and the cheapest method within given error bounds.
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "afb/bullet/Method.h"
#include "afb/figure/Figure.h"
#include "afb/sim/Drop.h"

namespace afb::sim {

/// One method of a chart: how it was asked for and what it is.
struct ChartMethod {
    std::string label; ///< as given: "default", "raw", "default:substeps=2:iterations=10"
    bullet::Method method;
};

/// Parses "NAME[:knob=value]...": a preset or "raw" (methodByName), then each knob override in order (as the
/// CLI's --knob flags). Returns nullopt with `error` set on an unknown name or knob, a bad value, or a raw method
/// asking for afbullet's techniques.
std::optional<ChartMethod> parseChartMethod(std::string_view spec, std::string& error);

/// What a chart runs.
struct ChartOptions {
    std::vector<ChartMethod> methods;           ///< labels unique: they name the points
    std::vector<double> heightsM = {1.0, 10.0}; ///< drop heights (scenarios), metres
    std::vector<double> hz = {60.0};            ///< frame rates (scenarios)
    int repeats = 3;                            ///< runs of each (method, figure, scenario), for the cost's spread
    int count = 1;                              ///< instances per run (yaw 37°·i, one world)
    double seconds = 10.0;                      ///< simulated time per run
    bool sleeping = true;                       ///< the rest rules put figures to sleep (settle time needs it)
    int threads = 2;                            ///< worker threads; each run owns its world
};

/// One run of the matrix.
struct ChartRun {
    std::string label;      ///< ChartMethod::label
    std::size_t figure = 0; ///< index into the figures charted
    double heightM = 0, hz = 0;
    int repeat = 0;
    DropResult result;
};

/// The runs of the matrix, results empty: for each of `figures` figures, method, height, rate and repeat, in that
/// nesting order (runChart's order).
std::vector<ChartRun> chartRuns(std::size_t figures, const ChartOptions& options);
/// The drop of one run of the matrix, with `method` (the run's ChartMethod's).
DropOptions chartDropOptions(const ChartOptions& options, const ChartRun& run, const bullet::Method& method);

/// Runs the whole matrix: for each figure, method, height, rate and repeat (in that nesting order, which is the
/// order of the result) one drop. Runs are spread over `options.threads` threads, repeat by repeat (all first
/// repeats, then all second ones: load on the machine falls on every method alike); every run owns its world,
/// so every result but the timings is the same for any thread count. `progress(done, total)` is called from the
/// calling thread now and then while runs finish, and once at the end.
std::vector<ChartRun> runChart(const std::vector<figure::Figure>& figures, const ChartOptions& options,
                               const std::function<void(int done, int total)>& progress = {});

/// The four error measures a chart plots, each against the cost.
enum class ChartMetric { Anchor, Limit, Penetration, Settle };
inline constexpr ChartMetric kChartMetrics[] = {ChartMetric::Anchor, ChartMetric::Limit, ChartMetric::Penetration,
                                                ChartMetric::Settle};

/// One method on one figure over every scenario of the chart.
struct ChartPoint {
    std::string figure; ///< the figure's name
    std::string label;  ///< the method's label
    /// Cost: CPU microseconds per awake body-step (thread CPU time of the steps with a body awake / awake
    /// body-steps, summed over the scenarios of one repeat), the median of the repeats and their min and max; 0
    /// when no body was ever awake (nothing to charge).
    double costUs = 0, costMinUs = 0, costMaxUs = 0;
    double anchorM = 0;            ///< worst max_anchor_error_m over the scenarios
    double limitDeg = 0;           ///< worst max_limit_violation_deg
    double penetrationM = 0;       ///< worst max_penetration_m
    std::optional<double> settleS; ///< worst settle_time_s; nullopt when some run never came to rest
    bool exploded = false;         ///< some run exploded
    bool operator==(const ChartPoint&) const = default;
};

/// One point per (figure, method), figures in order, methods in the order charted.
std::vector<ChartPoint> chartPoints(const std::vector<ChartRun>& runs, const std::vector<std::string>& figureNames,
                                    const std::vector<ChartMethod>& methods);

/// A point's value of `metric` in the units charted: anchor and penetration in mm, limit in degrees, settle in
/// seconds (+∞ when it never came to rest).
double metricValue(const ChartPoint& p, ChartMetric metric);
/// "max anchor error, mm" and the like.
std::string_view metricTitle(ChartMetric metric);

/// The indices of the points no other point dominates, minimising every objective: point i is dominated when
/// some j is no worse in every objective and better in one. `objectives[i]` holds point i's values (all of the
/// same length). Ties (equal in everything) are all kept. Ascending order.
std::vector<std::size_t> paretoFront(const std::vector<std::vector<double>>& objectives);

/// The front of `points` (one figure's) in cost and the given metrics, among the points that did not explode and
/// have a cost (an exploded method is no choice; one never awake has no cost to compare). Ascending order.
std::vector<std::size_t> chartFront(const std::vector<ChartPoint>& points, const std::vector<ChartMetric>& metrics);

/// Upper bounds on a method's errors; unset bounds do not constrain.
struct ChartBounds {
    std::optional<double> anchorM, limitDeg, penetrationM, settleS;
    bool any() const { return anchorM || limitDeg || penetrationM || settleS; }
    /// The bounds a summary recommends within when none are given: joints open at most 10 mm, limits overshot at
    /// most 5°, contacts at most 20 mm deep (what a game shows without visible artefacts on a human-sized figure).
    static ChartBounds defaults() { return {0.010, 5.0, 0.020, std::nullopt}; }
};

/// The index of the cheapest point (lowest median cost) of `points` that has a cost, did not explode and meets every
/// bound (a settle bound also demands that it came to rest), or nullopt when none does. Ties go to the first.
std::optional<std::size_t> cheapestWithin(const std::vector<ChartPoint>& points, const ChartBounds& bounds);

/// The CSV of every run: method_label, height_m, hz, repeat, then every drop field and knob (dropCsvHeader).
std::string chartRunsCsv(const std::vector<ChartRun>& runs);

/// summary.md: the setup, then per figure a table of every method (members of the all-errors front marked), that
/// front, the front of each panel (cost and one error), the methods that exploded, and the cheapest method
/// within `bounds` (ChartBounds::defaults() when `bounds` sets none, and then said so), or that none is.
std::string chartSummaryMarkdown(const std::vector<ChartPoint>& points, const ChartOptions& options,
                                 const ChartBounds& bounds, std::size_t runs);

} // namespace afb::sim
