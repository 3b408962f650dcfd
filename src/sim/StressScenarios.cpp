// The stress scenarios (Stress.h): figures written as .af text on a skeleton built in code (so they go through the
// one figure builder, findings and all), and spawns of the bundled humanoid.
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>

#include "afb/decl/AfParser.h"
#include "afb/decl/Md5Anim.h"
#include "afb/decl/Md5Mesh.h"
#include "afb/figure/Skeleton.h"
#include "afb/sim/Stress.h"

namespace afb::sim {
namespace {

constexpr double kMetresPerUnit = 0.0254; // the default UnitSystem: .af numbers are Doom units

// A Doom-unit number as the lexer reads it: fixed notation (no exponent), never a leading-zero integer.
std::string units(double metres) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.6f", metres / kMetresPerUnit);
    return buf;
}
std::string num(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.6f", v);
    return buf;
}
std::string vecUnits(double x, double y, double z) {
    return "( " + units(x) + ", " + units(y) + ", " + units(z) + " )";
}

// One joint of a generated skeleton: model-space position in metres, identity orientation.
struct GenJoint {
    std::string name;
    int parent;
    Eigen::Vector3d positionM;
};

// An md5 skeleton of `joints` (bind pose = af_pose, identity orientations) and a figure built from `afText` on it.
figure::Figure buildGenerated(const std::string& afText, const std::vector<GenJoint>& joints) {
    decl::Md5Mesh mesh;
    decl::Md5Anim anim;
    anim.frameRate = 24;
    for (const GenJoint& j : joints) {
        const Eigen::Vector3d p = j.positionM / kMetresPerUnit;
        mesh.joints.push_back({j.name, j.parent, {p.x(), p.y(), p.z()}, {0, 0, 0}});
        anim.hierarchy.push_back({j.name, j.parent, 0, 0});
        Eigen::Vector3d local = p;
        if (j.parent >= 0) local -= joints[static_cast<std::size_t>(j.parent)].positionM / kMetresPerUnit;
        anim.baseframe.push_back({{local.x(), local.y(), local.z()}, {0, 0, 0}});
    }
    anim.bounds = {{{-1, -1, -1}, {1, 1, 1}}};
    anim.frames = {{}};
    const int last = static_cast<int>(joints.size()) - 1;
    decl::Md5SubMesh sub;
    sub.shader = "stress";
    sub.verts = {{0, 0, 0, 1}, {0, 0, 1, 1}, {0, 0, 2, 1}};
    sub.tris = {{{0, 1, 2}}};
    sub.weights = {{last, 1, {0, 0, 0}}, {last, 1, {1, 0, 0}}, {last, 1, {0, 1, 0}}};
    mesh.meshes.push_back(sub);

    text::Diagnostics diags;
    const auto af = decl::parseAf(afText, "stress.af", diags);
    std::optional<figure::Skeleton> skeleton;
    if (af && !af->decls.empty())
        skeleton = figure::Skeleton::build(mesh, anim, Eigen::Vector3d::Zero(), diags, "stress");
    std::optional<figure::Figure> f;
    if (skeleton) f = figure::buildFigure({&af->decls[0], &*skeleton, {}}, diags);
    // The generators are this file's own text: a failure is a bug here, not bad input.
    if (!f) throw std::logic_error("stress scenario figure does not build:\n" + diags.str() + "\n" + afText);
    return std::move(*f);
}

std::string settings(const std::string& name, bool selfCollision) {
    return "articulatedFigure " + name +
           " {\n\tsettings {\n\t\tmodel \"stress\"\n\t\tfriction 0.01, 0.01, 0.8\n\t\tsuspendSpeed 20, 30, 40, 60\n"
           "\t\tnoMoveTime 1\n\t\tnoMoveTranslation 10\n\t\tnoMoveRotation 10\n\t\tminMoveTime -1\n"
           "\t\tmaxMoveTime -1\n\t\tcontents corpse\n\t\tclipMask solid, corpse\n\t\tselfCollision " +
           std::string(selfCollision ? "1" : "0") + "\n\t}\n";
}

// A box body of `sizeM` centred at `centreM` (model space, axis-aligned) with mass `massKg`, driving `joint`.
std::string boxBody(const std::string& name, const std::string& joint, const Eigen::Vector3d& centreM,
                    const Eigen::Vector3d& sizeM, double massKg) {
    const Eigen::Vector3d h = sizeM / 2;
    const double volumeUnits3 = sizeM.prod() / (kMetresPerUnit * kMetresPerUnit * kMetresPerUnit);
    return "\tbody \"" + name + "\" {\n\t\tjoint \"" + joint + "\"\n\t\tmod orientation\n\t\tmodel box( " +
           vecUnits(-h.x(), -h.y(), -h.z()) + ", " + vecUnits(h.x(), h.y(), h.z()) + " )\n\t\torigin " +
           vecUnits(centreM.x(), centreM.y(), centreM.z()) + "\n\t\tdensity " + num(massKg / volumeUnits3) +
           "\n\t\tcontainedJoints \"" + joint + "\"\n\t}\n";
}

// A chain of boxes along +X from the model origin, each link joined to the previous one by a ball-and-socket
// joint with a cone limit about the chain's axis (apex angle; 0: no limit); the first optionally hangs from the
// world at the origin.
struct Link {
    double lengthM, widthM, massKg;
};
struct ChainSpec {
    std::string name;
    std::vector<Link> links;
    bool worldAttached = false;
    double coneApexDeg = 120;
    bool selfCollision = true;
};

figure::Figure chainFigure(const ChainSpec& spec) {
    std::vector<GenJoint> joints;
    std::string text = settings(spec.name, spec.selfCollision);
    double x = 0;
    for (std::size_t i = 0; i < spec.links.size(); ++i) {
        const Link& l = spec.links[i];
        const std::string joint = i == 0 ? "origin" : "j" + std::to_string(i);
        joints.push_back({joint, static_cast<int>(i) - 1, Eigen::Vector3d(x, 0, 0)});
        text += boxBody("l" + std::to_string(i), joint, Eigen::Vector3d(x + l.lengthM / 2, 0, 0),
                        Eigen::Vector3d(l.lengthM, l.widthM, l.widthM), l.massKg);
        x += l.lengthM;
    }
    joints.push_back({"end", static_cast<int>(spec.links.size()) - 1, Eigen::Vector3d(x, 0, 0)});
    if (spec.worldAttached)
        text += "\tballAndSocketJoint \"hook\" {\n\t\tbody1 \"l0\"\n\t\tbody2 \"world\"\n\t\tanchor joint( \"origin\" "
                ")\n\t\tfriction 0.1\n\t}\n";
    for (std::size_t i = 1; i < spec.links.size(); ++i) {
        const std::string n = std::to_string(i);
        text += "\tballAndSocketJoint \"c" + n + "\" {\n\t\tbody1 \"l" + n + "\"\n\t\tbody2 \"l" +
                std::to_string(i - 1) + "\"\n\t\tanchor joint( \"j" + n + "\" )\n\t\tfriction 0.1\n";
        if (spec.coneApexDeg > 0) text += "\t\tconeLimit ( 1, 0, 0 ), " + num(spec.coneApexDeg) + ", ( 1, 0, 0 )\n";
        text += "\t}\n";
    }
    return buildGenerated(text + "}\n", joints);
}

// The AF guide's warning case: bodies that overlap at the load pose and cannot separate within their limits.
// Three boxes in a U: "a" and "c" (0.4 m long) joined through the short upright "b" by two hinges held to ±2°,
// "c" overlapping "a" by 3 cm (only jointed pairs are exempt from collision), so the contact pushes them apart
// and the limits push them back, in every step.
figure::Figure overlapFigure() {
    const std::vector<GenJoint> joints = {{"origin", -1, {0, 0, 0}},
                                          {"jb", 0, {0.45, 0, 0}},
                                          {"jc", 1, {0.45, 0, 0.07}},
                                          {"end", 2, {0, 0, 0.07}}};
    std::string text = settings("overlap", true);
    text += boxBody("a", "origin", {0.2, 0, 0}, {0.4, 0.1, 0.1}, 5);
    text += boxBody("b", "jb", {0.45, 0, 0.035}, {0.1, 0.1, 0.17}, 2);
    text += boxBody("c", "jc", {0.2, 0, 0.07}, {0.4, 0.1, 0.1}, 5);
    auto hinge = [](const std::string& name, const std::string& b1, const std::string& b2, const std::string& joint) {
        return "\thinge \"" + name + "\" {\n\t\tbody1 \"" + b1 + "\"\n\t\tbody2 \"" + b2 + "\"\n\t\tanchor joint( \"" +
               joint + "\" )\n\t\taxis ( 0, 1, 0 )\n\t\tfriction 0.1\n\t\tlimit 0, 4, 0\n\t}\n";
    };
    text += hinge("ab", "b", "a", "jb") + hinge("bc", "c", "b", "jc");
    return buildGenerated(text + "}\n", joints);
}

Eigen::Matrix3d rotation(const Eigen::Vector3d& axis, double deg) {
    return Eigen::AngleAxisd(deg * std::numbers::pi / 180, axis.normalized()).toRotationMatrix();
}

// The lowest point of `f`'s bodies when turned by `r`, model-space z.
double lowestZ(const figure::Figure& f, const Eigen::Matrix3d& r) {
    double lo = 1e30;
    for (const figure::FigureBody& b : f.bodies)
        for (const Eigen::Vector3d& v : b.shape.vertices) lo = std::min(lo, (r * b.loadPose.apply(v)).z());
    return lo;
}

// The bounds of `f`'s bodies turned by `r`, model space about the origin.
Eigen::AlignedBox3d bounds(const figure::Figure& f, const Eigen::Matrix3d& r) {
    Eigen::AlignedBox3d box;
    for (const figure::FigureBody& b : f.bodies)
        for (const Eigen::Vector3d& v : b.shape.vertices) box.extend(r * b.loadPose.apply(v));
    return box;
}

// A spawn of figure 0 turned by `r` with its lowest point at `heightM` above the ground (negative: inside it).
StressSpawn spawnAt(const figure::Figure& f, const Eigen::Matrix3d& r, double heightM, double x = 0, double y = 0) {
    StressSpawn s;
    s.entity.rotation = r;
    s.entity.position = Eigen::Vector3d(x, y, heightM - lowestZ(f, r));
    return s;
}

// A figure alone, turned by `r`, its lowest point at `heightM`.
StressSetup single(figure::Figure f, const Eigen::Matrix3d& r, double heightM) {
    StressSetup s;
    s.spawns.push_back(spawnAt(f, r, heightM));
    s.figures.push_back(std::move(f));
    return s;
}

// A chain hanging from the world at `heightM`, spawned horizontal (it swings down).
StressSetup hanging(figure::Figure f, double heightM) {
    StressSetup s;
    StressSpawn sp;
    sp.entity.position = Eigen::Vector3d(0, 0, heightM);
    s.spawns.push_back(sp);
    s.figures.push_back(std::move(f));
    return s;
}

// The humanoid's usual drop pose: yaw 37°, tilted 20° about X.
Eigen::Matrix3d humanoidTilt() { return rotation({1, 0, 0}, 20) * rotation({0, 0, 1}, 37); }

std::optional<StressSetup> humanoidDrop(const StressContent& c, double heightM, double hz) {
    if (!c.humanoid) return std::nullopt;
    StressSetup s = single(*c.humanoid, humanoidTilt(), heightM);
    s.hz = hz;
    return s;
}

StressScenario chainMassRatio(int ratio) {
    return {"chain-mass-" + std::to_string(ratio),
            "8-link chain, masses alternating 1 and " + std::to_string(ratio) + " kg, dropped 1 m tilted 20°", false,
            [ratio](const StressContent&) -> std::optional<StressSetup> {
                ChainSpec spec{"chain_mass_" + std::to_string(ratio), {}};
                for (int i = 0; i < 8; ++i) spec.links.push_back({0.3, 0.06, i % 2 == 0 ? 1.0 : double(ratio)});
                return single(chainFigure(spec), rotation({0, 1, 0}, 20), 1.0);
            }};
}

// The built figures: chains of mass and inertia ratios, ropes, overlapping bodies, tiny bodies.
void addBuiltScenarios(std::vector<StressScenario>& out) {
    for (int ratio : {1, 10, 100, 1000}) out.push_back(chainMassRatio(ratio));
    out.push_back({"thin-rods", "4 rods 1 m x 2 cm (inertia ratio 1250:1, floored at 1000:1), dropped 1 m tilted 20°",
                   false, [](const StressContent&) -> std::optional<StressSetup> {
                       ChainSpec spec{"thin_rods", {}};
                       for (int i = 0; i < 4; ++i) spec.links.push_back({1.0, 0.02, 1.0});
                       return single(chainFigure(spec), rotation({0, 1, 0}, 20), 1.0);
                   }});
    out.push_back({"rope-30", "30 links of 10 x 2 cm, 0.1 kg, hung from the world at 4 m, released horizontal", false,
                   [](const StressContent&) -> std::optional<StressSetup> {
                       ChainSpec spec{"rope", {}, true};
                       for (int i = 0; i < 30; ++i) spec.links.push_back({0.1, 0.02, 0.1});
                       return hanging(chainFigure(spec), 4.0);
                   }});
    out.push_back({"heavy-weight",
                   "5 links of 1 kg hung from the world at 3 m with a 100 kg block, released horizontal", false,
                   [](const StressContent&) -> std::optional<StressSetup> {
                       ChainSpec spec{"heavy_weight", {}, true};
                       for (int i = 0; i < 5; ++i) spec.links.push_back({0.3, 0.04, 1.0});
                       spec.links.push_back({0.3, 0.3, 100.0});
                       return hanging(chainFigure(spec), 3.0);
                   }});
    out.push_back({"overlap",
                   "3 bodies overlapping 3 cm at the load pose, held by ±2° hinges (AF guide), dropped 0.5 m", false,
                   [](const StressContent&) -> std::optional<StressSetup> {
                       return single(overlapFigure(), Eigen::Matrix3d::Identity(), 0.5);
                   }});
    out.push_back({"tiny-bodies", "5 cubes of 1 cm, 50 g, chained, dropped 1 m tilted 20°", false,
                   [](const StressContent&) -> std::optional<StressSetup> {
                       ChainSpec spec{"tiny", {}};
                       for (int i = 0; i < 5; ++i) spec.links.push_back({0.01, 0.01, 0.05});
                       return single(chainFigure(spec), rotation({0, 1, 0}, 20), 1.0);
                   }});
}

// The bundled humanoid alone: drops from height and at coarse steps, a spin, spawned in the ground or outside its
// limits, hit while lying.
void addHumanoidScenarios(std::vector<StressScenario>& out) {
    out.push_back({"humanoid-drop-10m", "bundled humanoid dropped 10 m", true,
                   [](const StressContent& c) { return humanoidDrop(c, 10, 60); }});
    out.push_back({"humanoid-drop-100m", "bundled humanoid dropped 100 m", true,
                   [](const StressContent& c) { return humanoidDrop(c, 100, 60); }});
    out.push_back({"humanoid-30hz", "humanoid dropped 1 m at 30 Hz (dt 1/30 s)", true,
                   [](const StressContent& c) { return humanoidDrop(c, 1, 30); }});
    out.push_back({"humanoid-15hz", "humanoid dropped 1 m at 15 Hz (dt 1/15 s)", true,
                   [](const StressContent& c) { return humanoidDrop(c, 1, 15); }});
    out.push_back({"humanoid-spin", "humanoid spinning at 20 rad/s about a horizontal axis, 2 m up", true,
                   [](const StressContent& c) -> std::optional<StressSetup> {
                       auto s = humanoidDrop(c, 2, 60);
                       if (s) s->spawns[0].angularVelocity = Eigen::Vector3d(1, 1, 0).normalized() * 20;
                       return s;
                   }});
    out.push_back({"humanoid-in-ground", "humanoid upright, spawned with its lowest 10 cm inside the ground", true,
                   [](const StressContent& c) -> std::optional<StressSetup> {
                       if (!c.humanoid) return std::nullopt;
                       StressSetup s = single(*c.humanoid, rotation({0, 0, 1}, 37), -0.1);
                       s.spawnGraceS = 0.25;
                       return s;
                   }});
    out.push_back({"humanoid-outside-limits", "humanoid with knees and elbows spawned 20° outside their hinge ranges",
                   true, [](const StressContent& c) -> std::optional<StressSetup> {
                       if (!c.humanoid) return std::nullopt;
                       figure::Figure f = *c.humanoid;
                       f.name += "_outside_limits";
                       // Shift each hinge range so the load pose (φ = 0) lies 20° below its lower end.
                       for (figure::FigureConstraint& k : f.constraints)
                           if (auto* r = std::get_if<figure::HingeRange>(&k.limit)) {
                               const double shift = 20 * std::numbers::pi / 180 - r->lowerRad;
                               r->lowerRad += shift;
                               r->upperRad += shift;
                           }
                       StressSetup s = single(std::move(f), humanoidTilt(), 0.5);
                       s.spawnGraceS = 0.25;
                       return s;
                   }});
    out.push_back({"humanoid-projectile", "humanoid lying on the ground, hit at the torso by 500 kg·m/s after 1 s",
                   true, [](const StressContent& c) -> std::optional<StressSetup> {
                       if (!c.humanoid) return std::nullopt;
                       StressSetup s = single(*c.humanoid, rotation({0, 1, 0}, -90), 0.02);
                       int torso = 0;
                       for (std::size_t i = 0; i < s.figures[0].bodies.size(); ++i)
                           if (s.figures[0].bodies[i].name == "torso") torso = static_cast<int>(i);
                       s.impulse = StressImpulse{1.0, 0, torso, Eigen::Vector3d(0, 500, 0)};
                       return s;
                   }});
}

// `count` humanoids dropped in a pile, two side by side per layer, each layer turned 37° from the one below.
StressScenario humanoidPile(int count) {
    const int layers = (count + 1) / 2;
    const std::string description = std::to_string(count) + " humanoids lying, " + std::to_string(layers) +
                                    " layers of 2 over one spot, dropped from 0.5 m up";
    return {"humanoid-pile-" + std::to_string(count), description, true,
            [count](const StressContent& c) -> std::optional<StressSetup> {
                if (!c.humanoid) return std::nullopt;
                StressSetup s;
                s.figures.push_back(*c.humanoid);
                const Eigen::Matrix3d lying = rotation({0, 1, 0}, -90);
                const Eigen::AlignedBox3d box = bounds(s.figures[0], lying);
                const double thickness = box.sizes().z() + 0.05, lateral = box.sizes().y() / 2 + 0.03;
                for (int i = 0; i < count; ++i) {
                    const int layer = i / 2;
                    const Eigen::Matrix3d yaw = rotation({0, 0, 1}, 37.0 * layer);
                    const Eigen::Vector3d offset = yaw * Eigen::Vector3d(0, i % 2 == 0 ? -lateral : lateral, 0);
                    s.spawns.push_back(
                        spawnAt(s.figures[0], yaw * lying, 0.5 + thickness * layer, offset.x(), offset.y()));
                }
                return s;
            }};
}

std::vector<StressScenario> makeScenarios() {
    std::vector<StressScenario> out;
    addBuiltScenarios(out);
    addHumanoidScenarios(out);
    // The small pile shows in seconds of CPU what the large one shows in minutes (a heap that creeps on physics
    // alone); the large one is the scale a game's battlefield reaches.
    out.push_back(humanoidPile(12));
    out.push_back(humanoidPile(160));
    return out;
}
} // namespace

const std::vector<StressScenario>& stressScenarios() {
    static const std::vector<StressScenario> scenarios = makeScenarios();
    return scenarios;
}

const StressScenario* findStressScenario(std::string_view name) {
    for (const StressScenario& s : stressScenarios())
        if (s.name == name) return &s;
    return nullptr;
}

std::vector<std::string_view> stressCiScenarios() {
    return {"chain-mass-100",    "chain-mass-1000",    "rope-30", "heavy-weight", "tiny-bodies",
            "humanoid-drop-10m", "humanoid-projectile"};
}

} // namespace afb::sim
