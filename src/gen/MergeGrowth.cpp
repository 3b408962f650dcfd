// afb gen's maxMergeGrowth rule: a bone too small for a body of its own joins an ancestor's body, but a braid, a
// strap or a plume hanging off that body would stretch its shape over everything the bone reaches. Such a bone's
// vertices join the body only while the body stays within GenRules::maxMergeGrowth of the volume fitted to its own
// bones; the rest are left out of every body and reported, as stray vertices are (docs/cli.md, afb gen).
#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "Fit.h"

namespace afb::gen::detail {
namespace {

// The volume of the body fitted to `points` with its axis from `joints`.
double fittedVolume(const Rig& rig, int head, const std::vector<int>& childHeads, const std::set<int>& joints,
                    std::vector<Eigen::Vector3d> points, double height, const std::vector<std::string>& shapes) {
    BodyFit trial;
    trial.head = head;
    trial.points = std::move(points);
    fitFrame(trial, boneAxis(rig, head, childHeads, std::vector<int>(joints.begin(), joints.end())), height, shapes);
    return trial.volume;
}

// The joint that names a body: its head's, or for the base body its joint with the most vertices.
const RigJoint& namingJoint(const Rig& rig, const BodyFit& body) {
    return rig.joints[static_cast<std::size_t>(body.head > 0 ? body.head : body.mainJoint)];
}

// The report of a bone left out of `body`, before its vertices are counted in (addPoint).
StrayVertices leftOutReport(const Rig& rig, const BodyFit& body, int joint, double growth) {
    StrayVertices r;
    r.joint = rig.joints[static_cast<std::size_t>(joint)].name;
    r.body = namingJoint(rig, body).name;
    r.growth = growth;
    r.nearestM = INFINITY;
    return r;
}

// One more vertex of a left-out branch: counted, and its distance from the joint that names the body.
void addPoint(StrayVertices& r, const Rig& rig, const BodyFit& body, const Member& m) {
    const double d =
        (rig.surfaces[m.surface].vertices[m.vertex].position - namingJoint(rig, body).bind.position).norm() *
        kMetresPerDoomUnit;
    ++r.vertices;
    ++r.boneVertices;
    r.nearestM = std::min(r.nearestM, d);
    r.farthestM = std::max(r.farthestM, d);
}

} // namespace

std::vector<int> limitMergeGrowth(const Rig& rig, const GenRules& rules, const std::vector<bool>& mergedSmall,
                                  const std::vector<int>& childHeads, double height, BodyFit& body,
                                  std::vector<Member>& members, VertexMask& stray, std::vector<StrayVertices>& report) {
    const auto parentOf = [&](int j) { return rig.joints[static_cast<std::size_t>(j)].parent; };
    // A merged bone between the body and a body hanging from it (a neck, a waist) is a link, not an attachment:
    // it counts as the body's own.
    std::set<int> links;
    for (int c : childHeads)
        for (int a = parentOf(c); a > 0 && mergedSmall[static_cast<std::size_t>(a)]; a = parentOf(a)) links.insert(a);
    const auto small = [&](int j) { return mergedSmall[static_cast<std::size_t>(j)] && !links.count(j); };
    std::set<int> own;
    for (int j : body.joints)
        if (!small(j)) own.insert(j);
    if (!(rules.maxMergeGrowth > 0) || own.size() == body.joints.size()) return body.joints;
    // The body's own vertices: those its other bones weigh most. Too few to fit a shape to, and the rule stands aside.
    std::map<int, std::vector<Eigen::Vector3d>> pointsOf;
    for (const Member& m : members) pointsOf[m.joint].push_back(rig.surfaces[m.surface].vertices[m.vertex].position);
    std::vector<Eigen::Vector3d> ownPoints;
    for (int j : own) ownPoints.insert(ownPoints.end(), pointsOf[j].begin(), pointsOf[j].end());
    if (ownPoints.size() < static_cast<std::size_t>(std::max(4, rules.minVertices))) return body.joints;
    const double ownVolume = fittedVolume(rig, body.head, childHeads, own, ownPoints, height, rules.shapes);
    // Parents before children (joint order), each bone judged with the merged bones between it and the body's own
    // (not with its siblings' branches, so that left and right come out alike). A bone hanging from a bone left out
    // is left out with it; a bone without vertices follows its parent (it only turns the body's axis).
    std::set<int> kept = own;
    std::map<int, int> cutAt;            // a left-out bone → the bone where its branch was cut
    std::map<int, std::size_t> reportOf; // a bone where a branch was cut → its entry in `report`
    for (int j : body.joints) {
        if (!small(j)) continue;
        if (cutAt.count(parentOf(j))) {
            cutAt[j] = cutAt[parentOf(j)];
            continue;
        }
        if (pointsOf[j].empty()) {
            kept.insert(j);
            continue;
        }
        std::set<int> trialJoints = own;
        std::vector<Eigen::Vector3d> trial = ownPoints;
        for (int a = j; small(a); a = parentOf(a)) {
            trialJoints.insert(a);
            trial.insert(trial.end(), pointsOf[a].begin(), pointsOf[a].end());
        }
        const double volume = fittedVolume(rig, body.head, childHeads, trialJoints, trial, height, rules.shapes);
        if (volume <= rules.maxMergeGrowth * ownVolume) {
            kept.insert(j);
        } else {
            cutAt[j] = j;
            reportOf[j] = report.size();
            report.push_back(leftOutReport(rig, body, j, volume / ownVolume));
        }
    }
    if (cutAt.empty()) return body.joints;
    // The left-out vertices, counted at the bone where their branch was cut.
    std::vector<Member> staying;
    body.points.clear();
    for (const Member& m : members) {
        const auto cut = cutAt.find(m.joint);
        if (cut == cutAt.end()) {
            staying.push_back(m);
            body.points.push_back(rig.surfaces[m.surface].vertices[m.vertex].position);
            continue;
        }
        stray[m.surface][m.vertex] = true;
        addPoint(report[reportOf.at(cut->second)], rig, body, m);
    }
    members = std::move(staying);
    return {kept.begin(), kept.end()};
}

} // namespace afb::gen::detail
