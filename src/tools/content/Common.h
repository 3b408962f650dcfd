#pragma once
// What every part of afb_gen_content shares: angle constants, the rounding that keeps the output short and
// stable, the output folder, and the entry point of each bundled figure.
#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace afb::gen {

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kDeg = kPi / 180.0;

/// `v` rounded to `decimals` decimals, never -0. The md5 and .af writers print a double in its shortest exact
/// form, so a rounded value prints with at most `decimals` decimals and the same on every machine.
inline double rnd(double v, int decimals = 4) {
    const double scale = std::pow(10.0, decimals);
    const double r = std::round(v * scale) / scale;
    return r == 0.0 ? 0.0 : r;
}

/// The folder written into (same layout as the repository root) and the files written so far.
struct Output {
    std::filesystem::path root;
    std::vector<std::string> written; ///< paths relative to root, in the order written

    /// Writes `text` to root/`rel` (creating folders), byte for byte; throws std::runtime_error on failure.
    void write(const std::string& rel, const std::string& text);
};

// One function per bundled figure: writes its md5 files and its .af (the .def files are written by main).
void writeHumanoid(Output& out); ///< models/md5/humanoid/*, af/humanoid.af
void writeProps(Output& out);    ///< models/md5/props/props*, af/props.af
void writeLamp(Output& out);     ///< models/md5/props/lamp/*, af/lamp.af
void writeBuggy(Output& out);    ///< models/md5/props/buggy/*, af/buggy.af

} // namespace afb::gen
