// afb chart's matrix, its points and the choices it offers (Chart.h). Plotting is the tool's (src/cli).
#include "afb/sim/Chart.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <limits>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>

#include "afb/sim/RawRagdoll.h"
#include "afb/sim/Report.h"

namespace afb::sim {
namespace {

std::string formatNumber(double v, const char* format) {
    char buf[64];
    std::snprintf(buf, sizeof buf, format, v);
    return buf;
}

double median(std::vector<double> v) {
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

} // namespace

std::optional<ChartMethod> parseChartMethod(std::string_view spec, std::string& error) {
    const std::size_t colon = spec.find(':');
    const std::string_view name = spec.substr(0, colon);
    auto method = methodByName(name);
    if (!method) {
        error = "method " + std::string(spec) + ": unknown method " + std::string(name) + " (";
        for (std::string_view n : methodNames()) error += " " + std::string(n);
        error += " )";
        return std::nullopt;
    }
    std::string_view rest = colon == std::string_view::npos ? std::string_view() : spec.substr(colon + 1);
    while (!rest.empty()) {
        const std::size_t next = rest.find(':');
        const std::string_view item = rest.substr(0, next);
        rest = next == std::string_view::npos ? std::string_view() : rest.substr(next + 1);
        const std::size_t eq = item.find('=');
        const bullet::MethodKnob* knob = eq == std::string_view::npos ? nullptr : bullet::findKnob(item.substr(0, eq));
        if (!knob) {
            error = "method " + std::string(spec) + ": '" + std::string(item) + "' is not KNOB=VALUE with a knob of " +
                    "afb methods";
            return std::nullopt;
        }
        if (std::string e = bullet::setKnob(*method, *knob, item.substr(eq + 1)); !e.empty()) {
            error = "method " + std::string(spec) + ": " + e;
            return std::nullopt;
        }
    }
    if (std::string e = rawMethodError(*method); !e.empty()) {
        error = "method " + std::string(spec) + ": " + e;
        return std::nullopt;
    }
    return ChartMethod{std::string(spec), *method};
}

std::vector<ChartRun> chartRuns(std::size_t figures, const ChartOptions& o) {
    std::vector<ChartRun> runs;
    for (std::size_t f = 0; f < figures; ++f)
        for (const ChartMethod& m : o.methods)
            for (double h : o.heightsM)
                for (double hz : o.hz)
                    for (int r = 0; r < std::max(1, o.repeats); ++r) runs.push_back({m.label, f, h, hz, r, {}});
    return runs;
}

DropOptions chartDropOptions(const ChartOptions& o, const ChartRun& run, const bullet::Method& method) {
    DropOptions d;
    d.heightM = run.heightM;
    d.hz = run.hz;
    d.count = std::max(1, o.count);
    d.seconds = o.seconds;
    d.sleeping = o.sleeping;
    d.method = method;
    return d;
}

std::vector<ChartRun> runChart(const std::vector<figure::Figure>& figures, const ChartOptions& o,
                               const std::function<void(int, int)>& progress) {
    std::vector<ChartRun> runs = chartRuns(figures.size(), o);
    std::vector<bullet::Method> methodOf;
    for (const ChartRun& run : runs)
        for (const ChartMethod& m : o.methods)
            if (m.label == run.label) {
                methodOf.push_back(m.method);
                break;
            }

    // Executed repeat by repeat (every method's first repeat, then every method's second, …), so that a change
    // of load on the machine during the chart falls on every method alike instead of on the last ones.
    std::vector<std::size_t> order(runs.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return runs[a].repeat < runs[b].repeat; });

    const int total = static_cast<int>(runs.size());
    std::atomic<std::size_t> next{0};
    std::mutex mutex;
    std::condition_variable finished;
    int done = 0;
    auto worker = [&] {
        for (std::size_t k = next++; k < order.size(); k = next++) {
            const std::size_t i = order[k];
            ChartRun& run = runs[i];
            run.result = runDrop(figures[run.figure], chartDropOptions(o, run, methodOf[i]));
            const std::lock_guard lock(mutex);
            ++done;
            finished.notify_one();
        }
    };
    std::vector<std::thread> threads;
    const int workers = std::clamp(o.threads, 1, std::max(1, total));
    for (int t = 0; t < workers; ++t) threads.emplace_back(worker);
    {
        std::unique_lock lock(mutex);
        while (done < total) {
            finished.wait_for(lock, std::chrono::milliseconds(250));
            if (progress) {
                const int now = done;
                lock.unlock();
                progress(now, total);
                lock.lock();
            }
        }
    }
    for (std::thread& t : threads) t.join();
    if (progress) progress(total, total);
    return runs;
}

std::vector<ChartPoint> chartPoints(const std::vector<ChartRun>& runs, const std::vector<std::string>& figureNames,
                                    const std::vector<ChartMethod>& methods) {
    std::vector<ChartPoint> points;
    for (std::size_t f = 0; f < figureNames.size(); ++f)
        for (const ChartMethod& m : methods) {
            ChartPoint p;
            p.figure = figureNames[f];
            p.label = m.label;
            std::map<int, std::pair<double, long long>> perRepeat; // CPU ms and awake body-steps
            bool allSettled = true, any = false;
            double settle = 0;
            for (const ChartRun& run : runs) {
                if (run.figure != f || run.label != m.label) continue;
                const DropResult& r = run.result;
                any = true;
                perRepeat[run.repeat].first += r.awakeStepCpuMs;
                perRepeat[run.repeat].second += r.awakeBodySteps;
                p.anchorM = std::max(p.anchorM, r.maxAnchorErrorM);
                p.limitDeg = std::max(p.limitDeg, r.maxLimitViolationDeg);
                p.penetrationM = std::max(p.penetrationM, r.maxPenetrationM);
                p.exploded = p.exploded || r.exploded;
                if (r.settleTimeS) settle = std::max(settle, *r.settleTimeS);
                else allSettled = false;
            }
            if (!any) continue;
            if (allSettled) p.settleS = settle;
            std::vector<double> costs; // repeats without an awake body-step have no cost to give
            for (const auto& [repeat, sums] : perRepeat)
                if (sums.second > 0) costs.push_back(sums.first * 1000.0 / static_cast<double>(sums.second));
            if (!costs.empty()) {
                p.costUs = median(costs);
                p.costMinUs = *std::min_element(costs.begin(), costs.end());
                p.costMaxUs = *std::max_element(costs.begin(), costs.end());
            }
            points.push_back(p);
        }
    return points;
}

double metricValue(const ChartPoint& p, ChartMetric metric) {
    switch (metric) {
    case ChartMetric::Anchor: return p.anchorM * 1000.0;
    case ChartMetric::Limit: return p.limitDeg;
    case ChartMetric::Penetration: return p.penetrationM * 1000.0;
    case ChartMetric::Settle: return p.settleS ? *p.settleS : std::numeric_limits<double>::infinity();
    }
    return 0;
}

std::string_view metricTitle(ChartMetric metric) {
    switch (metric) {
    case ChartMetric::Anchor: return "max anchor error, mm";
    case ChartMetric::Limit: return "max limit overshoot, degrees";
    case ChartMetric::Penetration: return "peak penetration, mm";
    case ChartMetric::Settle: return "settle time, s";
    }
    return "";
}

std::vector<std::size_t> paretoFront(const std::vector<std::vector<double>>& objectives) {
    std::vector<std::size_t> front;
    for (std::size_t i = 0; i < objectives.size(); ++i) {
        bool dominated = false;
        for (std::size_t j = 0; j < objectives.size() && !dominated; ++j) {
            if (j == i) continue;
            bool noWorse = true, better = false;
            for (std::size_t k = 0; k < objectives[i].size(); ++k) {
                noWorse = noWorse && objectives[j][k] <= objectives[i][k];
                better = better || objectives[j][k] < objectives[i][k];
            }
            dominated = noWorse && better;
        }
        if (!dominated) front.push_back(i);
    }
    return front;
}

std::vector<std::size_t> chartFront(const std::vector<ChartPoint>& points, const std::vector<ChartMetric>& metrics) {
    // Candidates: methods that held together and had an awake body to charge (an exploded method is no choice,
    // and one without a cost cannot be compared).
    std::vector<std::size_t> candidates;
    std::vector<std::vector<double>> objectives;
    for (std::size_t i = 0; i < points.size(); ++i) {
        const ChartPoint& p = points[i];
        if (p.exploded || p.costUs <= 0) continue;
        std::vector<double> o = {p.costUs};
        for (ChartMetric m : metrics) o.push_back(metricValue(p, m));
        candidates.push_back(i);
        objectives.push_back(std::move(o));
    }
    std::vector<std::size_t> front;
    for (std::size_t k : paretoFront(objectives)) front.push_back(candidates[k]);
    return front;
}

std::optional<std::size_t> cheapestWithin(const std::vector<ChartPoint>& points, const ChartBounds& b) {
    std::optional<std::size_t> best;
    for (std::size_t i = 0; i < points.size(); ++i) {
        const ChartPoint& p = points[i];
        if (p.exploded || p.costUs <= 0) continue;
        if (b.anchorM && p.anchorM > *b.anchorM) continue;
        if (b.limitDeg && p.limitDeg > *b.limitDeg) continue;
        if (b.penetrationM && p.penetrationM > *b.penetrationM) continue;
        if (b.settleS && (!p.settleS || *p.settleS > *b.settleS)) continue;
        if (!best || p.costUs < points[*best].costUs) best = i;
    }
    return best;
}

std::string chartRunsCsv(const std::vector<ChartRun>& runs) {
    std::string out = "method_label,height_m,hz,repeat," + dropCsvHeader() + "\n";
    for (const ChartRun& run : runs) {
        std::string label = run.label;
        if (label.find_first_of(",\"") != std::string::npos) {
            std::string quoted = "\"";
            for (char c : label) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
            label = quoted + "\"";
        }
        out += label + "," + formatNumber(run.heightM, "%g") + "," + formatNumber(run.hz, "%g") + "," +
               std::to_string(run.repeat) + "," + dropCsvRow(run.result) + "\n";
    }
    return out;
}

namespace {

std::string list(const std::vector<double>& values, const char* unit) {
    std::string out;
    for (double v : values) out += (out.empty() ? "" : ", ") + formatNumber(v, "%g");
    return out + unit;
}

std::string boundsText(const ChartBounds& b) {
    std::string out;
    auto add = [&](const std::string& s) { out += (out.empty() ? "" : ", ") + s; };
    if (b.anchorM) add("anchor ≤ " + formatNumber(*b.anchorM * 1000.0, "%g") + " mm");
    if (b.limitDeg) add("limit ≤ " + formatNumber(*b.limitDeg, "%g") + "°");
    if (b.penetrationM) add("penetration ≤ " + formatNumber(*b.penetrationM * 1000.0, "%g") + " mm");
    if (b.settleS) add("settle ≤ " + formatNumber(*b.settleS, "%g") + " s");
    return out;
}

std::string pointRow(const ChartPoint& p, bool onFront) {
    const std::string cost = p.costUs > 0 ? formatNumber(p.costUs, "%.2f") + " (" + formatNumber(p.costMinUs, "%.2f") +
                                                "–" + formatNumber(p.costMaxUs, "%.2f") + ")"
                                          : std::string("– (never awake)");
    return "| `" + p.label + "` | " + cost + " | " + formatNumber(p.anchorM * 1000.0, "%.1f") + " | " +
           formatNumber(p.limitDeg, "%.1f") + " | " + formatNumber(p.penetrationM * 1000.0, "%.1f") + " | " +
           (p.settleS ? formatNumber(*p.settleS, "%.2f") : std::string("never")) + " | " + (p.exploded ? "yes" : "no") +
           " | " + (onFront ? "**front**" : "") + " |\n";
}

} // namespace

std::string chartSummaryMarkdown(const std::vector<ChartPoint>& points, const ChartOptions& o,
                                 const ChartBounds& bounds, std::size_t runs) {
    std::ostringstream out;
    out << "# afb chart: speed against accuracy\n\n"
        << "Bullet " << bulletVersion() << " (" << bulletPrecision() << "); " << runs << " runs: " << o.methods.size()
        << " methods, heights " << list(o.heightsM, " m") << ", " << list(o.hz, " Hz") << ", " << o.repeats
        << " repeats; " << formatNumber(o.seconds, "%g") << " s each, " << o.count << " instance"
        << (o.count == 1 ? "" : "s") << ", sleeping " << (o.sleeping ? "on" : "off") << ".\n\n"
        << "Cost: thread CPU time per awake body-step, µs, the median of the repeats (min–max). Errors: the worst "
           "over the scenarios. A method is on the **Pareto front** when no other method is at least as cheap and "
           "as accurate in all four errors and better in one (methods that exploded are no choice and left out).\n";
    std::vector<std::string> figures;
    for (const ChartPoint& p : points)
        if (std::find(figures.begin(), figures.end(), p.figure) == figures.end()) figures.push_back(p.figure);
    const std::vector<ChartMetric> all(std::begin(kChartMetrics), std::end(kChartMetrics));
    for (const std::string& figure : figures) {
        std::vector<ChartPoint> mine;
        for (const ChartPoint& p : points)
            if (p.figure == figure) mine.push_back(p);
        const std::vector<std::size_t> front = chartFront(mine, all);
        out << "\n## " << figure << "\n\n"
            << "| method | cost µs (min–max) | anchor mm | limit ° | peak pen. mm | settle s | exploded | |\n"
            << "|---|---|---|---|---|---|---|---|\n";
        for (std::size_t i = 0; i < mine.size(); ++i)
            out << pointRow(mine[i], std::find(front.begin(), front.end(), i) != front.end());
        auto names = [&](std::vector<std::size_t> members) {
            std::sort(members.begin(), members.end(),
                      [&](std::size_t a, std::size_t b) { return mine[a].costUs < mine[b].costUs; });
            std::string text;
            for (std::size_t i : members) text += (text.empty() ? "" : ", ") + ("`" + mine[i].label + "`");
            return text.empty() ? std::string("none") : text;
        };
        out << "\nPareto front in cost and all four errors (cheapest first): " << names(front) << ".\n";
        for (ChartMetric m : kChartMetrics)
            out << "- front in cost and " << metricTitle(m) << ": " << names(chartFront(mine, {m})) << "\n";
        std::string exploded;
        for (const ChartPoint& p : mine)
            if (p.exploded) exploded += (exploded.empty() ? "" : ", ") + ("`" + p.label + "`");
        if (!exploded.empty()) out << "\nExploded (not on any front): " << exploded << ".\n";
        // Only a method inside the bounds it names is recommended; with none given, the defaults, said so.
        const ChartBounds within = bounds.any() ? bounds : ChartBounds::defaults();
        const std::optional<std::size_t> cheapest = cheapestWithin(mine, within);
        out << "\nCheapest within " << boundsText(within)
            << (bounds.any() ? std::string()
                             : " (the default bounds; set others with --max-anchor-error, --max-limit-error, "
                               "--max-penetration, --max-settle-time)")
            << ": " << (cheapest ? "`" + mine[*cheapest].label + "`" : std::string("none of the methods charted"))
            << ".\n";
    }
    return out.str();
}

} // namespace afb::sim
