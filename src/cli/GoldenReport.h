#pragma once
// Reports of `afb golden compare` for CI systems and people: a JUnit XML file (one test case per golden), a
// Markdown summary, and a picture of each failing golden's settled pose drawn over its recorded pose.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "afb/figure/Figure.h"

namespace afb::cli {

/// A joint (or "(entity)", the entity transform) past its tolerance.
struct JointMiss {
    std::string joint;
    double movedM = 0;    ///< distance from its recorded position, metres
    double turnedDeg = 0; ///< angle from its recorded orientation, degrees
};

/// The outcome of comparing one golden file.
struct GoldenCase {
    std::filesystem::path file; ///< as given on the command line
    std::string entity;         ///< empty when the file could not be read
    bool passed = false;
    /// Why the golden could not be compared (not a golden file, an input changed, a method that cannot run), one
    /// message per line; empty when it was compared.
    std::vector<std::string> errors;
    /// What compare printed on stderr about the golden that did not stop it (an input changed but compared anyway
    /// with --ignore-inputs, the loader's warnings), lines ending in newlines.
    std::string warnings;
    double worstM = 0, worstDeg = 0;         ///< the joint that moved most, and the one that turned most
    double toleranceM = 0, toleranceDeg = 0; ///< the golden's tolerances
    std::vector<JointMiss> missed;           ///< the joints past tolerance, in skeleton order
    std::vector<std::string> notes;          ///< "state hash differs", "joint count differs"
    double seconds = 0;                      ///< wall time of the re-run
    std::filesystem::path picture;           ///< the report's picture of a failing pose, relative to its folder
};

/// The one line `afb golden compare` prints per golden ("ok  FILE: worst joint …" or "FAIL FILE: …").
std::string caseLine(const GoldenCase& c);

/// Writes the JUnit XML report (testsuites / testsuite / testcase, with a failure per failing golden naming the
/// joints past tolerance, an error per golden that could not be compared) to `out` ("-": stdout). Returns an
/// error message when the file cannot be written.
std::optional<std::string> writeJUnit(const std::vector<GoldenCase>& cases, const std::filesystem::path& out);

/// Writes `dir`/summary.md: a table of every golden and, per failing one, its picture and the joints past
/// tolerance. Returns an error message when it cannot be written.
std::optional<std::string> writeMarkdown(const std::vector<GoldenCase>& cases, const std::filesystem::path& dir);

/// A pose to picture: the entity transform (model → world) and every md5 joint in model space, metres.
struct PoseRecord {
    figure::Transform entity;
    std::vector<figure::Transform> jointsModel;
};

/// Draws the settled pose `now` (orange) over the recorded pose `golden` (blue) of `figure` to `out` (PNG), in
/// world space with the ground; bodies are placed from the joints (figure::bodiesFromJoints), so the picture shows
/// what the comparison measures. Returns an error message on failure.
std::optional<std::string> drawGoldenPicture(const figure::Figure& figure, const PoseRecord& golden,
                                             const PoseRecord& now, const std::string& title,
                                             const std::string& subtitle, const std::filesystem::path& out);

} // namespace afb::cli
