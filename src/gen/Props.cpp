// afb gen's maxPropGrowth rule: a prop modelled onto a bone's own skin (a horned helmet, a crest, a blade skinned to
// the head or the hand) belongs to the bone's cluster, and it sits too close to the skin, with too many vertices,
// for strayFactor's median and deviation to single it out. What gives it away is what it does to the body: a
// minority of the bone's vertices, farther from the bone than most, that stretch the body far past what the rest
// of its vertices need. Those are left out of every body and reported (docs/cli.md, afb gen).
#include <algorithm>
#include <cmath>
#include <map>

#include "Fit.h"

namespace afb::gen::detail {
namespace {

// A prop is a minority of its bone's vertices: when more than this share lie past the radius, they are the bone's
// own skin (a bone whose cluster is a chain of blocks, a weapon's L-shaped body) and none is left out.
constexpr double kMaxPropShare = 0.25;

// One bone's far vertices (indices into the body's members) and what they do to the body.
struct Far {
    std::vector<std::size_t> members;
    double median = 0, limit = 0, nearest = INFINITY, farthest = 0, growth = 0;
};

// The far vertices of `joint` among `members` (indices `mine`), past propRadius times their median distance.
Far farVertices(const Rig& rig, const GenRules& rules, int joint, const std::vector<Member>& members,
                const std::vector<std::size_t>& mine) {
    std::vector<double> d;
    for (std::size_t i : mine)
        d.push_back(boneDistance(rig, joint, rig.surfaces[members[i].surface].vertices[members[i].vertex].position));
    Far far;
    far.median = median(d);
    far.limit = rules.propRadius * far.median;
    for (std::size_t k = 0; k < mine.size(); ++k)
        if (d[k] > far.limit) {
            far.members.push_back(mine[k]);
            far.nearest = std::min(far.nearest, d[k]);
            far.farthest = std::max(far.farthest, d[k]);
        }
    return far;
}

StrayVertices propReport(const Rig& rig, const BodyFit& body, int joint, std::size_t boneVertices, const Far& far) {
    StrayVertices r;
    r.rule = "maxPropGrowth";
    r.joint = rig.joints[static_cast<std::size_t>(joint)].name;
    r.body = rig.joints[static_cast<std::size_t>(body.head > 0 ? body.head : body.mainJoint)].name;
    r.vertices = static_cast<int>(far.members.size());
    r.boneVertices = static_cast<int>(boneVertices);
    r.nearestM = far.nearest * kMetresPerDoomUnit;
    r.farthestM = far.farthest * kMetresPerDoomUnit;
    r.medianM = far.median * kMetresPerDoomUnit;
    r.limitM = far.limit * kMetresPerDoomUnit;
    r.growth = far.growth;
    return r;
}

} // namespace

void trimProps(const Rig& rig, const GenRules& rules, const std::set<int>& own, const std::vector<int>& childHeads,
               double height, BodyFit& body, std::vector<Member>& members, VertexMask& stray,
               std::vector<StrayVertices>& report) {
    if (!(rules.maxPropGrowth > 0)) return;
    // The body's own vertices, per bone (indices into `members`).
    std::map<int, std::vector<std::size_t>> mine;
    for (std::size_t i = 0; i < members.size(); ++i)
        if (own.count(members[i].joint)) mine[members[i].joint].push_back(i);
    const auto pointsBut = [&](const std::vector<bool>& out) {
        std::vector<Eigen::Vector3d> points;
        for (const auto& [joint, indices] : mine)
            for (std::size_t i : indices)
                if (!out[i]) points.push_back(rig.surfaces[members[i].surface].vertices[members[i].vertex].position);
        return points;
    };
    const std::vector<bool> none(members.size(), false);
    double whole = -1; // fitted on demand: most bodies have no far vertex
    std::vector<bool> dropped(members.size(), false);
    for (const auto& [joint, indices] : mine) {
        if (indices.size() < kMinMedianVertices) continue;
        Far far = farVertices(rig, rules, joint, members, indices);
        if (far.members.empty() ||
            static_cast<double>(far.members.size()) > kMaxPropShare * static_cast<double>(indices.size()))
            continue;
        std::vector<bool> out(members.size(), false);
        for (std::size_t i : far.members) out[i] = true;
        std::vector<Eigen::Vector3d> rest = pointsBut(out);
        if (rest.size() < 4) continue;
        if (whole < 0) whole = fittedVolume(rig, body.head, childHeads, own, pointsBut(none), height, rules.shapes);
        const double trimmed = fittedVolume(rig, body.head, childHeads, own, std::move(rest), height, rules.shapes);
        if (!(whole > rules.maxPropGrowth * trimmed)) continue;
        far.growth = whole / trimmed;
        for (std::size_t i : far.members) {
            dropped[i] = true;
            stray[members[i].surface][members[i].vertex] = true;
        }
        report.push_back(propReport(rig, body, joint, indices.size(), far));
    }
    if (std::find(dropped.begin(), dropped.end(), true) == dropped.end()) return;
    std::vector<Member> staying;
    body.points.clear();
    for (std::size_t i = 0; i < members.size(); ++i)
        if (!dropped[i]) {
            staying.push_back(members[i]);
            body.points.push_back(rig.surfaces[members[i].surface].vertices[members[i].vertex].position);
        }
    members = std::move(staying);
}

} // namespace afb::gen::detail
