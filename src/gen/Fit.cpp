// afb gen's bodies: which bones share a body, and the smallest of Doom's shapes that holds each body's vertices.
#include "Fit.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <regex>

#include <Eigen/Eigenvalues>

#include "afb/figure/Polytope.h"

namespace afb::gen::detail {
namespace {

bool matchesAny(const std::vector<std::regex>& res, const std::string& name) {
    return std::any_of(res.begin(), res.end(), [&](const std::regex& re) { return std::regex_search(name, re); });
}

std::vector<std::regex> compile(const std::vector<std::string>& patterns) {
    std::vector<std::regex> out;
    for (const std::string& p : patterns) out.emplace_back(p, std::regex::ECMAScript | std::regex::icase);
    return out;
}

double extentOf(const std::vector<Eigen::Vector3d>& points) {
    if (points.empty()) return 0;
    Eigen::Vector3d lo = points[0], hi = points[0];
    for (const auto& p : points) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
    }
    return (hi - lo).maxCoeff();
}

} // namespace

bool bodySized(const std::vector<Eigen::Vector3d>& points, double boneLength, int minVertices, double minSpan) {
    return static_cast<int>(points.size()) >= minVertices && std::max(extentOf(points), boneLength) >= minSpan;
}

namespace {

// Principal axes of a point cloud (columns, by decreasing variance), a right-handed basis.
Eigen::Matrix3d principalAxes(const std::vector<Eigen::Vector3d>& points) {
    if (points.size() < 2) return Eigen::Matrix3d::Identity();
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& p : points) mean += p;
    mean /= static_cast<double>(points.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const auto& p : points) cov += (p - mean) * (p - mean).transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(cov);
    Eigen::Matrix3d axes;
    for (int i = 0; i < 3; ++i) axes.col(i) = solver.eigenvectors().col(2 - i);
    if (axes.determinant() < 0) axes.col(2) = -axes.col(2);
    return axes;
}

// A unit vector perpendicular to `d`, as close as possible to `hint`.
Eigen::Vector3d perpendicular(const Eigen::Vector3d& d, const Eigen::Vector3d& hint) {
    Eigen::Vector3d p = hint - d * d.dot(hint);
    if (p.norm() < 1e-6) p = d.unitOrthogonal();
    return p.normalized();
}

// The smallest uniform scale s about the origin for which every point lies inside `polytope` scaled by s.
double enclosingScale(const figure::Polytope& polytope, const std::vector<Eigen::Vector3d>& localPoints) {
    const auto planes = figure::facePlanes(polytope.vertices, polytope.faces);
    double s = 0;
    for (const auto& p : localPoints)
        for (const auto& plane : planes)
            if (plane.offset > 1e-12) s = std::max(s, plane.normal.dot(p) / plane.offset);
    return s;
}

double boxVolume(const Eigen::Vector3d& half) { return 8 * half.x() * half.y() * half.z(); }

// Fits every allowed shape in the body's frame and keeps the one of least volume that holds all its points.
void fitShape(BodyFit& body, const std::vector<std::string>& shapes) {
    std::vector<Eigen::Vector3d> local;
    local.reserve(body.points.size());
    for (const auto& p : body.points) local.push_back(body.frame.transpose() * (p - body.centre));
    const Eigen::Vector3d half = body.halfExtents;
    double best = std::numeric_limits<double>::infinity();
    for (const std::string& kind : shapes) {
        double volume = 0;
        Eigen::Vector3d h = half;
        decl::ShapeKind shape = decl::ShapeKind::Box;
        int sides = 0;
        double boneLength = 0, boneWidth = 0;
        if (kind == "box") {
            volume = boxVolume(h);
        } else if (kind == "cylinder") {
            // A prism along Z: scale the cross-section only, the end faces are the bounds'.
            shape = decl::ShapeKind::Cylinder;
            sides = 8;
            std::vector<Eigen::Vector3d> flat;
            for (const auto& p : local) flat.emplace_back(p.x(), p.y(), 0);
            const auto build = figure::makeCylinder(-Eigen::Vector3d(half.x(), half.y(), 1),
                                                    Eigen::Vector3d(half.x(), half.y(), 1), sides);
            const double s = std::max(enclosingScale(build.polytope, flat), 1e-9);
            h = Eigen::Vector3d(half.x() * s, half.y() * s, half.z());
            volume = sides / 2.0 * std::sin(2 * M_PI / sides) * h.x() * h.y() * 2 * h.z();
        } else if (kind == "octahedron" || kind == "dodecahedron") {
            const bool octa = kind == "octahedron";
            shape = octa ? decl::ShapeKind::Octahedron : decl::ShapeKind::Dodecahedron;
            const auto poly = octa ? figure::makeOctahedron(-half, half) : figure::makeDodecahedron(-half, half);
            const double s = std::max(enclosingScale(poly, local), 1e-9);
            h = half * s;
            volume = (octa ? 1.0 / 6.0 : (3 * std::sqrt(5.0) - 5) / 4) * boxVolume(h);
        } else if (kind == "bone") {
            // The bone's own frame (figure::boneFrame along the fit's Z) about the centre.
            shape = decl::ShapeKind::Bone;
            const Eigen::Vector3d d = body.frame.col(2);
            const Eigen::Matrix3d boneAxes = figure::boneFrame(body.centre - d, body.centre + d);
            std::vector<Eigen::Vector3d> boneLocal;
            for (const auto& p : body.points) boneLocal.push_back(boneAxes.transpose() * (p - body.centre));
            const double l0 = 2 * half.z(), w0 = 2 * std::max(half.x(), half.y());
            const double s = std::max(enclosingScale(figure::makeBone(l0, w0), boneLocal), 1e-9);
            boneLength = l0 * s;
            boneWidth = w0 * s;
            volume = boneWidth * boneWidth * boneLength / 8;
        } else {
            continue;
        }
        if (volume < best) {
            best = volume;
            body.shape = shape;
            body.halfExtents = h;
            body.sides = sides;
            body.boneLength = boneLength;
            body.boneWidth = boneWidth;
            body.volume = volume;
        }
    }
}

} // namespace

// What fitting a grouping needs, per joint: its group's head, whether it is skipped, the vertices it owns, whether it
// was merged into its body for its size; and the vertices left out before fitting.
struct FitInput {
    const std::vector<int>& group;
    const std::vector<bool>& skipped;
    const std::vector<std::vector<Eigen::Vector3d>>& owned;
    const std::vector<bool>& mergedSmall;
    const VertexMask& stray;
    int minVertices; // the fewest vertices of a body of its own (leastVertices)
};

// Fits one body per group, and one per branch maxMergeGrowth cuts that is big enough for it; `stray` and `report`
// take the vertices maxPropGrowth and maxMergeGrowth leave out.
std::vector<BodyFit> fitGroups(const Rig& rig, const GenRules& rules, const FitInput& in, VertexMask& stray,
                               std::vector<StrayVertices>& report);

// The model's height as fitting sees it: modelHeight without the stray vertices.
double fittedHeight(const Rig& rig, const VertexMask& stray) {
    std::vector<Eigen::Vector3d> points;
    for (std::size_t si = 0; si < rig.surfaces.size(); ++si)
        for (std::size_t vi = 0; vi < rig.surfaces[si].vertices.size(); ++vi)
            if (!stray[si][vi]) points.push_back(rig.surfaces[si].vertices[vi].position);
    if (points.empty())
        for (const auto& j : rig.joints) points.push_back(j.bind.position);
    return std::max(extentOf(points), 1e-6);
}

namespace {

// Each vertex counts for the joint that weighs it most, unless that joint is skipped or the vertex is stray.
struct Ownership {
    std::vector<std::vector<Eigen::Vector3d>> owned; // per joint, the positions of the vertices it owns
    std::vector<bool> skipped;                       // per joint, matched by the rules' skip list
    std::size_t vertexCount = 0;                     // vertices that are not stray
};

Ownership ownVertices(const Rig& rig, const std::vector<std::regex>& skipRe, const VertexMask& stray) {
    const std::size_t n = rig.joints.size();
    Ownership out;
    out.owned.resize(n);
    out.skipped.assign(n, false);
    for (std::size_t j = 0; j < n; ++j) out.skipped[j] = matchesAny(skipRe, rig.joints[j].name);
    for (std::size_t si = 0; si < rig.surfaces.size(); ++si)
        for (std::size_t vi = 0; vi < rig.surfaces[si].vertices.size(); ++vi) {
            const RigVertex& v = rig.surfaces[si].vertices[vi];
            if (stray[si][vi]) continue;
            ++out.vertexCount;
            const auto top =
                std::max_element(v.influences.begin(), v.influences.end(),
                                 [](const RigInfluence& a, const RigInfluence& b) { return a.weight < b.weight; });
            if (top != v.influences.end() && !out.skipped[static_cast<std::size_t>(top->joint)])
                out.owned[static_cast<std::size_t>(top->joint)].push_back(v.position);
        }
    return out;
}

// The fewest vertices a group needs for a body of its own (minVertices, minVertexFraction).
int leastVertices(const GenRules& rules, std::size_t vertexCount) {
    return std::max(rules.minVertices,
                    static_cast<int>(std::ceil(rules.minVertexFraction * static_cast<double>(vertexCount))));
}

// Which joint heads each joint's body (group[j]), as the rules and the sizes decide before fitting.
struct Grouping {
    const Rig& rig;
    const Ownership& own;
    std::vector<int> group;
    std::vector<bool> kept;        // per joint, matched by the rules' keep list: heads its own body whatever its size
    std::vector<bool> mergedSmall; // per joint, merged into an ancestor's body for its size (maxMergeGrowth)

    int joints() const { return static_cast<int>(group.size()); }
    int parentOf(int j) const { return rig.joints[static_cast<std::size_t>(j)].parent; }
    std::vector<Eigen::Vector3d> pointsOf(int head) const {
        std::vector<Eigen::Vector3d> pts;
        for (int j = 0; j < joints(); ++j)
            if (group[static_cast<std::size_t>(j)] == head)
                pts.insert(pts.end(), own.owned[static_cast<std::size_t>(j)].begin(),
                           own.owned[static_cast<std::size_t>(j)].end());
        return pts;
    }
    void mergeInto(int from, int into) {
        for (int& g : group)
            if (g == from) g = into;
    }
    // The same for a group too small for a body of its own: its joints are marked.
    void mergeSmall(int from, int into) {
        for (std::size_t j = 0; j < group.size(); ++j)
            if (group[j] == from) mergedSmall[j] = true;
        mergeInto(from, into);
    }
    // Head to the farthest joint below it in its group.
    double boneLength(int head) const {
        double length = 0;
        for (int j = head + 1; j < joints(); ++j) {
            const int parent = parentOf(j);
            if (parent >= 0 && group[static_cast<std::size_t>(parent)] == head)
                length = std::max(length, (rig.joints[static_cast<std::size_t>(j)].bind.position -
                                           rig.joints[static_cast<std::size_t>(head)].bind.position)
                                              .norm());
        }
        return length;
    }
};

// Named merges first (parents before children), then small groups into their parent's, children before parents so
// that what they gather counts (a group's size is the larger of its vertices' extent and its bone's length), then
// the base body (joint 0's) takes in its largest child group while it has too few vertices (the pelvis: Doom's base
// body, docs/format.md §2.4).
Grouping groupJoints(const Rig& rig, const GenRules& rules, const Ownership& own, double height) {
    const auto mergeRe = compile(rules.merge);
    const auto keepRe = compile(rules.keep);
    const int n = static_cast<int>(rig.joints.size());
    Grouping g{rig, own, std::vector<int>(static_cast<std::size_t>(n)), std::vector<bool>(static_cast<std::size_t>(n)),
               std::vector<bool>(static_cast<std::size_t>(n))};
    for (int j = 0; j < n; ++j) {
        const std::string& name = rig.joints[static_cast<std::size_t>(j)].name;
        const int parent = g.parentOf(j);
        g.kept[static_cast<std::size_t>(j)] = matchesAny(keepRe, name);
        g.group[static_cast<std::size_t>(j)] = j;
        if (parent >= 0 && !g.kept[static_cast<std::size_t>(j)] &&
            (matchesAny(mergeRe, name) || own.skipped[static_cast<std::size_t>(j)]))
            g.group[static_cast<std::size_t>(j)] = g.group[static_cast<std::size_t>(parent)];
    }
    const int minVertices = leastVertices(rules, own.vertexCount);
    for (int j = n - 1; j >= 1; --j) {
        if (g.group[static_cast<std::size_t>(j)] != j || g.kept[static_cast<std::size_t>(j)]) continue;
        if (!bodySized(g.pointsOf(j), g.boneLength(j), minVertices, rules.minBodyFraction * height))
            g.mergeSmall(j, g.group[static_cast<std::size_t>(g.parentOf(j))]);
    }
    while (static_cast<int>(g.pointsOf(0).size()) < std::max(minVertices, 1)) {
        int bestChild = -1;
        std::size_t bestCount = 0;
        for (int j = 1; j < n; ++j)
            if (g.group[static_cast<std::size_t>(j)] == j && g.group[static_cast<std::size_t>(g.parentOf(j))] == 0) {
                const std::size_t count = g.pointsOf(j).size();
                if (bestChild < 0 || count > bestCount) {
                    bestChild = j;
                    bestCount = count;
                }
            }
        if (bestChild < 0) break;
        g.mergeInto(bestChild, 0);
    }
    return g;
}

// The body whose volume is smallest against its neighbours, when under minVolumeRatio (−1: none). Against its
// parent, when everything hanging from it is small too (a leaf, a braid of helper bones); a link between two large
// bodies against the smaller of them (a thin waist between pelvis and chest).
int smallestBody(const std::vector<BodyFit>& bodies, const std::vector<bool>& kept, double minVolumeRatio) {
    int worst = -1;
    double worstRatio = minVolumeRatio;
    for (std::size_t i = 1; i < bodies.size(); ++i) {
        const BodyFit& b = bodies[i];
        if (b.parentBody < 0 || b.promoted || kept[static_cast<std::size_t>(b.head)]) continue;
        const double parentVolume = bodies[static_cast<std::size_t>(b.parentBody)].volume;
        double largestChild = 0;
        for (const BodyFit& c : bodies)
            if (c.parentBody == static_cast<int>(i)) largestChild = std::max(largestChild, c.volume);
        double ratio = std::numeric_limits<double>::infinity();
        if (largestChild < minVolumeRatio * parentVolume) ratio = b.volume / std::max(parentVolume, 1e-12);
        if (largestChild > 0) ratio = std::min(ratio, b.volume / std::max(std::min(parentVolume, largestChild), 1e-12));
        if (ratio < worstRatio) {
            worstRatio = ratio;
            worst = static_cast<int>(i);
        }
    }
    return worst;
}

} // namespace

std::vector<BodyFit> fitBodies(const Rig& rig, const GenRules& rules, VertexMask& stray,
                               std::vector<StrayVertices>& report) {
    const Ownership own = ownVertices(rig, compile(rules.skip), stray);
    Grouping grouping = groupJoints(rig, rules, own, fittedHeight(rig, stray));
    // Fit, then merge the body of least relative volume into its parent while that ratio is under minVolumeRatio
    // (the figure layer warns from 10:1 mass ratios across a joint; one density makes mass ratios volume ratios).
    for (;;) {
        VertexMask leftOut = stray;
        std::vector<StrayVertices> grown;
        std::vector<BodyFit> bodies = fitGroups(rig, rules,
                                                {grouping.group, own.skipped, own.owned, grouping.mergedSmall, stray,
                                                 leastVertices(rules, own.vertexCount)},
                                                leftOut, grown);
        const int worst = smallestBody(bodies, grouping.kept, rules.minVolumeRatio);
        if (worst < 0) {
            stray = std::move(leftOut);
            report.insert(report.end(), grown.begin(), grown.end());
            return bodies;
        }
        const BodyFit& b = bodies[static_cast<std::size_t>(worst)];
        grouping.mergeSmall(b.head, bodies[static_cast<std::size_t>(b.parentBody)].head);
    }
}

BoneAxis boneAxis(const Rig& rig, int head, const std::vector<int>& childHeads, const std::vector<int>& joints) {
    BoneAxis axis;
    axis.head = rig.joints[static_cast<std::size_t>(head)].bind.position;
    if (head == 0) return axis;
    if (childHeads.size() == 1) {
        axis.tail = rig.joints[static_cast<std::size_t>(childHeads[0])].bind.position;
        axis.toTail = true;
    } else if (childHeads.empty()) {
        double far = 0;
        for (int j : joints) {
            const Eigen::Vector3d p = rig.joints[static_cast<std::size_t>(j)].bind.position;
            if ((p - axis.head).norm() > far) {
                far = (p - axis.head).norm();
                axis.tail = p;
            }
        }
    }
    return axis;
}

// Frames: Z along the bone (toward the one child body, else the farthest joint of the group), X and Y the principal
// axes of the vertices across it; without a bone, the principal axes alone.
void fitFrame(BodyFit& b, const BoneAxis& axis, double height, const std::vector<std::string>& shapes) {
    const Eigen::Vector3d& head = axis.head;
    const Eigen::Matrix3d pca = principalAxes(b.points);
    Eigen::Vector3d d = pca.col(0);
    if (axis.tail && (*axis.tail - head).norm() > 1e-3 * height) d = (*axis.tail - head).normalized();
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& p : b.points) mean += p;
    mean /= static_cast<double>(b.points.size());
    if (!axis.tail && d.dot(mean - head) < 0) d = -d;
    const Eigen::Vector3d x = perpendicular(d, pca.col(0).cross(d).norm() > 0.3 ? pca.col(0) : pca.col(1));
    b.frame.col(0) = x;
    b.frame.col(1) = d.cross(x);
    b.frame.col(2) = d;
    // Bounds in that frame: the vertices, and along the bone from the head to the child's head.
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (const auto& p : b.points) {
        const Eigen::Vector3d q = b.frame.transpose() * (p - head);
        lo = lo.cwiseMin(q);
        hi = hi.cwiseMax(q);
    }
    if (axis.tail && axis.toTail) {
        lo.z() = std::min(lo.z(), 0.0);
        hi.z() = std::max(hi.z(), d.dot(*axis.tail - head));
    }
    Eigen::Vector3d half = (hi - lo) / 2;
    const double thickness = std::max(0.02 * height, 0.15 * 2 * half.maxCoeff());
    for (int k = 0; k < 3; ++k) half(k) = std::max(half(k), thickness / 2);
    b.centre = head + b.frame * ((lo + hi) / 2);
    b.halfExtents = half;
    fitShape(b, shapes);
    b.direction = (b.centre - head).norm() > 1e-6 * height ? Eigen::Vector3d((b.centre - head).normalized()) : d;
}

namespace {

// A kept bone without vertices (a head modelled apart, as Doom's def_head): a cube a tenth of the model's height,
// beyond the joint along the bone from its parent, as eight corner points.
void addCubePoints(const Rig& rig, BodyFit& b, double height) {
    const Eigen::Vector3d head = rig.joints[static_cast<std::size_t>(b.head)].bind.position;
    Eigen::Vector3d d = Eigen::Vector3d::UnitZ();
    if (b.parentBody >= 0) {
        const Eigen::Vector3d from =
            rig.joints[static_cast<std::size_t>(rig.joints[static_cast<std::size_t>(b.head)].parent)].bind.position;
        if ((head - from).norm() > 1e-6 * height) d = (head - from).normalized();
    }
    const double side = 0.1 * height;
    b.frame.col(2) = d;
    b.frame.col(0) = perpendicular(d, Eigen::Vector3d::UnitX());
    b.frame.col(1) = d.cross(b.frame.col(0));
    b.centre = head + d * (side / 2);
    b.halfExtents = Eigen::Vector3d::Constant(side / 2);
    for (int k = 0; k < 8; ++k)
        b.points.push_back(b.centre + b.frame * Eigen::Vector3d(k & 1 ? side / 2 : -side / 2,
                                                                k & 2 ? side / 2 : -side / 2,
                                                                k & 4 ? side / 2 : -side / 2));
}

// Bodies in joint order of their heads (the base body first), each with its joints and its parent body.
std::vector<BodyFit> bodiesOf(const Rig& rig, const std::vector<int>& group, std::map<int, int>& bodyOfHead) {
    const int n = static_cast<int>(rig.joints.size());
    std::vector<BodyFit> bodies;
    for (int j = 0; j < n; ++j)
        if (group[static_cast<std::size_t>(j)] == j) {
            bodyOfHead[j] = static_cast<int>(bodies.size());
            BodyFit b;
            b.head = j;
            bodies.push_back(b);
        }
    for (int j = 0; j < n; ++j)
        bodies[static_cast<std::size_t>(bodyOfHead.at(group[static_cast<std::size_t>(j)]))].joints.push_back(j);
    for (BodyFit& b : bodies)
        if (b.head > 0)
            b.parentBody =
                bodyOfHead.at(group[static_cast<std::size_t>(rig.joints[static_cast<std::size_t>(b.head)].parent)]);
    return bodies;
}

// A vertex is fitted by the body whose bones weigh it most together, when they weigh it at least the threshold
// (a vertex shared evenly between two bodies bends with both and belongs to neither's shape). Per body, its
// members: each vertex and the body's joint that weighs it most.
std::vector<std::vector<Member>> assignVertices(const Rig& rig, const GenRules& rules, const std::vector<int>& group,
                                                const std::vector<bool>& skipped, const std::map<int, int>& bodyOfHead,
                                                const VertexMask& stray, std::vector<BodyFit>& bodies) {
    std::vector<std::vector<Member>> members(bodies.size());
    const auto bodyOf = [&](int joint) { return bodyOfHead.at(group[static_cast<std::size_t>(joint)]); };
    for (std::size_t si = 0; si < rig.surfaces.size(); ++si)
        for (std::size_t vi = 0; vi < rig.surfaces[si].vertices.size(); ++vi) {
            const RigVertex& v = rig.surfaces[si].vertices[vi];
            if (stray[si][vi]) continue;
            std::map<int, double> byBody;
            for (const RigInfluence& in : v.influences)
                if (!skipped[static_cast<std::size_t>(in.joint)]) byBody[bodyOf(in.joint)] += in.weight;
            const auto top = std::max_element(byBody.begin(), byBody.end(),
                                              [](const auto& a, const auto& b) { return a.second < b.second; });
            if (top == byBody.end() || top->second < rules.weightThreshold) continue;
            const auto body = static_cast<std::size_t>(top->first);
            int joint = -1;
            double weight = 0;
            for (const RigInfluence& in : v.influences)
                if (!skipped[static_cast<std::size_t>(in.joint)] && bodyOf(in.joint) == top->first &&
                    in.weight > weight) {
                    joint = in.joint;
                    weight = in.weight;
                }
            bodies[body].points.push_back(v.position);
            members[body].push_back({si, vi, joint});
        }
    return members;
}

// `extra` put among `bodies` in the joint order of their heads, every parentBody index renumbered to match.
void insertBodies(std::vector<BodyFit>& bodies, std::vector<BodyFit> extra) {
    if (extra.empty()) return;
    for (BodyFit& b : extra) bodies.push_back(std::move(b));
    std::vector<std::size_t> order(bodies.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return bodies[a].head < bodies[b].head; });
    std::vector<int> newIndex(bodies.size());
    for (std::size_t k = 0; k < order.size(); ++k) newIndex[order[k]] = static_cast<int>(k);
    std::vector<BodyFit> sorted;
    for (std::size_t i : order) {
        sorted.push_back(std::move(bodies[i]));
        if (sorted.back().parentBody >= 0)
            sorted.back().parentBody = newIndex[static_cast<std::size_t>(sorted.back().parentBody)];
    }
    bodies = std::move(sorted);
}

} // namespace

std::vector<BodyFit> fitGroups(const Rig& rig, const GenRules& rules, const FitInput& in, VertexMask& stray,
                               std::vector<StrayVertices>& report) {
    const double height = fittedHeight(rig, in.stray);
    std::map<int, int> bodyOfHead;
    std::vector<BodyFit> bodies = bodiesOf(rig, in.group, bodyOfHead);
    std::vector<std::vector<Member>> members =
        assignVertices(rig, rules, in.group, in.skipped, bodyOfHead, in.stray, bodies);
    for (BodyFit& b : bodies) {
        std::size_t most = 0;
        b.mainJoint = b.head;
        for (int j : b.joints)
            if (in.owned[static_cast<std::size_t>(j)].size() > most) {
                most = in.owned[static_cast<std::size_t>(j)].size();
                b.mainJoint = j;
            }
    }
    std::vector<BodyFit> promoted;
    for (std::size_t bi = 0; bi < bodies.size(); ++bi) {
        BodyFit& b = bodies[bi];
        std::vector<int> childHeads;
        for (const BodyFit& c : bodies)
            if (c.parentBody == static_cast<int>(bi)) childHeads.push_back(c.head);
        trimProps(rig, rules, ownJoints(rig, in.mergedSmall, childHeads, b), childHeads, height, b, members[bi], stray,
                  report);
        std::vector<int> axisJoints;
        std::vector<CutBranch> cut =
            limitMergeGrowth(rig, rules, in.mergedSmall, childHeads, height, b, members[bi], axisJoints);
        settleBranches(rig, rules, {in.minVertices, height, in.owned, in.skipped}, std::move(cut), static_cast<int>(bi),
                       b, promoted, stray, report);
        if (b.points.size() < 4) addCubePoints(rig, b, height);
        fitFrame(b, boneAxis(rig, b.head, childHeads, axisJoints), height, rules.shapes);
    }
    insertBodies(bodies, std::move(promoted));
    return bodies;
}

} // namespace afb::gen::detail

namespace afb::gen {

double modelHeight(const Rig& rig) {
    std::vector<Eigen::Vector3d> points;
    for (const auto& s : rig.surfaces)
        for (const auto& v : s.vertices) points.push_back(v.position);
    if (points.empty())
        for (const auto& j : rig.joints) points.push_back(j.bind.position);
    return detail::extentOf(points);
}

} // namespace afb::gen
