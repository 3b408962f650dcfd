// Self-collision pairs the joints keep apart (PairPruning.h). Everything is in model space at the load pose: the
// body held still sits at its load pose, and each enclosure is the set of places a body can reach relative to it.
#include "PairPruning.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <numbers>
#include <optional>

#include <BulletCollision/NarrowPhaseCollision/btGjkPairDetector.h>
#include <BulletCollision/NarrowPhaseCollision/btPointCollector.h>
#include <BulletCollision/NarrowPhaseCollision/btVoronoiSimplexSolver.h>
#include <btBulletCollisionCommon.h>

#include "afb/detail/Convert.h"
#include "afb/figure/Collision.h"

namespace afb::bullet::detail {
namespace {

using figure::Figure;
using figure::FigureConstraint;
using Vec = Eigen::Vector3d;

constexpr double kPi = std::numbers::pi;
/// Beyond this half angle a cone enclosure is looser than the sphere about its apex (tan grows fast): use the sphere.
constexpr double kMaxConeHalfAngleRad = 65.0 * kPi / 180.0;
/// Sides of the polygon circumscribing a cone's base.
constexpr int kConeSides = 16;
/// Largest step between the sampled angles of a hinge's sweep.
constexpr double kHingeStepRad = 4.0 * kPi / 180.0;

/// The convex hull of `points` grown by `inflationM` in every direction (a Minkowski sum with a ball).
struct Region {
    std::vector<Vec> points;
    double inflationM = 0;
};

Region bodyRegion(const figure::FigureBody& b) {
    Region r;
    for (const Vec& v : b.shape.vertices) r.points.push_back(b.loadPose.apply(v));
    return r;
}

double angleBetween(const Vec& a, const Vec& b) {
    return std::atan2(a.cross(b).norm(), a.dot(b)); // exact at small and large angles
}

/// Every point of `r` rotated about the line through `anchor` along unit `axis` by angles in [lo, hi].
Region hingeSweep(const Region& r, const Vec& anchor, const Vec& axis, double lo, double hi) {
    if (hi - lo >= 2 * kPi) {
        lo = -kPi;
        hi = kPi;
    }
    const int steps = std::max(1, static_cast<int>(std::ceil((hi - lo) / kHingeStepRad)));
    const double step = (hi - lo) / steps;
    Region out;
    double reach = 0;
    for (const Vec& p : r.points) reach = std::max(reach, (p - anchor).norm());
    for (int k = 0; k <= steps; ++k) {
        const Eigen::AngleAxisd turn(lo + step * k, axis);
        for (const Vec& p : r.points) out.points.push_back(anchor + turn * (p - anchor));
    }
    // Between two samples a point moves along an arc whose chord lies in the hull; the arc leaves the chord by
    // at most its sagitta.
    out.inflationM = r.inflationM + (reach + r.inflationM) * (1 - std::cos(step / 2));
    return out;
}

/// The sphere about `anchor` that holds `r` however it turns about the anchor.
Region sphereAbout(const Region& r, const Vec& anchor) {
    double reach = 0;
    for (const Vec& p : r.points) reach = std::max(reach, (p - anchor).norm());
    return {{anchor}, reach + r.inflationM};
}

/// `r` turned about `anchor` so that `movingDir` (fixed in the moving body) stays within `halfAngleRad` of
/// `refDir` (fixed in the body held still): within the cone about refDir of half angle halfAngle + the widest angle
/// of r's points from movingDir, cut at r's reach from the anchor; the sphere when that cone is wide.
Region swingCone(const Region& r, const Vec& anchor, const Vec& movingDir, const Vec& refDir, double halfAngleRad) {
    double reach = 0, widest = 0;
    for (const Vec& p : r.points) {
        const Vec d = p - anchor;
        const double dist = d.norm();
        if (dist <= r.inflationM) return sphereAbout(r, anchor);
        reach = std::max(reach, dist + r.inflationM);
        widest = std::max(widest, angleBetween(d, movingDir) + std::asin(r.inflationM / dist));
    }
    // Points within 90° of movingDir span a convex cone, so the hull of r's points stays within `widest` too.
    const double cone = halfAngleRad + widest;
    if (widest >= kPi / 2 || cone >= kMaxConeHalfAngleRad) return sphereAbout(r, anchor);
    // Apex at the anchor, height `reach` along refDir: holds every point within `reach` of the anchor whose angle
    // from refDir is at most `cone` (its axial part is at most reach, its radial part at most axial·tan(cone)).
    const Vec axis = refDir.normalized();
    const Vec u = axis.unitOrthogonal(), v = axis.cross(u);
    const double radius = reach * std::tan(cone) / std::cos(kPi / kConeSides); // the polygon circumscribes
    Region out;
    out.points.push_back(anchor);
    for (int k = 0; k < kConeSides; ++k) {
        const double a = 2 * kPi * k / kConeSides;
        out.points.push_back(anchor + axis * reach + radius * (std::cos(a) * u + std::sin(a) * v));
    }
    return out;
}

/// Where body `moving` (joined to the body held still by `c`) can take the set `r` fixed in it, within c's limit
/// widened by the slack.
Region hop(const Figure& f, const FigureConstraint& c, int moving, const Region& r, const PruneSlack& slack) {
    const figure::Transform& pose1 = f.bodies[static_cast<std::size_t>(c.body1)].loadPose;
    const figure::Transform& pose2 = f.bodies[static_cast<std::size_t>(c.body2)].loadPose;
    const Vec anchor = pose1.apply(c.frameInBody1.position);
    const bool movingIsBody1 = moving == c.body1;
    const figure::JointFreedom freedom = figure::freedomOf(c.type);
    if (freedom.anchor != figure::AnchorHold::Point) return sphereAbout(r, anchor); // not followed (pathBetween)
    switch (freedom.rotation) {
    case figure::RotationHold::All: return r;
    case figure::RotationHold::AllButAxis: {
        const Vec axis = (pose1.rotation * c.frameInBody1.rotation.col(2)).normalized();
        double lo = -kPi, hi = kPi;
        if (const auto* range = std::get_if<figure::HingeRange>(&c.limit)) {
            // φ is body1's turn relative to body2 about the axis; body2 relative to body1 turns by −φ.
            lo = movingIsBody1 ? range->lowerRad : -range->upperRad;
            hi = movingIsBody1 ? range->upperRad : -range->lowerRad;
            lo -= slack.angleRad;
            hi += slack.angleRad;
        }
        return hingeSweep(r, anchor, axis, lo, hi);
    }
    case figure::RotationHold::None:
    case figure::RotationHold::Twist: {
        if (const auto* cone = std::get_if<figure::ConeLimit>(&c.limit)) {
            const Vec shaft = pose1.rotation * cone->shaftInBody1, axis = pose2.rotation * cone->axisInBody2;
            return swingCone(r, anchor, movingIsBody1 ? shaft : axis, movingIsBody1 ? axis : shaft,
                             cone->halfAngleRad + slack.angleRad);
        }
        if (const auto* pyramid = std::get_if<figure::PyramidLimit>(&c.limit)) {
            // The shaft's angle from f: tan² = tan²(planar 1) + tan²(planar 2), each planar angle within its half
            // angle (PyramidLimit), so at most the angle of the pyramid's corner.
            const double h1 = pyramid->halfAngle1Rad + slack.angleRad, h2 = pyramid->halfAngle2Rad + slack.angleRad;
            if (h1 >= kPi / 2 || h2 >= kPi / 2) return sphereAbout(r, anchor);
            const double corner = std::atan(std::hypot(std::tan(h1), std::tan(h2)));
            const Vec shaft = pose1.rotation * pyramid->shaftInBody1,
                      f0 = pose2.rotation * pyramid->basisInBody2.col(0);
            return swingCone(r, anchor, movingIsBody1 ? shaft : f0, movingIsBody1 ? f0 : shaft, corner);
        }
        return sphereAbout(r, anchor);
    }
    }
    return sphereAbout(r, anchor);
}

/// The joints a pruning path may follow: every constraint between two bodies that keeps their anchors together.
bool followed(const FigureConstraint& c) {
    return c.body2 >= 0 && c.body1 != c.body2 && figure::freedomOf(c.type).anchor == figure::AnchorHold::Point;
}

/// A shortest path of followed joints from body `from` to body `to`: the bodies and the constraints between them
/// (constraint k joins bodies k and k + 1); empty when there is none.
std::pair<std::vector<int>, std::vector<int>> pathBetween(const Figure& f, int from, int to) {
    const int n = static_cast<int>(f.bodies.size());
    std::vector<int> via(static_cast<std::size_t>(n), -1), prev(static_cast<std::size_t>(n), -1);
    std::vector<bool> seen(static_cast<std::size_t>(n), false);
    std::deque<int> queue{from};
    seen[static_cast<std::size_t>(from)] = true;
    while (!queue.empty()) {
        const int b = queue.front();
        queue.pop_front();
        if (b == to) break;
        for (std::size_t k = 0; k < f.constraints.size(); ++k) {
            const FigureConstraint& c = f.constraints[k];
            if (!followed(c) || (c.body1 != b && c.body2 != b)) continue;
            const int other = c.body1 == b ? c.body2 : c.body1;
            if (seen[static_cast<std::size_t>(other)]) continue;
            seen[static_cast<std::size_t>(other)] = true;
            via[static_cast<std::size_t>(other)] = static_cast<int>(k);
            prev[static_cast<std::size_t>(other)] = b;
            queue.push_back(other);
        }
    }
    if (!seen[static_cast<std::size_t>(to)]) return {};
    std::vector<int> bodies{to}, joints;
    for (int b = to; b != from; b = prev[static_cast<std::size_t>(b)]) {
        joints.push_back(via[static_cast<std::size_t>(b)]);
        bodies.push_back(prev[static_cast<std::size_t>(b)]);
    }
    std::reverse(bodies.begin(), bodies.end());
    std::reverse(joints.begin(), joints.end());
    return {bodies, joints};
}

/// Distance between two regions (GJK on their hulls, the inflations as margins), or nullopt when they overlap.
std::optional<double> distance(const Region& a, const Region& b) {
    btConvexHullShape ha, hb;
    for (const Vec& p : a.points) ha.addPoint(toBt(p), false);
    for (const Vec& p : b.points) hb.addPoint(toBt(p), false);
    ha.recalcLocalAabb();
    hb.recalcLocalAabb();
    ha.setMargin(static_cast<btScalar>(a.inflationM));
    hb.setMargin(static_cast<btScalar>(b.inflationM));
    btVoronoiSimplexSolver simplex;
    btGjkPairDetector gjk(&ha, &hb, &simplex, nullptr);
    btGjkPairDetector::ClosestPointInput input;
    input.m_transformA.setIdentity();
    input.m_transformB.setIdentity();
    btPointCollector result;
    gjk.getClosestPoints(input, result, nullptr);
    if (!result.m_hasResult) return std::nullopt;
    return static_cast<double>(result.m_distance);
}

} // namespace

std::vector<std::pair<int, int>> unreachablePairs(const Figure& f, const PruneSlack& slack) {
    std::vector<std::pair<int, int>> out;
    for (const auto& [i, j] : figure::selfCollisionPairs(f)) {
        const auto [bodies, joints] = pathBetween(f, i, j);
        if (bodies.size() < 3) continue; // no path, or a joint that does not keep them apart
        const std::size_t n = joints.size();
        // Hold each body of the path still in turn: the near side's enclosure grows hop by hop from body i, the
        // far side's from body j.
        std::vector<Region> fromI{bodyRegion(f.bodies[static_cast<std::size_t>(i)])};
        for (std::size_t k = 0; k < n; ++k)
            fromI.push_back(hop(f, f.constraints[static_cast<std::size_t>(joints[k])], bodies[k], fromI.back(), slack));
        Region fromJ = bodyRegion(f.bodies[static_cast<std::size_t>(j)]);
        bool apart = false;
        for (std::size_t m = n; !apart; --m) { // body m held still
            const std::optional<double> d = distance(fromI[m], fromJ);
            apart = d && *d > slack.distanceM;
            if (m == 0) break;
            fromJ = hop(f, f.constraints[static_cast<std::size_t>(joints[m - 1])], bodies[m], fromJ, slack);
        }
        if (apart) out.emplace_back(i, j);
    }
    return out;
}

} // namespace afb::bullet::detail
