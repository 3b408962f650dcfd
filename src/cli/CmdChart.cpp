// afb chart: speed against accuracy for a list of methods (plain Bullet's "raw" among them) on a list of figures.
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>

#include <unistd.h>

#include "ChartCli.h"
#include "ChartPlot.h"
#include "Commands.h"
#include "MethodOptions.h"
#include "Usage.h"
#include "afb/figure/Load.h"
#include "afb/sim/Chart.h"
#include "afb/sim/RawRagdoll.h"
#include "afb/sim/TrackChart.h"

namespace afb::cli {
namespace {

std::string clock(double seconds) {
    const long s = std::lround(seconds);
    char buf[32];
    std::snprintf(buf, sizeof buf, "%ld:%02ld", s / 60, s % 60);
    return buf;
}

// "  [##########..........] 12/40 runs  0:35 elapsed  ~0:52 left" on one rewritten stderr line.
void drawProgress(int done, int total, double elapsedSeconds) {
    constexpr int kWidth = 30;
    const int filled = total > 0 ? done * kWidth / total : kWidth;
    std::string bar(static_cast<std::size_t>(filled), '#');
    bar.resize(kWidth, '.');
    const std::string left =
        done > 0 && done < total ? "  ~" + clock(elapsedSeconds / done * (total - done)) + " left" : "";
    std::fprintf(stderr, "\r  [%s] %d/%d runs  %s elapsed%s   ", bar.c_str(), done, total,
                 clock(elapsedSeconds).c_str(), left.c_str());
    if (done == total) std::fprintf(stderr, "\n");
    std::fflush(stderr);
}

} // namespace

void addChartOptions(CLI::App* cmd, ChartCli& opt) {
    cmd->add_option("entities", opt.entities, "entityDefs to chart")->required();
    cmd->add_option("--base", opt.base, "Content folder (af/, def/, models/)")->capture_default_str();
    cmd->add_option("--methods", opt.methods, "Methods to chart, comma-separated (NAME[:KNOB=VALUE]...)")
        ->delimiter(',')
        ->capture_default_str();
    cmd->add_option("--heights", opt.chart.heightsM, "Drop heights, m, comma-separated")
        ->delimiter(',')
        ->check(within(0, 10000))
        ->capture_default_str();
    cmd->add_option("--hz", opt.chart.hz, "Frame rates, comma-separated")
        ->delimiter(',')
        ->check(within(1, 10000))
        ->capture_default_str();
    cmd->add_option("--repeats", opt.chart.repeats, "Runs of each combination (the cost's median and spread)")
        ->check(CLI::Range(1, 100))
        ->capture_default_str();
    cmd->add_option("--seconds", opt.chart.seconds, "Simulated time per run, s")
        ->check(within(0, 3600))
        ->capture_default_str();
    cmd->add_option("--count", opt.chart.count, "Instances per run (one world, yaw 37°·i)")
        ->check(CLI::Range(1, 1000))
        ->capture_default_str();
    cmd->add_option("--threads", opt.chart.threads, "Worker threads (each run owns its world)")
        ->check(CLI::Range(1, 256))
        ->capture_default_str();
    cmd->add_option("--out", opt.out, "Output folder (created)")->capture_default_str();
    cmd->add_option("--precision", opt.precision, "Bullet build: float or double (default: this binary's)")
        ->check(CLI::IsMember({"float", "double"}));
    cmd->add_flag("--no-sleep", opt.noSleep, "Never put figures to rest (no settle times)");
    cmd->add_option("--max-anchor-error", opt.maxAnchor, "Bound on the anchor error for the cheapest-method choice, m")
        ->check(nonNegative());
    cmd->add_option("--max-limit-error", opt.maxLimit, "Bound on the limit overshoot, degrees")->check(nonNegative());
    cmd->add_option("--max-penetration", opt.maxPenetration, "Bound on the peak penetration, m")->check(nonNegative());
    cmd->add_option("--max-settle-time", opt.maxSettle, "Bound on the settle time, s")->check(nonNegative());
}

namespace {

// The methods of --methods, each once; a spec that does not parse is a usage error.
std::vector<sim::ChartMethod> parseMethods(const std::vector<std::string>& specs) {
    std::vector<sim::ChartMethod> methods;
    for (const std::string& spec : specs) {
        std::string error;
        auto m = sim::parseChartMethod(spec, error);
        if (!m) usageError(error + methodSpecHint(spec));
        for (const sim::ChartMethod& other : methods)
            if (other.label == m->label) usageError("method " + spec + " is listed twice");
        methods.push_back(std::move(*m));
    }
    return methods;
}

// Runs the matrix into --out and prints its summary.
void runChartInto(const ChartCli& opt, const std::vector<figure::Figure>& figures,
                  const std::vector<std::string>& names) {
    const sim::ChartOptions& chart = opt.chart;
    const std::size_t total =
        figures.size() * chart.methods.size() * chart.heightsM.size() * chart.hz.size() * chart.repeats;
    std::printf("afb chart: Bullet %s (%s), %zu runs on %d threads into %s\n", sim::bulletVersion().c_str(),
                sim::bulletPrecision(), total, chart.threads, opt.out.string().c_str());
    std::fflush(stdout);
    const auto start = std::chrono::steady_clock::now();
    const bool tty = ::isatty(STDERR_FILENO) != 0;
    const std::vector<sim::ChartRun> runs = sim::runChart(figures, chart, [&](int done, int all) {
        if (tty)
            drawProgress(done, all, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    });
    writeChartOutputs(opt, runs, names);
}

// afb chart --track: tracking runs of the rigid methods at each strength instead of drops, into --out.
int trackChartCommand(ChartCli& opt) {
    sim::TrackChartOptions track;
    for (sim::ChartMethod& m : parseMethods(opt.methods)) {
        if (sim::isRaw(m.method) || m.method.backend != bullet::Backend::Rigid)
            std::printf("afb chart --track: %s left out (motors and keyframed bodies need the rigid backend)\n",
                        m.label.c_str());
        else track.methods.push_back(std::move(m));
    }
    if (track.methods.empty() || opt.strengths.empty() || opt.chart.hz.empty())
        usageError("--track needs a rigid method in --methods, a --strengths and a --hz value");
    track.strengths = opt.strengths;
    track.hz = opt.chart.hz;
    track.repeats = opt.chart.repeats;
    track.track.seconds = opt.chart.seconds;
    std::vector<figure::Figure> figures;
    std::vector<std::string> names;
    if (!loadChartFigures(opt, figures, names)) return kExitFailure;
    text::Diagnostics diags;
    std::filesystem::path anim = opt.trackAnim;
    if (!anim.is_absolute() && !std::filesystem::exists(anim) && std::filesystem::exists(opt.base / anim))
        anim = opt.base / anim;
    const auto loadedAnim = decl::loadMd5Anim(anim, diags);
    std::optional<std::vector<sim::TrackChartPoint>> points;
    if (loadedAnim) points = sim::runTrackChart(figures, *loadedAnim, track, diags);
    printDiagnostics(diags);
    std::error_code ec;
    std::filesystem::create_directories(opt.out, ec);
    if (!points || ec) {
        if (ec) std::cerr << "afb chart: cannot create " << opt.out.string() << ": " << ec.message() << "\n";
        return kExitFailure;
    }
    const std::string summary = sim::trackChartMarkdown(*points, track);
    std::ofstream(opt.out / "track.md") << summary;
    const std::string subtitle = "Bullet " + sim::bulletVersion() + " " + sim::bulletPrecision() + ", " +
                                 anim.filename().string() + ", " + CLI::detail::to_string(track.track.seconds) +
                                 " s, root keyframed";
    std::string plotError = writeTrackChartPlot(opt.out, *points, subtitle);
    if (plotError.empty()) plotError = runGnuplot(opt.out, "track.gp");
    std::printf("%s", summary.c_str());
    if (!plotError.empty()) std::cerr << "afb chart: warning: no track.png/track.svg: " << plotError << "\n";
    std::printf("\nwrote %s/{track.md,track.gp,track.dat%s}\n", opt.out.string().c_str(),
                plotError.empty() ? ",track.png,track.svg" : "");
    return 0;
}

int chartCommand(ChartCli& opt) {
    if (!opt.trackAnim.empty()) return trackChartCommand(opt);
    resolveChartOptions(opt);
    std::vector<figure::Figure> figures;
    std::vector<std::string> names;
    if (!loadChartFigures(opt, figures, names)) return kExitFailure;
    std::error_code ec;
    std::filesystem::create_directories(opt.out, ec);
    if (ec) {
        std::cerr << "afb chart: cannot create " << opt.out.string() << ": " << ec.message() << "\n";
        return kExitFailure;
    }
    runChartInto(opt, figures, names);
    return 0;
}

} // namespace

void addChartCommand(CLI::App& app, int& exitCode, char** argv) {
    auto* cmd =
        app.add_subcommand("chart", "Chart speed against accuracy: methods x figures x heights x rates\n"
                                    "Examples:\n  afb chart --base . chain --methods raw,fast,default --out chart\n"
                                    "  afb chart --base . humanoid --methods fast,default:substeps=2 --heights "
                                    "1,10 --out chart");
    cmd->footer("Writes into --out: runs.csv (one row per run: method_label, height_m, hz, repeat and every afb drop "
                "field and knob), front.png and front.svg (gnuplot: cost against each error, log-log, Pareto fronts "
                "dashed), front.gp and front.dat (their script and data), summary.md (per figure: every method, the "
                "Pareto front, the cheapest method within the --max-* bounds). With --track: track.md, track.png, "
                "track.svg, track.gp and track.dat (tracking error against cost per method and strength) instead.\n"
                "Methods: a preset or raw (plain Bullet), optionally with knob overrides: NAME[:KNOB=VALUE]..., e.g. "
                "raw:substeps=4 or default:position-iterations=8 (afb methods lists the methods and knobs).\n"
                "Cost: thread CPU time inside the steps per awake body-step (median of the repeats, min-max shown). "
                "Instruction counts: docs/performance.md.");
    auto opt = std::make_shared<ChartCli>();
    addChartOptions(cmd, *opt);
    cmd->add_option("--track", opt->trackAnim,
                    "The tracking panel instead of drops: every rigid method follows this md5anim (root keyframed, "
                    "as afb track) at each --strengths; writes track.md and track.png (tracking error against cost)");
    cmd->add_option("--strengths", opt->strengths, "Motor strengths of --track, comma-separated")
        ->delimiter(',')
        ->check(nonNegative())
        ->capture_default_str();
    cmd->callback([opt, &exitCode, argv] {
        if (!opt->precision.empty() && opt->precision != sim::bulletPrecision()) {
            execOtherPrecision(opt->precision, argv, "afb chart");
            exitCode = kExitFailure;
            return;
        }
        exitCode = chartCommand(*opt);
    });
}

void resolveChartOptions(ChartCli& opt) {
    sim::ChartOptions& chart = opt.chart;
    chart.sleeping = !opt.noSleep;
    chart.methods = parseMethods(opt.methods);
    if (chart.heightsM.empty() || chart.hz.empty() || chart.methods.empty())
        usageError("--heights, --hz and --methods need at least one value each");
}

bool loadChartFigures(const ChartCli& opt, std::vector<figure::Figure>& figures, std::vector<std::string>& names) {
    text::Diagnostics diags;
    auto lib = decl::Library::open(opt.base, diags);
    if (lib && findEntities(*lib, opt.entities, diags))
        for (const std::string& e : opt.entities) {
            std::optional<figure::LoadedFigure> loaded = figure::loadEntityFigure(*lib, e, {}, diags);
            if (!loaded) continue;
            names.push_back(loaded->figure.name);
            figures.push_back(std::move(loaded->figure));
        }
    printDiagnostics(diags);
    return !diags.hasErrors() && figures.size() == opt.entities.size();
}

void writeChartOutputs(const ChartCli& opt, const std::vector<sim::ChartRun>& runs,
                       const std::vector<std::string>& names) {
    const sim::ChartOptions& chart = opt.chart;
    const std::vector<sim::ChartPoint> points = sim::chartPoints(runs, names, chart.methods);
    const sim::ChartBounds bounds{opt.maxAnchor, opt.maxLimit, opt.maxPenetration, opt.maxSettle};
    std::ofstream(opt.out / "runs.csv") << sim::chartRunsCsv(runs);
    const std::string summary = sim::chartSummaryMarkdown(points, chart, bounds, runs.size());
    std::ofstream(opt.out / "summary.md") << summary;
    std::string heights, rates;
    for (double h : chart.heightsM) heights += (heights.empty() ? "" : ", ") + CLI::detail::to_string(h);
    for (double hz : chart.hz) rates += (rates.empty() ? "" : ", ") + CLI::detail::to_string(hz);
    const std::string subtitle = "Bullet " + sim::bulletVersion() + " " + sim::bulletPrecision() + ", drops from " +
                                 heights + " m at " + rates + " Hz, " + CLI::detail::to_string(chart.seconds) +
                                 " s; errors: worst over the drops";
    std::string plotError = writeChartPlot(opt.out, points, chart, subtitle);
    if (plotError.empty()) plotError = runGnuplot(opt.out);
    std::printf("\n%s", summary.c_str());
    for (const sim::ChartPoint& p : points)
        if (p.exploded) std::printf("note: %s exploded on %s\n", p.label.c_str(), p.figure.c_str());
    if (!plotError.empty()) std::cerr << "afb chart: warning: no front.png/front.svg: " << plotError << "\n";
    std::printf("\nwrote %s/{runs.csv,summary.md,front.gp,front.dat%s}\n", opt.out.string().c_str(),
                plotError.empty() ? ",front.png,front.svg" : "");
}

} // namespace afb::cli
