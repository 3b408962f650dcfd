// The tracking panel of afb chart (TrackChart.h): tracking runs per method and strength, folded into points.
#include "afb/sim/TrackChart.h"

#include <algorithm>
#include <cstdio>
#include <sstream>

namespace afb::sim {
namespace {

std::string chartFixed(double v, int decimals) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
    return buf;
}

double trackChartMedian(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n == 0 ? 0 : n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// One point: every rate and repeat of one figure, method and strength.
std::optional<TrackChartPoint> runPoint(const figure::Figure& figure, const decl::Md5Anim& anim,
                                        const TrackChartOptions& o, const ChartMethod& method, double strength,
                                        text::Diagnostics& diags) {
    TrackChartPoint p;
    p.figure = figure.name;
    p.label = method.label;
    p.strength = strength;
    std::vector<double> costs;
    for (int repeat = 0; repeat < std::max(1, o.repeats); ++repeat) {
        double cpuUs = 0;
        long long bodySteps = 0;
        for (double hz : o.hz) {
            TrackOptions t = o.track;
            t.hz = hz;
            t.strength = strength;
            t.method = method.method;
            const auto r = runTrack(figure, anim, t, diags);
            if (!r) return std::nullopt;
            cpuUs += r->cpuUsPerAwakeBodyStep * static_cast<double>(r->awakeBodySteps);
            bodySteps += r->awakeBodySteps;
            p.trackingRmsMm = std::max(p.trackingRmsMm, r->trackingRmsM * 1000.0);
            p.trackingRmsDeg = std::max(p.trackingRmsDeg, r->trackingRmsDeg);
            p.exploded = p.exploded || r->exploded;
        }
        if (bodySteps > 0) costs.push_back(cpuUs / static_cast<double>(bodySteps));
    }
    if (!costs.empty()) {
        p.costUs = trackChartMedian(costs);
        p.costMinUs = *std::min_element(costs.begin(), costs.end());
        p.costMaxUs = *std::max_element(costs.begin(), costs.end());
    }
    return p;
}

} // namespace

std::optional<std::vector<TrackChartPoint>> runTrackChart(const std::vector<figure::Figure>& figures,
                                                          const decl::Md5Anim& anim, const TrackChartOptions& o,
                                                          text::Diagnostics& diags) {
    std::vector<TrackChartPoint> points;
    for (const figure::Figure& figure : figures)
        for (const ChartMethod& method : o.methods)
            for (double strength : o.strengths) {
                auto p = runPoint(figure, anim, o, method, strength, diags);
                if (!p) return std::nullopt;
                points.push_back(std::move(*p));
            }
    return points;
}

std::string trackChartMarkdown(const std::vector<TrackChartPoint>& points, const TrackChartOptions& o) {
    std::ostringstream md;
    std::string rates, strengths;
    for (double hz : o.hz) rates += (rates.empty() ? "" : ", ") + chartFixed(hz, 0);
    for (double s : o.strengths) strengths += (strengths.empty() ? "" : ", ") + chartFixed(s, 2);
    md << "# afb chart: tracking error against cost\n\n"
       << "Each point: one method at one motor strength (" << strengths << " × the default gains, 15 Hz and damping "
       << "ratio 4), " << chartFixed(o.track.seconds, 1) << " s at " << rates << " Hz, root " << toString(o.track.root)
       << ", " << std::max(1, o.repeats) << " repeats. Cost: CPU µs per awake body-step (median, min–max of the "
       << "repeats); errors: every md5 joint after the " << chartFixed(o.track.warmupSeconds, 1)
       << " s warm-up, the worst rate.\n";
    std::string figure;
    for (const TrackChartPoint& p : points) {
        if (p.figure != figure) {
            figure = p.figure;
            md << "\n## " << figure << "\n\n"
               << "| method | strength | cost µs | min–max | tracking rms mm | tracking rms deg | exploded |\n"
               << "|---|---|---|---|---|---|---|\n";
        }
        md << "| " << p.label << " | " << chartFixed(p.strength, 2) << " | " << chartFixed(p.costUs, 2) << " | "
           << chartFixed(p.costMinUs, 2) << "–" << chartFixed(p.costMaxUs, 2) << " | " << chartFixed(p.trackingRmsMm, 1)
           << " | " << chartFixed(p.trackingRmsDeg, 2) << " | " << (p.exploded ? "yes" : "no") << " |\n";
    }
    return md.str();
}

} // namespace afb::sim
