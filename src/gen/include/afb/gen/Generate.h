#pragma once
// afb gen: a ragdoll figure from a rigged mesh. Bodies are fitted to the vertices weighted to each bone
// or group of bones, joints come from a humanoid template matched by bone names, and the result is a complete
// content folder (af/N.af, def/N.def, models/md5/N/N.md5mesh + af_pose.md5anim) that decl::Library, afb inspect
// and afb drop read as they read Doom's own.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "afb/decl/Af.h"
#include "afb/figure/Figure.h"
#include "afb/gen/Rig.h"
#include "afb/text/Diagnostics.h"

namespace afb::gen {

/// How the constraint at one bone is made: matched against the name of the joint where the child body starts.
struct JointTemplate {
    std::string role;    ///< what the template is for ("knee", "shoulder", …), for reports
    std::string pattern; ///< ECMAScript regular expression, searched case-insensitively in the joint name
    decl::ConstraintType type = decl::ConstraintType::Universal; ///< Universal, Hinge, BallAndSocket or Fixed
    double coneDeg = 60;       ///< universal / ball-and-socket: full apex angle of the cone limit, degrees (0: none)
    double tiltDeg = 0;        ///< the cone's axis, tilted from the bone's bind direction by this much …
    std::string tiltToward;    ///< … toward "down", "up", "forward" or "back" (model space); empty: no tilt
    double minDeg = 0;         ///< hinge: least bend from the bind pose, degrees (negative: past straight)
    double maxDeg = 120;       ///< hinge: most bend from the bind pose, degrees
    std::string bend = "back"; ///< hinge: the child swings "back" or "forward" when it bends
    double friction = 0.4;     ///< joint friction (docs/format.md §4.8)
};

/// Every choice afb gen makes, overridable by a JSON rules file (see loadRules).
struct GenRules {
    double weightThreshold = 0.5; ///< a vertex belongs to the body whose bones weigh it at least this much
    /// Bones always merged into their parent's body (regular expressions, case-insensitive): fingers, toes, twist
    /// and helper bones, hands and feet (Doom merges them into the forearm and the shin), props.
    std::vector<std::string> merge;
    std::vector<std::string> keep; ///< bones that always get a body of their own (win over merge and size rules)
    /// Bones whose vertices no body is fitted to (weapons, shields, props): they still merge into the parent's body,
    /// which drives them, but do not inflate it.
    std::vector<std::string> skip;
    /// Surfaces (meshes) no body is fitted to, matched against their name and their material (regular expressions,
    /// case-insensitive): props modelled as meshes of their own. Their vertices still follow their bones.
    std::vector<std::string> skipSurfaces;
    /// A vertex is not fitted when it lies farther from the bone that weighs it most than that bone's median
    /// vertex distance + the larger of strayFactor × max(1.4826 × the distances' median absolute deviation, half the
    /// median) and a tenth of the model's height: a prop or attachment weighted to a body bone (see
    /// strayVertices). 0 turns the rule off.
    double strayFactor = 6;
    /// A bone whose vertices and length (to its farthest child joint) both span less than this fraction of the
    /// model's height merges into its parent's body.
    double minBodyFraction = 0.08;
    int minVertices = 8;              ///< so does a bone with fewer vertices than this …
    double minVertexFraction = 0.005; ///< … or than this fraction of the model's vertices
    /// A bone merged into an ancestor's body because it is too small for one of its own (the three rules above and
    /// minVolumeRatio) adds its vertices to that body only while the body, fitted to its own bones' vertices and those
    /// of the merged bones between it and them, stays within this factor of the volume fitted to its own bones'
    /// alone (its own: the bones not merged for their size, and merged links to a body hanging from it). A bone
    /// that would grow it more (a braid or strap hanging off the head) is cut with every bone hanging from it. While
    /// the body with every kept bone is past the factor, the kept bones that grow it most alone are cut, with those
    /// within 10 % of their growth (a left and a right braid together). A cut branch big enough for a body of its own
    /// (minVertices, minVertexFraction, minBodyFraction) becomes one, jointed to that body; a smaller one's vertices
    /// are left out of every body and reported as stray (see StrayVertices::growth). 0 turns the rule off.
    double maxMergeGrowth = 1.6;
    /// A prop modelled onto a bone's own skin (a horned helmet on the head bone): the vertices of one of a body's own
    /// bones (as maxMergeGrowth counts them, with at least 8 vertices) farther from the bone than propRadius × their
    /// median distance from it are left out of every body and reported (see StrayVertices), when they are at most a
    /// quarter of the bone's vertices and the body fitted to its own bones' vertices with them is more than
    /// maxPropGrowth times the body fitted without them. Each bone is judged with the others' vertices kept; the
    /// rule runs before maxMergeGrowth, which then measures growth against the trimmed body. 0 turns it off.
    double maxPropGrowth = 1.8;
    double propRadius = 1.5; ///< maxPropGrowth's far vertices: past this multiple of the median distance (≥ 1)
    /// After fitting, a body merges into its parent (the smallest ratio first) when it and every body hanging from it
    /// are under this fraction of the parent's volume (a leaf, a braid of helper bones), or when it is under this
    /// fraction of the smaller of its parent and its largest child (a thin link): with one density, a 10:1 mass
    /// ratio across a joint is what the figure layer warns of.
    double minVolumeRatio = 0.1;
    std::vector<std::string> shapes; ///< shapes tried, smallest enclosing volume wins: box, cylinder,
                                     ///< dodecahedron, octahedron, bone
    /// Total mass = this × the bodies' volume when no --mass is given. The bodies enclose the mesh, so they hold
    /// about twice its volume: 500 gives a human-sized figure about what Doom's weigh (zsec: 250).
    double densityKgM3 = 500;
    std::optional<Eigen::Vector3d> forward; ///< the model's forward direction (model space); default: from the
                                            ///< feet (toe − ankle), else +X (Doom's)
    std::vector<JointTemplate> joints;      ///< first match wins
    JointTemplate fallback;                 ///< for every other bone
};

/// The built-in humanoid template.
GenRules defaultRules();

/// The default rules with the keys of a JSON file written over them. Keys: weightThreshold, merge, keep, skip,
/// skipSurfaces, strayFactor, maxMergeGrowth, maxPropGrowth, propRadius, minBodyFraction, minVertices,
/// minVertexFraction, minVolumeRatio, shapes, densityKgM3, forward ([x, y, z]), joints (a list: each {role, pattern,
/// type: universal|hinge|ballAndSocket|fixed, coneDeg, tiltDeg, tiltToward, minDeg, maxDeg, bend, friction}; put before
/// the defaults, so they win), fallback (an object as in joints). An unknown key, a wrong type or a bad regular
/// expression is an error naming the file.
std::optional<GenRules> loadRules(const std::filesystem::path& path, text::Diagnostics& diagnostics);
/// The same from JSON text; `fileName` is used in messages.
std::optional<GenRules> parseRules(const std::string& json, const std::string& fileName,
                                   text::Diagnostics& diagnostics);

/// What to generate.
struct GenOptions {
    std::string name;             ///< the figure's name: the .af decl, the entityDef, file names
    std::optional<double> massKg; ///< total mass; default rules.densityKgM3 × volume
    GenRules rules = defaultRules();
    std::string source; ///< the model's path as the user gave it, for messages about it (default: `name`)
    std::string outDir; ///< the content folder as the user gave it: messages about the written files name it
};

/// Vertices of one bone that no body is fitted to: far from the bone (GenRules::strayFactor), on a skipped surface
/// (GenRules::skipSurfaces), of a small bone that would grow the body it merges into too much
/// (GenRules::maxMergeGrowth), or a prop on a body's own bone (GenRules::maxPropGrowth). They stay in the written
/// mesh, skinned to their bones as before.
struct StrayVertices {
    std::string rule;     ///< the rule that left them out: strayFactor, skipSurfaces, maxMergeGrowth, maxPropGrowth
    std::string joint;    ///< the bone that weighs them most
    std::string surface;  ///< the surface matched by skipSurfaces; empty for the other rules
    std::string body;     ///< maxMergeGrowth, maxPropGrowth: the joint naming the body; empty for the others
    int vertices = 0;     ///< how many (maxMergeGrowth: of the bone and the bones hanging from it)
    int boneVertices = 0; ///< how many vertices the bone weighs most, these included (maxMergeGrowth: = vertices)
    double nearestM = 0;  ///< their least distance from the bone (maxMergeGrowth: from the body's joint), metres
    double farthestM = 0; ///< their greatest distance from the bone (maxMergeGrowth: from the body's joint), metres
    double medianM = 0;   ///< strayFactor, maxPropGrowth: the median distance of all the bone's vertices, metres
    double limitM = 0;    ///< strayFactor, maxPropGrowth: the distance past which a vertex counts as far, metres
    /// maxMergeGrowth: the body's volume with them over its own bones' volume; maxPropGrowth: over the volume
    /// without them (0 for the other rules)
    double growth = 0;
    /// maxMergeGrowth: cut because the branches kept together grew the body past the limit, each within it alone
    /// (`growth` is then the body's with every branch kept at that point)
    bool together = false;
};

/// Which vertices (per surface, per vertex) no body is fitted to, by the skipSurfaces and strayFactor rules, and
/// a report per bone and per skipped surface. A bone's distance is to the segments from its joint to each child
/// joint (its joint alone for a leaf), at the bind pose; bones weighing fewer than 8 vertices are left alone.
std::vector<std::vector<bool>> strayVertices(const Rig& rig, const GenRules& rules, std::vector<StrayVertices>& report);

/// One generated body, for reports and tests.
struct GeneratedBody {
    std::string name;
    std::string joint; ///< the joint it drives ("origin" for the base body)
    decl::ShapeKind shape = decl::ShapeKind::Box;
    Eigen::Vector3d centre;  ///< centre of its shape at the bind pose, model space, Doom units
    double volumeUnits3 = 0; ///< Doom units³
    double massKg = 0;
    std::vector<int> joints; ///< the rig joints it contains (containedJoints)
    int vertices = 0;        ///< vertices fitted
};

/// One generated constraint, for reports.
struct GeneratedJoint {
    std::string name;
    std::string role; ///< the template that matched ("" for the fallback)
    int body1 = 0, body2 = 0;
};

/// A generated figure and every file of its content folder, as values.
struct Generated {
    std::string name;
    decl::AfDecl af;
    decl::Md5Mesh mesh;
    decl::Md5Anim afPose;
    Eigen::Vector3d modelOffset = Eigen::Vector3d::Zero(); ///< the model decl's offset: the root joint's bind position
    std::vector<GeneratedBody> bodies;
    std::vector<GeneratedJoint> joints;
    std::vector<StrayVertices> stray; ///< vertices no body was fitted to (reported as warnings too)
    double totalMassKg = 0;
    /// The figure built from `af` on the written skeleton (default units), as loading the folder gives it.
    std::optional<figure::Figure> figure;
};

/// Fits bodies and joints to `rig`. Errors (nothing to fit, a figure the figure layer refuses) in `diagnostics`.
std::optional<Generated> generateFigure(const Rig& rig, const GenOptions& options, text::Diagnostics& diagnostics);

/// Paths of a generated content folder, relative to its root.
struct ContentPaths {
    std::string af, def, mesh, afPose;
};
ContentPaths contentPaths(const std::string& name);

/// The `.def` text: a model decl (mesh, offset, af_pose) and an entityDef (idAFEntity_Generic, articulatedFigure).
std::string defText(const Generated& generated);

/// Writes the content folder under `dir` (creating folders). Errors name the file.
bool writeContent(const Generated& generated, const std::filesystem::path& dir, text::Diagnostics& diagnostics);

/// A figure name from a file name: letters, digits and '_' (others become '_'), not starting with a digit.
std::string figureNameFor(const std::filesystem::path& model);

} // namespace afb::gen
