// Findings checked on the built figure at its load pose: limits and spring lengths that exclude it, and id's
// "behave weird or explode" list.
#include <algorithm>
#include <map>

#include "FigureBuilder.h"
#include "afb/detail/DoomMath.h"
#include "afb/figure/Collision.h"
#include "afb/figure/Limits.h"

namespace afb::figure::detail {

// A limit the load pose already exceeds is enforced from the first step: the engine pushes the joint in at
// once (docs/format.md §4.3, §4.5). The excess is measured as the drop metrics measure it (Limits.h), on the
// built frames.
void Builder::lintLimitAtLoadPose(const FigureConstraint& c, const std::string& what) {
    auto rotation = [&](int body) -> Matrix3d {
        if (body < 0) return Matrix3d::Identity(); // a world constraint's data is in model space
        return m_figure.bodies[static_cast<std::size_t>(body)].loadPose.rotation;
    };
    const Matrix3d body1 = rotation(c.body1), body2 = rotation(c.body2);
    const double excess = limitExcessRad(c, body1, body2);
    auto deg = [](double rad) { return fmt(rad / kRadPerDeg); };
    if (const auto* cone = std::get_if<ConeLimit>(&c.limit); cone && excess > 1e-6)
        warning(c.location, what + ": the shaft starts " + deg(coneAngleRad(*cone, body1, body2)) +
                                " deg from the cone axis, outside the half-angle " + deg(cone->halfAngleRad) +
                                " deg: it is pushed in at once");
    if (const auto* pyramid = std::get_if<PyramidLimit>(&c.limit); pyramid && excess > 1e-6) {
        const Eigen::Vector2d a = pyramidPlanarAnglesRad(*pyramid, body1, body2);
        warning(c.location, what + ": the shaft starts outside the pyramid (" + deg(a.x()) + ", " + deg(a.y()) +
                                " deg from its axis; limits " + deg(pyramid->halfAngle1Rad) + ", " +
                                deg(pyramid->halfAngle2Rad) + " deg): it is pushed in at once");
    }
    if (const auto* hinge = std::get_if<HingeRange>(&c.limit); hinge && excess > 1e-9)
        warning(c.location, what + ": the limit [" + deg(hinge->lowerRad) + ", " + deg(hinge->upperRad) +
                                "] deg excludes the load pose (0 deg): the joint is pushed into range at "
                                "once");
}

// A spring whose load-pose length lies outside [minLength, maxLength] meets its length row at the first step,
// which moves the bodies by the whole excess at once (§4.7).
void Builder::lintSpringAtLoadPose(const FigureConstraint& c, double lengthM, const std::string& what) {
    const SpringParams& sp = c.spring;
    const bool tooShort = lengthM<sp.minLengthM, tooLong = sp.maxLengthM> 0 && lengthM > sp.maxLengthM;
    if (!tooShort && !tooLong) return;
    warning(c.location,
            what + ": the anchors start " + fmt(lengthM) + " m apart, " +
                (tooShort ? "below minLength " + fmt(sp.minLengthM) : "above maxLength " + fmt(sp.maxLengthM)) +
                " m: the length row moves the bodies by the difference at once");
}

void Builder::checkFigure() {
    // Names that differ only in case merge at load (§1.8).
    auto caseClash = [&](auto&& items, const char* what) {
        std::map<std::string, std::string> seen;
        for (const auto& it : items) {
            const auto [pos, fresh] = seen.emplace(lower(it.name), it.name);
            if (!fresh && pos->second != it.name)
                error(it.location, std::string(what) + " '" + it.name + "' differs only in case from '" + pos->second +
                                       "': the engine's lookup merges them");
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
            warning(b.location,
                    "body '" + b.name + "' has principal moments " + fmt(hi / lo) +
                        ":1 apart (more than 10:1): thin bodies spin unstably (figure::stabilizeMassProperties, "
                        "opt-in, clamps it)");
    }
    for (const FigureConstraint& c : m_figure.constraints) {
        if (c.body2 < 0) continue;
        const FigureBody& a = m_figure.bodies[static_cast<std::size_t>(c.body1)];
        const FigureBody& b = m_figure.bodies[static_cast<std::size_t>(c.body2)];
        const double ratio = std::max(a.massKg, b.massKg) / std::min(a.massKg, b.massKg);
        if (ratio > 10.0)
            warning(c.location,
                    std::string(toString(c.type)) + " '" + c.name + "' joins masses " + fmt(a.massKg) + " and " +
                        fmt(b.massKg) +
                        " (more than 10:1): the solver struggles with such ratios (figure::stabilizeMassProperties, "
                        "opt-in, evens them out)");
    }
    // Self-colliding pairs that overlap or touch at the load pose fight their joints from the first step (deeper than
    // the tolerance: bullet::RagdollAsset::overlappingPairs, exempt under Method::exemptOverlapping).
    const auto pairs = selfCollisionPairs(m_figure);
    for (const auto& [i, j] : pairs) {
        const FigureBody& a = m_figure.bodies[static_cast<std::size_t>(i)];
        const FigureBody& b = m_figure.bodies[static_cast<std::size_t>(j)];
        const double gap = separation(a, b);
        if (gap < -kTouchToleranceM)
            warning(b.location, "self-colliding bodies '" + a.name + "' and '" + b.name +
                                    "' overlap at the load pose (depth " + fmt(-gap * 1000) +
                                    " mm): their contact would fight the joints, so afbullet's methods exempt the "
                                    "pair from collision (method knob exempt-overlapping; the engine and legacy "
                                    "keep it)");
        else if (gap < kTouchToleranceM)
            warning(b.location, "self-colliding bodies '" + a.name + "' and '" + b.name + "' " +
                                    (gap < 0 ? "overlap" : "touch") + " at the load pose (" +
                                    (gap < 0 ? "depth " + fmt(-gap * 1000) : "gap " + fmt(gap * 1000)) +
                                    " mm): their contact will fight the joints");
    }
}

} // namespace afb::figure::detail
