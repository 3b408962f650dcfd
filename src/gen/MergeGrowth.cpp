// afb gen's maxMergeGrowth rule: a bone too small for a body of its own joins an ancestor's body, but a braid, a
// strap or a plume hanging off that body would stretch its shape over everything the bone reaches. Such a bone's
// vertices join the body only while the body stays within GenRules::maxMergeGrowth of the volume fitted to its own
// bones. A branch cut from it becomes a body of its own when the size rules would give it one (an arm merged into
// the chest for its small volume); otherwise its vertices are left out of every body and reported, as stray
// vertices are (docs/cli.md, afb gen).
#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "Fit.h"

namespace afb::gen::detail {

double fittedVolume(const Rig& rig, int head, const std::vector<int>& childHeads, const std::set<int>& joints,
                    std::vector<Eigen::Vector3d> points, double height, const std::vector<std::string>& shapes) {
    BodyFit trial;
    trial.head = head;
    trial.points = std::move(points);
    fitFrame(trial, boneAxis(rig, head, childHeads, std::vector<int>(joints.begin(), joints.end())), height, shapes);
    return trial.volume;
}

std::set<int> ownJoints(const Rig& rig, const std::vector<bool>& mergedSmall, const std::vector<int>& childHeads,
                        const BodyFit& body) {
    const auto parentOf = [&](int j) { return rig.joints[static_cast<std::size_t>(j)].parent; };
    std::set<int> links;
    for (int c : childHeads)
        for (int a = parentOf(c); a > 0 && mergedSmall[static_cast<std::size_t>(a)]; a = parentOf(a)) links.insert(a);
    std::set<int> own;
    for (int j : body.joints)
        if (!mergedSmall[static_cast<std::size_t>(j)] || links.count(j)) own.insert(j);
    return own;
}

namespace {

// The joint that names a body: its head's, or for the base body its joint with the most vertices.
const RigJoint& namingJoint(const Rig& rig, const BodyFit& body) {
    return rig.joints[static_cast<std::size_t>(body.head > 0 ? body.head : body.mainJoint)];
}

} // namespace

namespace {

void leaveOut(const Rig& rig, const BodyFit& body, const CutBranch& branch, VertexMask& stray,
              std::vector<StrayVertices>& report) {
    StrayVertices r;
    r.rule = "maxMergeGrowth";
    r.joint = rig.joints[static_cast<std::size_t>(branch.bone)].name;
    r.body = namingJoint(rig, body).name;
    r.growth = branch.growth;
    r.nearestM = INFINITY;
    for (const Member& m : branch.members) {
        const Eigen::Vector3d& p = rig.surfaces[m.surface].vertices[m.vertex].position;
        const double d = (p - namingJoint(rig, body).bind.position).norm() * kMetresPerDoomUnit;
        ++r.vertices;
        ++r.boneVertices;
        r.nearestM = std::min(r.nearestM, d);
        r.farthestM = std::max(r.farthestM, d);
        stray[m.surface][m.vertex] = true;
    }
    report.push_back(r);
}

// From a cut branch's bone to the farthest joint hanging from the branch (a group's bone length, as the size rules
// measure it).
double branchLength(const Rig& rig, const CutBranch& branch) {
    const Eigen::Vector3d& head = rig.joints[static_cast<std::size_t>(branch.bone)].bind.position;
    double length = 0;
    for (const RigJoint& j : rig.joints)
        if (std::binary_search(branch.joints.begin(), branch.joints.end(), j.parent))
            length = std::max(length, (j.bind.position - head).norm());
    return length;
}

// A cut branch as a body of its own: jointed to `parent` at the branch's bone, fitted to the branch's vertices as
// a leaf body, named by its bone. Its axis runs toward its farthest joint but a skipped one's: a prop's bone (a
// lamp held in the hand) is no end of the limb.
BodyFit branchBody(const Rig& rig, const GenRules& rules, const BodySizing& sizing, const CutBranch& branch, int parent,
                   std::vector<Eigen::Vector3d> points) {
    BodyFit c;
    c.head = branch.bone;
    c.mainJoint = branch.bone;
    c.parentBody = parent;
    c.promoted = true;
    c.joints = branch.joints;
    std::size_t most = 0;
    for (int j : c.joints)
        if (sizing.owned[static_cast<std::size_t>(j)].size() > most) {
            most = sizing.owned[static_cast<std::size_t>(j)].size();
            c.mainJoint = j;
        }
    c.points = std::move(points);
    std::vector<int> axisJoints;
    for (int j : c.joints)
        if (!sizing.skipped[static_cast<std::size_t>(j)]) axisJoints.push_back(j);
    fitFrame(c, boneAxis(rig, c.head, {}, axisJoints.empty() ? c.joints : axisJoints), sizing.height, rules.shapes);
    return c;
}

} // namespace

void settleBranches(const Rig& rig, const GenRules& rules, const BodySizing& sizing, std::vector<CutBranch> cut,
                    int bodyIndex, BodyFit& body, std::vector<BodyFit>& promoted, VertexMask& stray,
                    std::vector<StrayVertices>& report) {
    for (const CutBranch& branch : cut) {
        std::vector<Eigen::Vector3d> points;
        for (const Member& m : branch.members) points.push_back(rig.surfaces[m.surface].vertices[m.vertex].position);
        // At least 4 vertices: the fewest a shape is fitted to.
        if (!bodySized(points, branchLength(rig, branch), std::max(4, sizing.minVertices),
                       rules.minBodyFraction * sizing.height)) {
            leaveOut(rig, body, branch, stray, report);
            continue;
        }
        promoted.push_back(branchBody(rig, rules, sizing, branch, bodyIndex, std::move(points)));
        std::vector<int> rest;
        for (int j : body.joints)
            if (!std::binary_search(branch.joints.begin(), branch.joints.end(), j)) rest.push_back(j);
        body.joints = std::move(rest);
    }
}

std::vector<CutBranch> limitMergeGrowth(const Rig& rig, const GenRules& rules, const std::vector<bool>& mergedSmall,
                                        const std::vector<int>& childHeads, double height, BodyFit& body,
                                        std::vector<Member>& members, std::vector<int>& axisJoints) {
    axisJoints = body.joints;
    const auto parentOf = [&](int j) { return rig.joints[static_cast<std::size_t>(j)].parent; };
    const std::set<int> own = ownJoints(rig, mergedSmall, childHeads, body);
    const auto small = [&](int j) { return !own.count(j); };
    if (!(rules.maxMergeGrowth > 0) || own.size() == body.joints.size()) return {};
    // The body's own vertices: those its other bones weigh most. Too few to fit a shape to, and the rule stands aside.
    std::map<int, std::vector<Eigen::Vector3d>> pointsOf;
    for (const Member& m : members) pointsOf[m.joint].push_back(rig.surfaces[m.surface].vertices[m.vertex].position);
    std::vector<Eigen::Vector3d> ownPoints;
    for (int j : own) ownPoints.insert(ownPoints.end(), pointsOf[j].begin(), pointsOf[j].end());
    if (ownPoints.size() < static_cast<std::size_t>(std::max(4, rules.minVertices))) return {};
    const double ownVolume = fittedVolume(rig, body.head, childHeads, own, ownPoints, height, rules.shapes);
    // Parents before children (joint order), each bone judged with the merged bones between it and the body's own
    // (not with its siblings' branches, so that left and right come out alike). A bone hanging from a bone left out
    // is left out with it; a bone without vertices follows its parent (it only turns the body's axis).
    std::set<int> kept = own;
    std::map<int, int> cutAt; // a left-out bone → the bone where its branch was cut
    std::vector<CutBranch> cut;
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
            cut.push_back({j, volume / ownVolume, {}, {}});
        }
    }
    if (cut.empty()) return {};
    const auto branchOf = [&](int bone) {
        return std::find_if(cut.begin(), cut.end(), [&](const CutBranch& b) { return b.bone == bone; });
    };
    for (const auto& [joint, at] : cutAt) branchOf(at)->joints.push_back(joint);
    // The left-out vertices go with the bone where their branch was cut.
    std::vector<Member> staying;
    body.points.clear();
    for (const Member& m : members) {
        const auto at = cutAt.find(m.joint);
        if (at == cutAt.end()) {
            staying.push_back(m);
            body.points.push_back(rig.surfaces[m.surface].vertices[m.vertex].position);
        } else {
            branchOf(at->second)->members.push_back(m);
        }
    }
    members = std::move(staying);
    axisJoints.assign(kept.begin(), kept.end());
    return cut;
}

} // namespace afb::gen::detail
