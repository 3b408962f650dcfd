// Mass and inertia stabilisation (Stabilize.h).
#include "afb/figure/Stabilize.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace afb::figure {
namespace {

double pairRatio(const FigureBody& a, const FigureBody& b) {
    return std::max(a.massKg, b.massKg) / std::min(a.massKg, b.massKg);
}

std::string number(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.4g", v);
    return buf;
}

// A ratio a little above the bound still counts as within it (round-off of the redistribution).
constexpr double kSlack = 1.0 + 1e-9;

} // namespace

bool needsStabilizing(const Figure& figure, const StabilizeOptions& options) {
    for (const FigureConstraint& c : figure.constraints)
        if (c.body2 >= 0 && pairRatio(figure.bodies[static_cast<std::size_t>(c.body1)],
                                      figure.bodies[static_cast<std::size_t>(c.body2)]) > options.maxMassRatio * kSlack)
            return true;
    for (const FigureBody& b : figure.bodies)
        if (b.inertiaKgM2.maxCoeff() > options.maxInertiaRatio * kSlack * b.inertiaKgM2.minCoeff()) return true;
    return false;
}

Figure stabilizeMassProperties(const Figure& figure, const StabilizeOptions& options, StabilizeReport* report) {
    Figure out = figure;
    const double maxRatio = std::max(1.0, options.maxMassRatio);
    // Gauss–Seidel over the pairs: each pair over the bound is brought exactly to it (heavy = ratio × light, same
    // sum); a few sweeps settle chains, where evening one pair unbalances its neighbour.
    for (int sweep = 0; sweep < 8; ++sweep) {
        bool moved = false;
        for (const FigureConstraint& c : out.constraints) {
            if (c.body2 < 0 || c.type == JointType::Spring) continue;
            FigureBody& a = out.bodies[static_cast<std::size_t>(c.body1)];
            FigureBody& b = out.bodies[static_cast<std::size_t>(c.body2)];
            if (pairRatio(a, b) <= maxRatio * kSlack) continue;
            FigureBody& heavy = a.massKg > b.massKg ? a : b;
            FigureBody& light = a.massKg > b.massKg ? b : a;
            const double sum = heavy.massKg + light.massKg;
            light.massKg = sum / (1.0 + maxRatio);
            heavy.massKg = sum - light.massKg;
            moved = true;
        }
        if (!moved) break;
    }
    const double maxInertia = std::max(1.0, options.maxInertiaRatio);
    for (std::size_t i = 0; i < out.bodies.size(); ++i) {
        FigureBody& b = out.bodies[i];
        const FigureBody& before = figure.bodies[i];
        const double scale = b.massKg / before.massKg;
        b.inertiaKgM2 = before.inertiaKgM2 * scale;
        const double floor = b.inertiaKgM2.maxCoeff() / maxInertia;
        const bool raised = b.inertiaKgM2.minCoeff() < floor / kSlack;
        b.inertiaKgM2 = b.inertiaKgM2.cwiseMax(floor);
        if (!report || (scale == 1.0 && !raised)) continue;
        std::string line = b.name + ":";
        if (scale != 1.0) line += " mass " + number(before.massKg) + " -> " + number(b.massKg) + " kg;";
        if (raised)
            line += " principal moments raised to 1/" + number(maxInertia) + " of the largest (" +
                    number(before.inertiaKgM2.minCoeff() * scale) + " -> " + number(floor) + " kg·m²);";
        line.pop_back();
        report->changes.push_back(line);
    }
    return out;
}

} // namespace afb::figure
