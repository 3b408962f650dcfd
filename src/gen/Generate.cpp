// afb gen: bodies (Fit.cpp) + joints from the template + masses, assembled into an .af decl, checked by building
// the figure, and written as a content folder with the decl writers.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <regex>
#include <set>

#include "Fit.h"
#include "afb/decl/AfParser.h"
#include "afb/detail/DoomMath.h"
#include "afb/detail/Lexer.h"
#include "afb/figure/Collision.h"
#include "afb/figure/Figure.h"
#include "afb/figure/Skeleton.h"

namespace afb::gen {
namespace {

using detail::BodyFit;
constexpr double kDeg = M_PI / 180.0;

double rnd(double v, int decimals = 4) {
    const double scale = std::pow(10.0, decimals);
    const double r = std::round(v * scale) / scale;
    return r == 0.0 ? 0.0 : r;
}

double significant(double v, int digits) {
    if (v == 0 || !std::isfinite(v)) return v;
    return rnd(v, digits - 1 - static_cast<int>(std::floor(std::log10(std::abs(v)))));
}

decl::Vec3 vec(const Eigen::Vector3d& v, int decimals = 4) {
    return {rnd(v.x(), decimals), rnd(v.y(), decimals), rnd(v.z(), decimals)};
}
decl::AfVector lit(const Eigen::Vector3d& v, int decimals = 4) { return decl::AfVector::fromLiteral(vec(v, decimals)); }

// A body or constraint name: the joint's, unique ignoring case, never "origin" or "world" (docs/format.md §1.4).
std::string uniqueName(const std::string& wanted, std::set<std::string>& taken) {
    std::string base = wanted.empty() ? "body" : wanted;
    if (text::lowerAscii(base) == "origin" || text::lowerAscii(base) == "world") base += "_body";
    std::string name = base;
    for (int k = 2; taken.count(text::lowerAscii(name)); ++k) name = base + "_" + std::to_string(k);
    taken.insert(text::lowerAscii(name));
    return name;
}

// The direction `v` turned toward `target` by at most `angleRad` (not past it).
Eigen::Vector3d tiltToward(const Eigen::Vector3d& v, const Eigen::Vector3d& target, double angleRad) {
    const double between = std::acos(std::clamp(v.dot(target), -1.0, 1.0));
    Eigen::Vector3d axis = v.cross(target);
    if (axis.norm() < 1e-9 || angleRad <= 0) return v;
    return Eigen::AngleAxisd(std::min(angleRad, between), axis.normalized()) * v;
}

// The model's forward direction: the rules', else the mean horizontal direction from ankles to toes, else +X.
Eigen::Vector3d forwardOf(const Rig& rig, const GenRules& rules) {
    if (rules.forward) return *rules.forward;
    const std::regex toe("toe|ball|foot", std::regex::ECMAScript | std::regex::icase);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const RigJoint& j : rig.joints)
        if (j.parent >= 0 && std::regex_search(j.name, toe)) {
            Eigen::Vector3d d = j.bind.position - rig.joints[static_cast<std::size_t>(j.parent)].bind.position;
            d.z() = 0;
            if (d.norm() > 1e-9) sum += d.normalized();
        }
    if (sum.norm() > 0.5) return sum.normalized();
    return Eigen::Vector3d::UnitX();
}

const JointTemplate& templateFor(const std::string& jointName, const GenRules& rules) {
    for (const JointTemplate& t : rules.joints)
        if (std::regex_search(jointName, std::regex(t.pattern, std::regex::ECMAScript | std::regex::icase))) return t;
    return rules.fallback;
}

// containedJoints for a group: "*head -*child …" when that selects exactly the group's joints (the engine's
// descendant scan, docs/format.md §5.3), else the joints one by one.
std::string containedJoints(const Rig& rig, const BodyFit& body, const std::vector<BodyFit>& bodies) {
    const int n = static_cast<int>(rig.joints.size());
    const auto subtree = [&](int j) {
        std::set<int> s{j};
        for (int k = j + 1; k < n && rig.joints[static_cast<std::size_t>(k)].parent >= j; ++k) s.insert(k);
        return s;
    };
    std::set<int> selected = subtree(body.head);
    std::string text = "*" + rig.joints[static_cast<std::size_t>(body.head)].name;
    for (const BodyFit& other : bodies)
        if (other.head > body.head && selected.count(other.head)) {
            for (int j : subtree(other.head)) selected.erase(j);
            text += " -*" + rig.joints[static_cast<std::size_t>(other.head)].name;
        }
    if (selected == std::set<int>(body.joints.begin(), body.joints.end())) return text;
    text.clear();
    for (int j : body.joints) text += (text.empty() ? "" : " ") + rig.joints[static_cast<std::size_t>(j)].name;
    return text;
}

decl::AfShape shapeOf(const BodyFit& b) {
    decl::AfShape s;
    s.kind = b.shape;
    if (b.shape == decl::ShapeKind::Bone) {
        const Eigen::Vector3d d = b.frame.col(2) * (b.boneLength / 2);
        s.v1 = lit(b.centre - d);
        s.v2 = lit(b.centre + d);
        s.width = rnd(b.boneWidth);
        return s;
    }
    s.v1 = lit(-b.halfExtents);
    s.v2 = lit(b.halfExtents);
    if (b.shape == decl::ShapeKind::Cylinder) s.numSides = b.sides;
    return s;
}

decl::AfConstraint constraintFor(const Rig& rig, const BodyFit& child, const std::string& name,
                                 const std::string& body1, const std::string& body2, const JointTemplate& t,
                                 const Eigen::Vector3d& forward) {
    decl::AfConstraint c;
    c.type = t.type;
    c.name = name;
    c.body1 = body1;
    c.body2 = body2;
    const std::string& jointName = rig.joints[static_cast<std::size_t>(child.head)].name;
    const Eigen::Vector3d d = child.direction;
    if (t.type == decl::ConstraintType::Fixed) return c;
    c.anchor = decl::AfVector::fromJoint(jointName);
    c.friction = t.friction;
    if (t.type == decl::ConstraintType::Hinge) {
        // Bending back turns the child toward −forward: about forward × d (right-handed, docs/format.md §4.5).
        Eigen::Vector3d axis = t.bend == "back" ? forward.cross(d) : d.cross(forward);
        if (axis.norm() < 0.2) axis = Eigen::Vector3d::UnitZ().cross(forward);
        c.axis = lit(axis.normalized(), 8); // unit within 1e-8: no engine distortion of the limit (§4.5)
        // limit a0, a1, a2 allows [a2 − a0 − a1/2, a2 − a0 + a1/2] (docs/format.md §4.5).
        c.limit = decl::HingeLimit{0, rnd(t.maxDeg - t.minDeg), rnd((t.maxDeg + t.minDeg) / 2)};
        return c;
    }
    Eigen::Vector3d coneAxis = d;
    if (!t.tiltToward.empty() && t.coneDeg > 0) {
        const Eigen::Vector3d target = t.tiltToward == "down"      ? Eigen::Vector3d(-Eigen::Vector3d::UnitZ())
                                       : t.tiltToward == "up"      ? Eigen::Vector3d(Eigen::Vector3d::UnitZ())
                                       : t.tiltToward == "forward" ? forward
                                                                   : Eigen::Vector3d(-forward);
        // The bind pose stays 5° inside the cone.
        const double tilt = std::clamp(t.tiltDeg, 0.0, std::max(0.0, t.coneDeg / 2 - 5)) * kDeg;
        coneAxis = tiltToward(d, target, tilt);
    }
    if (t.type == decl::ConstraintType::Universal) {
        c.shafts = std::array<decl::AfVector, 2>{lit(d), lit(-d)};
        if (t.coneDeg > 0) c.limit = decl::ConeLimit{lit(coneAxis), rnd(t.coneDeg), std::nullopt};
    } else if (t.coneDeg > 0) { // ball and socket: the shaft is the child's bone
        c.limit = decl::ConeLimit{lit(coneAxis), rnd(t.coneDeg), lit(d)};
    }
    return c;
}

std::string centimetres(double metres) { return std::to_string(static_cast<long>(std::lround(metres * 100))); }

// A volume factor with one decimal.
std::string growthText(double factor) {
    const long tenths = std::lround(factor * 10);
    return std::to_string(tenths / 10) + "." + std::to_string(tenths % 10);
}

// One warning per bone (or skipped surface) whose vertices no body is fitted to, naming the model as given.
void reportStray(const std::vector<StrayVertices>& stray, const std::string& model, double maxGrowth,
                 double maxPropGrowth, text::Diagnostics& diagnostics) {
    for (const StrayVertices& s : stray) {
        if (!s.surface.empty()) {
            diagnostics.warning({model, 0, 0}, "surface \"" + s.surface + "\" (" + std::to_string(s.vertices) +
                                                   " vertices) is skipped by the rules: no body is fitted to it");
            continue;
        }
        if (s.rule == "maxPropGrowth") {
            diagnostics.warning({model, 0, 0},
                                std::to_string(s.vertices) + " of the " + std::to_string(s.boneVertices) +
                                    " vertices of bone \"" + s.joint + "\" lie " + centimetres(s.nearestM) + "-" +
                                    centimetres(s.farthestM) + " cm from it, past " + centimetres(s.limitM) +
                                    " cm (its median " + centimetres(s.medianM) +
                                    " cm), and would make the body of \"" + s.body + "\" " + growthText(s.growth) +
                                    " times the volume of its other vertices' (at most " + growthText(maxPropGrowth) +
                                    "): a prop on the bone? no body is fitted to them (rules: maxPropGrowth)");
            continue;
        }
        if (s.rule == "maxMergeGrowth") {
            diagnostics.warning({model, 0, 0},
                                std::to_string(s.vertices) + " of the " + std::to_string(s.boneVertices) +
                                    " vertices of bone \"" + s.joint + "\" and the bones hanging from it lie " +
                                    centimetres(s.nearestM) + "-" + centimetres(s.farthestM) + " cm from joint \"" +
                                    s.body + "\", whose body the bone is merged into for its size: " +
                                    (s.together ? "with the branches kept beside it, it would make that body "
                                                : "it would make that body ") +
                                    growthText(s.growth) + " times the volume of its own bones' (at most " +
                                    growthText(maxGrowth) + "); no body is fitted to them (rules: maxMergeGrowth)");
            continue;
        }
        diagnostics.warning({model, 0, 0},
                            std::to_string(s.vertices) + " of the " + std::to_string(s.boneVertices) +
                                " vertices weighted to bone \"" + s.joint + "\" lie " + centimetres(s.nearestM) + "-" +
                                centimetres(s.farthestM) + " cm from it, past " + centimetres(s.limitM) +
                                " cm (its median " + centimetres(s.medianM) +
                                " cm): a prop or attachment? no body is fitted to them (rules: strayFactor, "
                                "skipSurfaces)");
    }
}

// The settings block: the engine's friction and contents for a corpse, every body colliding with the others.
decl::AfSettings settingsFor(const std::string& name, double massKg) {
    decl::AfSettings settings;
    settings.model = "model_" + name;
    settings.skin = "";
    settings.friction = decl::SettingsFriction{0.01, 0.01, 0.8, std::nullopt};
    settings.totalMass = massKg;
    settings.contents = decl::ContentsList{{"corpse"}};
    settings.clipMask = decl::ContentsList{{"solid", "corpse"}};
    settings.selfCollision = true;
    return settings;
}

// One body per fit, in fit order, all of one density (Doom's: mass per cubic unit, docs/format.md §3.3).
void addBodies(Generated& out, const Rig& rig, const std::vector<BodyFit>& fits, double massKg, double totalVolume,
               const text::SourceLocation& written) {
    decl::AfDecl& af = out.af;
    const double density = massKg / totalVolume;
    std::set<std::string> bodyNames;
    for (const BodyFit& b : fits) {
        decl::AfBody body;
        body.location = written;
        const bool base = b.head == 0;
        body.name = uniqueName(rig.joints[static_cast<std::size_t>(base ? b.mainJoint : b.head)].name, bodyNames);
        body.joint = base ? "origin" : rig.joints[static_cast<std::size_t>(b.head)].name;
        body.mod = "orientation";
        body.model = shapeOf(b);
        body.origin = lit(b.centre);
        if (b.shape != decl::ShapeKind::Bone) {
            const Eigen::Vector3d angles = figure::rotationToAngles(b.frame);
            if (angles.norm() > 0) body.angles = decl::AfVector::fromLiteral(vec(angles));
        }
        body.density = significant(density, 6); // the same for every body; totalMass sets the sum
        body.containedJoints = containedJoints(rig, b, fits);
        af.order.push_back({decl::AfBlockRef::Kind::Body, af.bodies.size()});
        af.bodies.push_back(std::move(body));
        out.bodies.push_back({af.bodies.back().name, af.bodies.back().joint, b.shape, b.centre, b.volume,
                              massKg * b.volume / totalVolume, b.joints, static_cast<int>(b.points.size())});
    }
}

// One constraint per body with a parent body, from the rules' template for its head joint.
void addConstraints(Generated& out, const Rig& rig, const std::vector<BodyFit>& fits, const GenOptions& options,
                    const Eigen::Vector3d& forward, const text::SourceLocation& written) {
    decl::AfDecl& af = out.af;
    std::set<std::string> constraintNames;
    for (std::size_t i = 0; i < fits.size(); ++i) {
        const BodyFit& b = fits[i];
        if (b.parentBody < 0) continue;
        const std::string& jointName = rig.joints[static_cast<std::size_t>(b.head)].name;
        const JointTemplate& t = templateFor(jointName, options.rules);
        decl::AfConstraint c = constraintFor(rig, b, uniqueName(af.bodies[i].name, constraintNames), af.bodies[i].name,
                                             af.bodies[static_cast<std::size_t>(b.parentBody)].name, t, forward);
        c.location = written;
        af.order.push_back({decl::AfBlockRef::Kind::Constraint, af.constraints.size()});
        af.constraints.push_back(std::move(c));
        out.joints.push_back({af.constraints.back().name, t.role, static_cast<int>(i), b.parentBody});
    }
}

// Builds the figure once, as the runtime will, and turns self-collision off for the smaller of every pair of bodies
// that touch at the bind pose (as the hand-made figures do for the upper arms against the chest); the flags change
// nothing else in the figure. False when the figure does not build (the reasons are in `diagnostics`).
bool buildAndExemptTouching(Generated& out, const std::vector<BodyFit>& fits, const GenOptions& options,
                            text::Diagnostics& diagnostics) {
    decl::AfDecl& af = out.af;
    text::Diagnostics skeletonDiags;
    const auto skeleton = figure::Skeleton::build(out.mesh, out.afPose, out.modelOffset, skeletonDiags, options.name);
    if (!skeleton) {
        diagnostics.append(skeletonDiags);
        return false;
    }
    text::Diagnostics findings;
    figure::FigureInput input;
    input.decl = &af;
    input.skeleton = &*skeleton;
    auto fig = figure::buildFigure(input, findings);
    if (!fig) {
        diagnostics.append(findings);
        diagnostics.error({options.name, 0, 0}, "the generated figure does not build (see above)");
        return false;
    }
    // The figure's other findings (mass ratios, thin bodies) are the user's to see; touching pairs are fixed below.
    for (const text::Diagnostic& d : findings.items())
        if (d.message.find("self-colliding bodies") == std::string::npos) diagnostics.add(d);
    for (const auto& [a, b] : figure::selfCollisionPairs(*fig)) {
        const auto ia = static_cast<std::size_t>(a), ib = static_cast<std::size_t>(b);
        if (!af.bodies[ia].selfCollision.value_or(true) || !af.bodies[ib].selfCollision.value_or(true)) continue;
        if (figure::separation(fig->bodies[ia], fig->bodies[ib]) >= figure::kTouchToleranceM) continue;
        const std::size_t smaller = fits[ia].volume <= fits[ib].volume ? ia : ib;
        af.bodies[smaller].selfCollision = false;
        fig->bodies[smaller].selfCollision = false;
    }
    out.figure = std::move(fig);
    return true;
}

} // namespace

std::optional<Generated> generateFigure(const Rig& rig, const GenOptions& options, text::Diagnostics& diagnostics) {
    const text::SourceLocation where{options.name, 0, 0};
    if (rig.joints.empty()) {
        diagnostics.error(where, "the rig has no joints");
        return std::nullopt;
    }
    Generated out;
    out.name = options.name;
    const std::string commandline = "Generated by afb gen";
    out.mesh = toMd5Mesh(rig, commandline);
    out.afPose = bindPoseAnim(rig, commandline);
    out.modelOffset = rig.joints[0].bind.position;

    detail::VertexMask stray = strayVertices(rig, options.rules, out.stray);
    const std::vector<BodyFit> fits = detail::fitBodies(rig, options.rules, stray, out.stray);
    reportStray(out.stray, options.source.empty() ? options.name : options.source, options.rules.maxMergeGrowth,
                options.rules.maxPropGrowth, diagnostics);
    const Eigen::Vector3d forward = forwardOf(rig, options.rules);
    double totalVolume = 0;
    for (const BodyFit& b : fits) totalVolume += b.volume;
    const double volumeM3 = totalVolume * std::pow(kMetresPerDoomUnit, 3);
    const double mass = options.massKg.value_or(rnd(options.rules.densityKgM3 * volumeM3, 1));
    if (!(mass > 0) || !(totalVolume > 0)) {
        diagnostics.error(where, "the bodies have no volume or the mass is not positive");
        return std::nullopt;
    }

    decl::AfDecl& af = out.af;
    af.name = options.name;
    // Findings name the file the decl is written to (and the body or constraint), under the folder as given.
    const std::string afPath = contentPaths(options.name).af;
    const text::SourceLocation written{
        options.outDir.empty() ? afPath : (std::filesystem::path(options.outDir) / afPath).string(), 0, 0};
    af.location = written;
    af.settings.push_back(settingsFor(options.name, mass));
    af.order.push_back({decl::AfBlockRef::Kind::Settings, 0});
    addBodies(out, rig, fits, mass, totalVolume, written);
    addConstraints(out, rig, fits, options, forward, written);
    out.totalMassKg = mass;
    if (!buildAndExemptTouching(out, fits, options, diagnostics)) return std::nullopt;
    return out;
}

ContentPaths contentPaths(const std::string& name) {
    return {"af/" + name + ".af", "def/" + name + ".def", "models/md5/" + name + "/" + name + ".md5mesh",
            "models/md5/" + name + "/af_pose.md5anim"};
}

std::string defText(const Generated& g) {
    const ContentPaths paths = contentPaths(g.name);
    std::string text = "// Generated by afb gen.\n\nmodel model_" + g.name + " {\n\tmesh\t" + paths.mesh + "\n";
    if (g.modelOffset.norm() > 0) {
        const decl::Vec3 o = vec(g.modelOffset, 9);
        const auto num = [](double v) {
            std::string s = std::to_string(v);
            s.erase(s.find_last_not_of('0') + 1);
            if (s.back() == '.') s.pop_back();
            return s == "-0" ? std::string("0") : s;
        };
        text += "\toffset ( " + num(o.x) + " " + num(o.y) + " " + num(o.z) + " )\n";
    }
    text += "\tanim af_pose\t" + paths.afPose + "\n}\n\n";
    text += "entityDef " + g.name + " {\n\t\"spawnclass\"\t\"idAFEntity_Generic\"\n\t\"model\"\t\"model_" + g.name +
            "\"\n\t\"articulatedFigure\"\t\"" + g.name + "\"\n}\n";
    return text;
}

bool writeContent(const Generated& g, const std::filesystem::path& dir, text::Diagnostics& diagnostics) {
    const ContentPaths paths = contentPaths(g.name);
    const std::pair<std::string, std::string> files[] = {
        {paths.af, decl::writeAf(g.af)},
        {paths.def, defText(g)},
        {paths.mesh, decl::writeMd5Mesh(g.mesh)},
        {paths.afPose, decl::writeMd5Anim(g.afPose)},
    };
    for (const auto& [rel, text] : files) {
        const std::filesystem::path p = dir / rel;
        std::error_code ec;
        std::filesystem::create_directories(p.parent_path(), ec);
        std::ofstream f(p, std::ios::binary | std::ios::trunc);
        f << text;
        if (!f) {
            diagnostics.error({p.string(), 0, 0}, "cannot write the file");
            return false;
        }
    }
    return true;
}

std::string figureNameFor(const std::filesystem::path& model) {
    std::string name = model.stem().string();
    for (char& c : name)
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') c = '_';
    if (name.empty() || std::isdigit(static_cast<unsigned char>(name[0]))) name = "figure_" + name;
    return name;
}

} // namespace afb::gen
