// afb chart's gnuplot script and data (ChartPlot.h). gnuplot draws; this file only decides what.
#include "ChartPlot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include <sys/wait.h>
#include <unistd.h>

namespace afb::cli {
namespace {

using sim::ChartMetric;
using sim::ChartPoint;

// Log axes cannot show 0: values below this floor are drawn at it (0.01 mm, 0.01°, 0.01 s).
constexpr double kFloor = 0.01;

// Colour-blind-safe colours (Okabe–Ito), one per figure.
constexpr const char* kColours[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000"};
constexpr int kColourCount = static_cast<int>(std::size(kColours));

// A metric's value as drawn: floored, and a run that never came to rest drawn at the run's length.
double drawn(const ChartPoint& p, ChartMetric m, double seconds) {
    const double v = sim::metricValue(p, m);
    if (!std::isfinite(v)) return seconds;
    return std::max(v, kFloor);
}

std::string plotNumber(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    return buf;
}

// gnuplot string literal (double quotes; backslashes and quotes escaped).
std::string quoted(const std::string& s) {
    std::string out = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\') out += '\\';
        out += c;
    }
    return out + "\"";
}

// A label without tabs or newlines (the data file is tab-separated).
std::string cell(std::string s) {
    std::replace_if(
        s.begin(), s.end(), [](char c) { return c == '\t' || c == '\n' || c == '\r'; }, ' ');
    return s;
}

// Tic marks 1, 2, 5 × 10^k within [lo, hi] (gnuplot's log axes mark only the decades).
std::string ticList(double lo, double hi) {
    std::string out;
    for (int k = static_cast<int>(std::floor(std::log10(lo))); k <= static_cast<int>(std::ceil(std::log10(hi))); ++k)
        for (double m : {1.0, 2.0, 5.0}) {
            const double v = m * std::pow(10.0, k);
            if (v >= lo && v <= hi) out += (out.empty() ? "" : ", ") + plotNumber(v);
        }
    return out;
}

// Point labels of a data block: alternate points (by cost) above and below, so neighbours do not overlap.
std::string labels(int block, int column, int labelColumn, const char* every, const char* offset, int lineType) {
    return "\"front.dat\" index " + std::to_string(block) + " " + every + " using 1:" + std::to_string(column) + ":" +
           std::to_string(labelColumn) + " with labels left offset char " + offset + " font \",9\" tc lt " +
           std::to_string(lineType) + " notitle";
}

} // namespace

std::string writeChartPlot(const std::filesystem::path& dir, const std::vector<ChartPoint>& points,
                           const sim::ChartOptions& options, const std::string& subtitle) {
    std::vector<std::string> figures;
    for (const ChartPoint& p : points)
        if (std::find(figures.begin(), figures.end(), p.figure) == figures.end()) figures.push_back(p.figure);

    // front.dat: per figure f, block 5f holds its points, cheapest first (cost, min, max, the four drawn errors,
    // label, settle label) and blocks 5f+1 … 5f+4 the front of each panel, cheapest first (cost, drawn error).
    std::ostringstream data;
    data << "# afb chart data: blocks of 5 per figure (points; fronts in anchor, limit, penetration, settle)\n";
    for (const std::string& figure : figures) {
        std::vector<ChartPoint> mine;
        for (const ChartPoint& p : points)
            if (p.figure == figure) mine.push_back(p);
        std::stable_sort(mine.begin(), mine.end(),
                         [](const ChartPoint& a, const ChartPoint& b) { return a.costUs < b.costUs; });
        data << "# " << cell(figure) << ": cost_us cost_min cost_max anchor_mm limit_deg penetration_mm settle_s "
             << "label settle_label\n";
        for (const ChartPoint& p : mine) {
            data << plotNumber(p.costUs) << '\t' << plotNumber(p.costMinUs) << '\t' << plotNumber(p.costMaxUs);
            for (ChartMetric m : sim::kChartMetrics) data << '\t' << plotNumber(drawn(p, m, options.seconds));
            // Exploded methods are marked; a settle label only where the method came to rest (an empty field is
            // missing to gnuplot: no label).
            const std::string label = cell(p.label) + (p.exploded ? " ✗" : "");
            data << '\t' << label << '\t' << (p.settleS ? label : std::string()) << '\n';
        }
        for (ChartMetric m : sim::kChartMetrics) {
            const std::vector<std::size_t> front = sim::chartFront(mine, {m}); // ascending: cheapest first
            data << "\n\n# " << cell(figure) << ": front in cost and " << sim::metricTitle(m) << "\n";
            for (std::size_t i : front)
                data << plotNumber(mine[i].costUs) << '\t' << plotNumber(drawn(mine[i], m, options.seconds)) << '\n';
        }
        data << "\n\n";
    }

    // Ranges: log axes padded by a factor around the data (room on the right for the labels), never empty.
    double xLo = 1e300, xHi = 0;
    for (const ChartPoint& p : points)
        if (p.costUs > 0) { // a point without a cost (never awake) is not drawn
            xLo = std::min(xLo, p.costMinUs);
            xHi = std::max(xHi, p.costMaxUs);
        }
    if (xHi <= 0) xLo = xHi = 1;
    auto yRange = [&](ChartMetric m) {
        double lo = 1e300, hi = 0;
        for (const ChartPoint& p : points) {
            lo = std::min(lo, drawn(p, m, options.seconds));
            hi = std::max(hi, drawn(p, m, options.seconds));
        }
        return std::make_pair(lo / 2, hi * 2);
    };

    const int figureCount = static_cast<int>(figures.size());
    std::ostringstream gp;
    gp << "# afb chart: cost against error for every method and figure. Regenerate the pictures with\n"
       << "#   gnuplot front.gp      (in this folder; writes front.png and front.svg)\n"
       << "set datafile separator \"\\t\"\n"
       << "set encoding utf8\n";
    for (int f = 0; f < figureCount; ++f)
        gp << "set linetype " << f + 1 << " lc rgb " << quoted(kColours[f % kColourCount]) << " lw 1.5 pt 7 ps 1.1\n";
    const std::string title = "afb chart: speed against accuracy\\n" + subtitle + "; ✗: exploded (off the fronts)";
    const char* terminals[][2] = {{"pngcairo size 1600,1200 font \"DejaVu Sans,11\" noenhanced", "front.png"},
                                  {"svg size 1600,1200 font \"DejaVu Sans,11\" noenhanced", "front.svg"}};
    for (const auto& [terminal, file] : terminals) {
        gp << "\nset terminal " << terminal << "\nset output " << quoted(file) << "\n"
           << "set multiplot layout 2,2 title \"" << title << "\"\n"
           << "set logscale xy\nset grid xtics ytics mxtics mytics lc rgb \"#dddddd\"\n"
           << "set key top right box opaque\n"
           << "set xlabel \"cost: CPU µs per awake body-step (median, bars: min–max of " << options.repeats
           << " repeats)\"\n"
           << "set xrange [" << plotNumber(xLo / 1.5) << ":" << plotNumber(xHi * 3) << "]\n"
           << "set xtics (" << ticList(xLo / 1.5, xHi * 3) << ")\n";
        int panel = 0;
        for (ChartMetric m : sim::kChartMetrics) {
            std::string ylabel(sim::metricTitle(m));
            if (m == ChartMetric::Settle) ylabel += " (never: drawn at " + plotNumber(options.seconds) + " s)";
            else ylabel += " (0 drawn at " + plotNumber(kFloor) + ")";
            const auto [yLo, yHi] = yRange(m);
            gp << "set ylabel " << quoted(ylabel) << "\nset yrange [" << plotNumber(yLo) << ":" << plotNumber(yHi)
               << "]\n"
               << "set ytics (" << ticList(yLo, yHi) << ")\n"
               << "set title " << quoted(std::string(sim::metricTitle(m)) + " against cost; dashed: Pareto front")
               << "\nplot ";
            for (int f = 0; f < figureCount; ++f) {
                const int block = 5 * f;
                const int column = 4 + panel;
                const int labelColumn = m == ChartMetric::Settle ? 9 : 8;
                if (f > 0) gp << ", \\\n     ";
                gp << "\"front.dat\" index " << block << " using 1:" << column << ":2:3 with xerrorbars lt " << f + 1
                   << " title " << quoted(figures[static_cast<std::size_t>(f)]) << ", \\\n     "
                   << labels(block, column, labelColumn, "every 2::0", "0.5,0.6", f + 1) << ", \\\n     "
                   << labels(block, column, labelColumn, "every 2::1", "0.5,-0.6", f + 1) << ", \\\n     "
                   << "\"front.dat\" index " << block + 1 + panel << " using 1:2 with lines lt " << f + 1
                   << " dt 2 notitle";
            }
            gp << "\n";
            ++panel;
        }
        gp << "unset multiplot\nset output\n";
    }

    std::ofstream dataFile(dir / "front.dat");
    dataFile << data.str();
    std::ofstream scriptFile(dir / "front.gp");
    scriptFile << gp.str();
    if (!dataFile || !scriptFile) return "cannot write " + (dir / "front.gp").string();
    return {};
}

std::string writeTrackChartPlot(const std::filesystem::path& dir, const std::vector<sim::TrackChartPoint>& points,
                                const std::string& subtitle) {
    // track.dat: one block per figure and method (in the order of the points), by strength: cost, min, max, mm,
    // degrees, label.
    std::ostringstream data;
    std::vector<std::string> titles;
    double xLo = 1e300, xHi = 0, mmLo = 1e300, mmHi = 0, degLo = 1e300, degHi = 0;
    for (std::size_t i = 0; i < points.size();) {
        std::size_t end = i;
        while (end < points.size() && points[end].figure == points[i].figure && points[end].label == points[i].label)
            ++end;
        std::vector<sim::TrackChartPoint> line(points.begin() + static_cast<std::ptrdiff_t>(i),
                                               points.begin() + static_cast<std::ptrdiff_t>(end));
        std::stable_sort(line.begin(), line.end(),
                         [](const auto& a, const auto& b) { return a.strength < b.strength; });
        titles.push_back(points[i].figure + " " + points[i].label);
        data << "# " << cell(titles.back()) << ": cost_us cost_min cost_max tracking_rms_mm tracking_rms_deg label\n";
        for (const sim::TrackChartPoint& p : line) {
            const double mm = std::max(p.trackingRmsMm, kFloor), deg = std::max(p.trackingRmsDeg, kFloor);
            data << plotNumber(std::max(p.costUs, kFloor)) << '\t' << plotNumber(std::max(p.costMinUs, kFloor)) << '\t'
                 << plotNumber(std::max(p.costMaxUs, kFloor)) << '\t' << plotNumber(mm) << '\t' << plotNumber(deg)
                 << "\t×" << plotNumber(p.strength) << (p.exploded ? " ✗" : "") << '\n';
            xLo = std::min(xLo, std::max(p.costMinUs, kFloor));
            xHi = std::max(xHi, std::max(p.costMaxUs, kFloor));
            mmLo = std::min(mmLo, mm), mmHi = std::max(mmHi, mm);
            degLo = std::min(degLo, deg), degHi = std::max(degHi, deg);
        }
        data << "\n\n";
        i = end;
    }
    if (titles.empty()) return "no tracking points to plot";

    std::ostringstream gp;
    gp << "# afb chart --track: tracking error against cost. Regenerate the pictures with\n"
       << "#   gnuplot track.gp      (in this folder; writes track.png and track.svg)\n"
       << "set datafile separator \"\\t\"\nset encoding utf8\n";
    for (std::size_t k = 0; k < titles.size(); ++k)
        gp << "set linetype " << k + 1 << " lc rgb " << quoted(kColours[k % kColourCount]) << " lw 1.5 pt 7 ps 1.1\n";
    const char* terminals[][2] = {{"pngcairo size 1600,700 font \"DejaVu Sans,11\" noenhanced", "track.png"},
                                  {"svg size 1600,700 font \"DejaVu Sans,11\" noenhanced", "track.svg"}};
    const std::pair<int, std::string> panels[] = {{4, "tracking rms, mm"}, {5, "tracking rms, degrees"}};
    for (const auto& [terminal, file] : terminals) {
        gp << "\nset terminal " << terminal << "\nset output " << quoted(file) << "\n"
           << "set multiplot layout 1,2 title \"afb chart: tracking error against cost\\n"
           << quoted(subtitle).substr(1) << "\nset logscale xy\nset grid xtics ytics mxtics mytics lc rgb \"#dddddd\"\n"
           << "set key top right box opaque\n"
           << "set xlabel \"cost: CPU µs per awake body-step (median, bars: min–max of the repeats)\"\n"
           << "set xrange [" << plotNumber(xLo / 1.5) << ":" << plotNumber(xHi * 3) << "]\n"
           << "set xtics (" << ticList(xLo / 1.5, xHi * 3) << ")\n";
        for (const auto& [column, title] : panels) {
            const double lo = column == 4 ? mmLo / 2 : degLo / 2, hi = column == 4 ? mmHi * 2 : degHi * 2;
            gp << "set ylabel " << quoted(title) << "\nset yrange [" << plotNumber(lo) << ":" << plotNumber(hi)
               << "]\nset ytics (" << ticList(lo, hi) << ")\nset title "
               << quoted(title + " against cost; labels: motor strength") << "\nplot ";
            for (std::size_t k = 0; k < titles.size(); ++k) {
                const std::string index = "\"track.dat\" index " + std::to_string(k);
                gp << (k > 0 ? ", \\\n     " : "") << index << " using 1:" << column << ":2:3 with xerrorbars lt "
                   << k + 1 << " title " << quoted(titles[k]) << ", \\\n     " << index << " using 1:" << column
                   << " with lines lt " << k + 1 << " notitle, \\\n     " << index << " using 1:" << column
                   << ":6 with labels left offset char 0.5,0.6 font \",9\" tc lt " << k + 1 << " notitle";
            }
            gp << "\n";
        }
        gp << "unset multiplot\nset output\n";
    }
    std::ofstream dataFile(dir / "track.dat");
    dataFile << data.str();
    std::ofstream scriptFile(dir / "track.gp");
    scriptFile << gp.str();
    if (!dataFile || !scriptFile) return "cannot write " + (dir / "track.gp").string();
    return {};
}

std::string runGnuplot(const std::filesystem::path& dir, const std::string& script) {
    const pid_t pid = ::fork();
    if (pid < 0) return "cannot start gnuplot";
    if (pid == 0) {
        if (::chdir(dir.c_str()) != 0) ::_exit(126);
        ::execlp("gnuplot", "gnuplot", script.c_str(), static_cast<char*>(nullptr));
        ::_exit(127);
    }
    int status = 0;
    if (::waitpid(pid, &status, 0) < 0) return "gnuplot: lost track of it";
    if (WIFEXITED(status) && WEXITSTATUS(status) == 127)
        return "gnuplot not found (install it: cmake/install-deps.sh); the script is " + (dir / script).string();
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
        return "gnuplot failed on " + (dir / script).string() + " (exit status " +
               std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + ")";
    return {};
}

} // namespace afb::cli
