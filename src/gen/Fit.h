#pragma once
// Internal to afb gen: grouping bones into bodies and fitting one of Doom's shapes to each group's vertices.
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "afb/decl/Af.h"
#include "afb/gen/Generate.h"

namespace afb::gen::detail {

/// One body as fitted, in the rig's model space (Doom units, bind pose).
struct BodyFit {
    int head = 0;                        ///< the group's first joint (the joint the body drives; 0 for the base body)
    int mainJoint = 0;                   ///< the group's joint with the most vertices (names the base body)
    int parentBody = -1;                 ///< the body holding the head's parent joint; -1 for the base body
    std::vector<int> joints;             ///< every joint of the group, ascending
    std::vector<Eigen::Vector3d> points; ///< the vertices it was fitted to
    Eigen::Matrix3d frame = Eigen::Matrix3d::Identity();   ///< columns: the fit's axes (Z along the bone)
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();      ///< the shape's centre (its centre of mass)
    Eigen::Vector3d halfExtents = Eigen::Vector3d::Ones(); ///< box-like shapes: bounds half extents in `frame`
    decl::ShapeKind shape = decl::ShapeKind::Box;
    int sides = 0;                                        ///< cylinder sides
    double boneLength = 0, boneWidth = 0;                 ///< bone shape: length along frame Z, width
    double volume = 0;                                    ///< Doom units³
    Eigen::Vector3d direction = Eigen::Vector3d::UnitZ(); ///< from the head joint toward the body (unit)
    bool promoted = false; ///< a branch the maxMergeGrowth rule cut from its parent's body, made a body of its own
};

/// The size rules for a body of its own: at least `minVertices` points, and their extent or the bone's length (to
/// its farthest joint) at least `minSpan` (GenRules::minBodyFraction of the model's height).
bool bodySized(const std::vector<Eigen::Vector3d>& points, double boneLength, int minVertices, double minSpan);

/// Vertices left out of every fit, per surface and vertex (strayVertices).
using VertexMask = std::vector<std::vector<bool>>;

/// Groups the rig's joints into bodies (merge rules, size rules, the base body) and fits a shape to each, to every
/// vertex but those set in `stray`. Vertices the maxMergeGrowth rule leaves out are set in `stray` and reported in
/// `report`.
std::vector<BodyFit> fitBodies(const Rig& rig, const GenRules& rules, VertexMask& stray,
                               std::vector<StrayVertices>& report);

/// Where a body's frame runs: from its head joint toward `tail` when set (else along the vertices' principal axis).
struct BoneAxis {
    Eigen::Vector3d head = Eigen::Vector3d::Zero(); ///< the head joint, model space
    std::optional<Eigen::Vector3d> tail;            ///< the one child body's head joint, or a leaf's farthest joint
    bool toTail = false;                            ///< the bounds reach the tail (a body with one child body)
};

/// The axis of a body with head joint `head` and the child bodies whose head joints are `childHeads`: toward the one
/// child's head, else (a leaf) toward the farthest of `joints` from the head; none for the base body (head 0).
BoneAxis boneAxis(const Rig& rig, int head, const std::vector<int>& childHeads, const std::vector<int>& joints);

/// Fits `body`'s frame and shape to its points (at least one) along `axis` (`height`: the model's, for the least
/// thickness): sets frame, centre, halfExtents, shape, sides, bone length and width, volume and direction.
void fitFrame(BodyFit& body, const BoneAxis& axis, double height, const std::vector<std::string>& shapes);

/// One vertex a body is fitted to: where it is in the rig, and the body's joint that weighs it most.
struct Member {
    std::size_t surface = 0, vertex = 0;
    int joint = 0;
};

/// The joints of `body` that count as its own: every joint but those merged into it for their size
/// (`mergedSmall`), except the merged bones between it and a body hanging from it (a neck, a waist: links).
std::set<int> ownJoints(const Rig& rig, const std::vector<bool>& mergedSmall, const std::vector<int>& childHeads,
                        const BodyFit& body);

/// The volume of the body with head joint `head` fitted to `points`, its axis from `joints` (boneAxis, fitFrame).
double fittedVolume(const Rig& rig, int head, const std::vector<int>& childHeads, const std::set<int>& joints,
                    std::vector<Eigen::Vector3d> points, double height, const std::vector<std::string>& shapes);

/// The distance from `p` to bone `joint`: to the nearest segment from its joint to a child joint, or to its joint
/// when it has none (bind pose, model space).
double boneDistance(const Rig& rig, int joint, const Eigen::Vector3d& p);

/// The median of `values` (at least one).
double median(std::vector<double> values);
/// The fewest vertices of a bone whose distances' median the stray and prop rules judge by (fewer give no meaningful
/// median: such a bone is left as it is).
constexpr std::size_t kMinMedianVertices = 8;

/// The maxPropGrowth rule on one body (GenRules::maxPropGrowth): for each of its `own` bones with at least 8
/// members, the vertices farther from the bone than GenRules::propRadius times their median distance are removed
/// from `body.points` and `members`, set in `stray` and reported, when they are at most a quarter of the bone's and
/// the body fitted to its own bones' vertices with them is more than the factor times the body fitted without
/// them. Each bone is judged with every other bone's vertices kept.
void trimProps(const Rig& rig, const GenRules& rules, const std::set<int>& own, const std::vector<int>& childHeads,
               double height, BodyFit& body, std::vector<Member>& members, VertexMask& stray,
               std::vector<StrayVertices>& report);

/// A branch of small bones the maxMergeGrowth rule cuts from a body: the bone where it was cut, the bones hanging
/// from it, their vertices and how much they would grow the body.
struct CutBranch {
    int bone = 0;
    double growth = 0;           ///< the body's volume with the branch over its own bones' volume
    bool together = false;       ///< cut for the growth of the branches kept together (each within the limit alone)
    std::vector<int> joints;     ///< the bone and the bones cut with it, ascending
    std::vector<Member> members; ///< their vertices, removed from the body
};

/// The maxMergeGrowth rule on one body (GenRules::maxMergeGrowth): the vertices of its joints set in `mergedSmall`
/// (bones merged into it for their size) stay in `body.points` and `members` only while the body fitted to them
/// stays within the factor of the volume of the body fitted to its other joints' vertices, each branch judged alone
/// and then the kept ones together (the kept bones that grow it most alone cut first, near-equal ones together,
/// until the body with every kept branch is within the factor). The others are removed
/// from `body.points` and `members` and returned, one branch per cut bone; their joints stay in `body.joints`.
/// `childHeads` and `height` as for boneAxis and fitFrame. `axisJoints` takes the body's joints that still count
/// for its axis (all of them but the cut bones).
std::vector<CutBranch> limitMergeGrowth(const Rig& rig, const GenRules& rules, const std::vector<bool>& mergedSmall,
                                        const std::vector<int>& childHeads, double height, BodyFit& body,
                                        std::vector<Member>& members, std::vector<int>& axisJoints);

/// What a body of its own needs (bodySized) and what names it (the vertices each joint weighs most).
struct BodySizing {
    int minVertices = 0;                                    ///< fewest vertices (minVertices, minVertexFraction)
    double height = 0;                                      ///< the model's, as fitting sees it
    const std::vector<std::vector<Eigen::Vector3d>>& owned; ///< per joint, the vertices it weighs most
    const std::vector<bool>& skipped;                       ///< per joint, matched by the rules' skip list
};

/// The branches maxMergeGrowth cut from `body` (number `bodyIndex`): each big enough for a body of its own
/// (bodySized, its length from its bone to the farthest joint hanging from it) becomes one, fitted as a leaf body
/// (its axis toward its farthest joint not matched by the skip list) jointed to `body`, appended to `promoted` and
/// its joints taken out of `body.joints`; the vertices of the others are set in `stray` and reported, one entry per
/// cut bone.
void settleBranches(const Rig& rig, const GenRules& rules, const BodySizing& sizing, std::vector<CutBranch> cut,
                    int bodyIndex, BodyFit& body, std::vector<BodyFit>& promoted, VertexMask& stray,
                    std::vector<StrayVertices>& report);

} // namespace afb::gen::detail
