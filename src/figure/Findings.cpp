// Figure-wide findings: id's "behave weird or explode" list, checked on the built figure at its load pose.
#include <algorithm>
#include <map>

#include "FigureBuilder.h"
#include "afb/figure/Collision.h"

namespace afb::figure::detail {

void Builder::checkFigure() {
    // Names that differ only in case merge at load (§1.8).
    auto caseClash = [&](auto&& items, const char* what) {
        std::map<std::string, std::string> seen;
        for (const auto& it : items) {
            const auto [pos, fresh] = seen.emplace(lower(it.name), it.name);
            if (!fresh && pos->second != it.name)
                error(it.location, std::string(what) + " '" + it.name + "' differs only in case from '" +
                                       pos->second + "': the engine's lookup merges them");
        }
    };
    caseClash(m_decl.bodies, "body");
    caseClash(m_decl.constraints, "constraint");

    for (const FigureBody& b : m_figure.bodies) {
        if (b.massKg < 1.0 || b.massKg > 100.0)
            warning(b.location, "body '" + b.name + "' has mass " + fmt(b.massKg) +
                                    ", outside [1, 100]: bodies that light or heavy make figures unstable");
        const double hi = b.inertiaKgM2.maxCoeff(), lo = b.inertiaKgM2.minCoeff();
        if (lo > 0 && hi / lo > 10.0)
            warning(b.location, "body '" + b.name + "' has principal moments " + fmt(hi / lo) +
                                    ":1 apart (more than 10:1): thin bodies spin unstably");
    }
    for (const FigureConstraint& c : m_figure.constraints) {
        if (c.body2 < 0) continue;
        const FigureBody& a = m_figure.bodies[static_cast<std::size_t>(c.body1)];
        const FigureBody& b = m_figure.bodies[static_cast<std::size_t>(c.body2)];
        const double ratio = std::max(a.massKg, b.massKg) / std::min(a.massKg, b.massKg);
        if (ratio > 10.0)
            warning(c.location, std::string(toString(c.type)) + " '" + c.name + "' joins masses " +
                                    fmt(a.massKg) + " and " + fmt(b.massKg) +
                                    " (more than 10:1): the solver struggles with such ratios");
    }
    // Self-colliding pairs that overlap or touch at the load pose fight their joints from the first step.
    const auto pairs = selfCollisionPairs(m_figure);
    for (const auto& [i, j] : pairs) {
        const FigureBody& a = m_figure.bodies[static_cast<std::size_t>(i)];
        const FigureBody& b = m_figure.bodies[static_cast<std::size_t>(j)];
        const double gap = separation(a, b);
        if (gap < kTouchToleranceM)
            warning(b.location, "self-colliding bodies '" + a.name + "' and '" + b.name + "' " +
                                    (gap < 0 ? "overlap" : "touch") + " at the load pose (" +
                                    (gap < 0 ? "depth " + fmt(-gap * 1000) : "gap " + fmt(gap * 1000)) +
                                    " mm): their contact will fight the joints");
    }
}

} // namespace afb::figure::detail
