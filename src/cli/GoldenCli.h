#pragma once
// afb golden compare's options, its run of one golden file and its outputs, shared by the one-process command and
// by plan/run/merge (goldens spread over many processes), so that both compare and report by the same code.
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "GoldenReport.h"

namespace afb::cli {

/// The options of `afb golden compare`.
struct GoldenCompareCli {
    std::vector<std::filesystem::path> files;
    bool exact = false;
    bool ignoreInputs = false;
    std::filesystem::path junit, report;
};

/// Registers compare's options on `cmd` (afb golden compare, afb plan golden compare).
void addGoldenCompareOptions(CLI::App* cmd, GoldenCompareCli& opt);

/// Re-runs one golden file. With opt.report, a failing pose is drawn into opt.report under a name unique among
/// `pictures` (which receives the name, even when the drawing fails).
GoldenCase compareGolden(const std::filesystem::path& file, const GoldenCompareCli& opt,
                         std::vector<std::filesystem::path>& pictures);

/// A file name in the report folder for the picture of `c`, unique among `taken` (which receives it).
std::filesystem::path goldenPictureName(const GoldenCase& c, std::vector<std::filesystem::path>& taken);

/// Where compare's lines for people go: stdout, or stderr when the JUnit report is written to stdout.
std::FILE* goldenTextStream(const GoldenCompareCli& opt);

/// Prints what compare prints for one golden: its warnings and errors on stderr, its line and the joints past
/// tolerance on `text`.
void printGoldenCase(const GoldenCase& c, std::FILE* text);

/// Writes the JUnit file and the Markdown summary the options ask for, and says where on `text`; `pictures`: the
/// picture names taken. Returns compare's exit code: 1 when a golden failed or a report cannot be written.
int finishGoldenCompare(const GoldenCompareCli& opt, const std::vector<GoldenCase>& cases, std::size_t pictures);

/// The input files of a golden file, relative to `base`, with their hashes: the file itself and, when it reads as
/// a golden, every input file it recorded (as they are now).
nlohmann::json goldenInputs(const std::filesystem::path& file, const std::filesystem::path& base);

} // namespace afb::cli
