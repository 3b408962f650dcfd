#pragma once
// afb chart's options, inputs and outputs, shared by the one-process command and by plan/run/merge (the batch of
// its runs over many processes), so that both read, run and write the chart by the same code.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "afb/figure/Figure.h"
#include "afb/sim/Chart.h"

namespace afb::cli {

/// The options of `afb chart`.
struct ChartCli {
    std::filesystem::path base = ".";
    std::vector<std::string> entities;
    // exact is the default; the iterative default it replaced stays on the front.
    std::vector<std::string> methods = {"raw", "legacy", "fast", "balanced", "iterative", "default", "accurate"};
    sim::ChartOptions chart;
    std::filesystem::path out = "chart";
    std::string precision;
    bool noSleep = false;
    std::optional<double> maxAnchor, maxLimit, maxPenetration, maxSettle;
    /// afb chart --track: the md5anim of the tracking panel (empty: the chart of drops) and its motor strengths.
    std::filesystem::path trackAnim;
    std::vector<double> strengths = {0.25, 0.5, 1, 2, 4};
};

/// Registers afb chart's options on `cmd` (afb chart, afb plan chart).
void addChartOptions(CLI::App* cmd, ChartCli& opt);
/// Completes opt.chart from the options (methods parsed, sleeping); a command line that makes no sense is a usage
/// error.
void resolveChartOptions(ChartCli& opt);
/// The figures of opt.entities from opt.base, with their names; false (diagnostics printed) when one fails.
bool loadChartFigures(const ChartCli& opt, std::vector<figure::Figure>& figures, std::vector<std::string>& names);
/// Writes runs.csv, summary.md and the plots into opt.out and prints the summary. `runs` in runChart's order.
void writeChartOutputs(const ChartCli& opt, const std::vector<sim::ChartRun>& runs,
                       const std::vector<std::string>& names);

} // namespace afb::cli
