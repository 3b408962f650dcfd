// afb gen's maxMergeGrowth rule: a bone too small for a body of its own joins an ancestor's body, but a braid, a
// strap or a plume hanging off that body would stretch its shape over everything the bone reaches. Such a bone's
// vertices join the body only while the body stays within GenRules::maxMergeGrowth of the volume fitted to its own
// bones, each branch judged alone and then the branches kept together. A branch cut from it becomes a body of its own
// when the size rules would give it one (an arm merged into the chest for its small volume); otherwise its vertices are
// left out of every body and reported, as stray vertices are (docs/cli.md, afb gen).
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
    r.together = branch.together;
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

namespace {

// One body as the maxMergeGrowth rule sees it: its own bones (ownJoints) and their vertices, and the vertices of
// each of its joints.
struct MergeJudge {
    const Rig& rig;
    const GenRules& rules;
    const std::vector<int>& childHeads;
    double height = 0;
    const BodyFit& body;
    std::set<int> own;
    std::map<int, std::vector<Eigen::Vector3d>> pointsOf;
    std::vector<Eigen::Vector3d> ownPoints;
    double ownVolume = 0;

    int parentOf(int j) const { return rig.joints[static_cast<std::size_t>(j)].parent; }
    bool small(int j) const { return !own.count(j); }
    bool hasPoints(int j) const { return pointsOf.count(j) && !pointsOf.at(j).empty(); }
    // The volume of the body fitted to its own bones' vertices and those of `merged`, in that order.
    double volume(const std::vector<int>& merged) const {
        std::set<int> joints = own;
        std::vector<Eigen::Vector3d> points = ownPoints;
        for (int j : merged) {
            joints.insert(j);
            if (hasPoints(j)) points.insert(points.end(), pointsOf.at(j).begin(), pointsOf.at(j).end());
        }
        return fittedVolume(rig, body.head, childHeads, joints, std::move(points), height, rules.shapes);
    }
    bool withinLimit(double v) const { return v <= rules.maxMergeGrowth * ownVolume; }
};

// A bone where a branch is cut: the body's growth with it (alone, or with every branch kept at the time) and
// whether the branches' combined growth cut it.
struct CutRoot {
    double growth = 0;
    bool together = false;
};

// Branches whose growth alone lies within this fraction of the largest are cut together: a mirrored rig's left and
// right alike, and a hand-made model's (dwarf.x's braids: bone for bone, 5 to 9 % apart).
constexpr double kTogether = 0.1;

// The merged bones cut from the body, each → the root its branch was cut at: a root and every merged bone hanging
// from one. Parents before children (joint order).
std::map<int, int> cutBones(const MergeJudge& m, const std::map<int, CutRoot>& roots) {
    std::map<int, int> cutAt;
    for (int j : m.body.joints) {
        if (!m.small(j)) continue;
        if (cutAt.count(m.parentOf(j))) cutAt[j] = cutAt[m.parentOf(j)];
        else if (roots.count(j)) cutAt[j] = j;
    }
    return cutAt;
}

// Each merged bone judged with the merged bones between it and the body's own (not with its siblings' branches,
// so that left and right come out alike), parents first; a bone hanging from a cut bone is cut with it, a bone
// without vertices follows its parent (it only turns the body's axis). Returns the roots cut; `keptGrowth` takes
// the growth of each bone kept that has vertices.
std::map<int, CutRoot> judgeAlone(const MergeJudge& m, std::map<int, double>& keptGrowth) {
    std::map<int, CutRoot> roots;
    std::set<int> cut;
    for (int j : m.body.joints) {
        if (!m.small(j)) continue;
        if (cut.count(m.parentOf(j))) {
            cut.insert(j);
            continue;
        }
        if (!m.hasPoints(j)) continue;
        std::vector<int> chain;
        for (int a = j; m.small(a); a = m.parentOf(a)) chain.push_back(a);
        const double volume = m.volume(chain);
        if (m.withinLimit(volume)) {
            keptGrowth[j] = volume / m.ownVolume;
        } else {
            cut.insert(j);
            roots[j] = {volume / m.ownVolume, false};
        }
    }
    return roots;
}

// The branches kept together: while the body with every kept merged bone is past the limit, the kept bones that
// grow it most alone are cut, together with those within kTogether of the most, each with the bones hanging from
// it (a branch cut below it included).
void judgeTogether(const MergeJudge& m, std::map<int, double> keptGrowth, std::map<int, CutRoot>& roots) {
    for (;;) {
        const std::map<int, int> cutAt = cutBones(m, roots);
        for (auto it = keptGrowth.begin(); it != keptGrowth.end();)
            it = cutAt.count(it->first) ? keptGrowth.erase(it) : std::next(it);
        if (keptGrowth.empty()) return;
        std::vector<int> kept;
        for (int j : m.body.joints)
            if (m.small(j) && !cutAt.count(j)) kept.push_back(j);
        const double volume = m.volume(kept);
        if (m.withinLimit(volume)) return;
        double most = 0;
        for (const auto& entry : keptGrowth) most = std::max(most, entry.second);
        for (const auto& entry : keptGrowth)
            if (entry.second >= most - kTogether * most) roots[entry.first] = {volume / m.ownVolume, true};
    }
}

} // namespace

std::vector<CutBranch> limitMergeGrowth(const Rig& rig, const GenRules& rules, const std::vector<bool>& mergedSmall,
                                        const std::vector<int>& childHeads, double height, BodyFit& body,
                                        std::vector<Member>& members, std::vector<int>& axisJoints) {
    axisJoints = body.joints;
    MergeJudge m{rig, rules, childHeads, height, body, ownJoints(rig, mergedSmall, childHeads, body), {}, {}, 0};
    if (!(rules.maxMergeGrowth > 0) || m.own.size() == body.joints.size()) return {};
    // The body's own vertices: those its other bones weigh most. Too few to fit a shape to, and the rule stands aside.
    for (const Member& mb : members)
        m.pointsOf[mb.joint].push_back(rig.surfaces[mb.surface].vertices[mb.vertex].position);
    for (int j : m.own)
        if (m.hasPoints(j)) m.ownPoints.insert(m.ownPoints.end(), m.pointsOf[j].begin(), m.pointsOf[j].end());
    if (m.ownPoints.size() < static_cast<std::size_t>(std::max(4, rules.minVertices))) return {};
    m.ownVolume = m.volume({});
    std::map<int, double> keptGrowth;
    std::map<int, CutRoot> roots = judgeAlone(m, keptGrowth);
    judgeTogether(m, std::move(keptGrowth), roots);
    if (roots.empty()) return {};
    const std::map<int, int> cutAt = cutBones(m, roots);
    std::vector<CutBranch> cut;
    for (const auto& [bone, root] : roots)
        if (cutAt.at(bone) == bone) cut.push_back({bone, root.growth, root.together, {}, {}});
    const auto branchOf = [&](int bone) {
        return std::find_if(cut.begin(), cut.end(), [&](const CutBranch& b) { return b.bone == bone; });
    };
    for (const auto& [joint, at] : cutAt) branchOf(at)->joints.push_back(joint);
    // The left-out vertices go with the bone where their branch was cut.
    std::vector<Member> staying;
    body.points.clear();
    for (const Member& mb : members) {
        const auto at = cutAt.find(mb.joint);
        if (at == cutAt.end()) {
            staying.push_back(mb);
            body.points.push_back(rig.surfaces[mb.surface].vertices[mb.vertex].position);
        } else {
            branchOf(at->second)->members.push_back(mb);
        }
    }
    members = std::move(staying);
    axisJoints.clear();
    for (int j : body.joints)
        if (!cutAt.count(j)) axisJoints.push_back(j);
    return cut;
}

} // namespace afb::gen::detail
