// Methods: the knob table and the named presets (docs/methods.md has the measurements behind each preset).
#include "afb/bullet/Method.h"

#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>

namespace afb::bullet {
namespace {

constexpr std::array<std::string_view, 8> kPresetNames = {"fast",     "balanced", "iterative", "default",
                                                          "accurate", "exact",    "legacy",    "multibody"};

const std::array<MethodKnob, 32> kKnobs = {{
    {"backend", "Simulation backend: rigid (btRigidBody + constraints) or multibody (btMultiBody)", &Method::backend},
    {"substeps", "Substeps per frame (each of dt / substeps)", &Method::substeps},
    {"impact-substeps",
     "Most substeps of a frame while a ragdoll and another object's dynamic body close fast (1: off)",
     &Method::impactSubsteps},
    {"iterations", "Solver iterations of the world (contacts)", &Method::iterations},
    {"joint-iterations", "Solver iterations of the figure's joints and limits (0: the world's)",
     &Method::jointIterations},
    {"solver-tolerance", "Stop iterating once no row's velocity changes more than its root (m^2/s^2; 0: never)",
     &Method::solverTolerance},
    {"split-impulse", "Bullet's split impulse for contact penetration (on/off)", &Method::splitImpulse},
    {"contact-erp", "Error reduction per step of contact penetration", &Method::contactErp},
    {"joint-erp", "Error reduction per step of Bullet's joint rows", &Method::jointErp},
    {"limit-erp", "Error reduction per step of limit rows", &Method::limitErp},
    {"warm-starting", "Warm starting of contact and joint rows (on/off)", &Method::warmStarting},
    {"warm-starting-factor", "Fraction of the last impulse a row starts from", &Method::warmStartingFactor},
    {"friction-directions",
     "Friction rows per contact point: 1 (Bullet's default, the sliding direction) or 2 "
     "(both tangents)",
     &Method::frictionDirections},
    {"position-iterations", "Position sweeps after each substep over joints, limits and contacts (0: off)",
     &Method::positionIterations},
    {"position-tree",
     "After the sweeps, Newton steps over each ragdoll's joint tree: 0 off, 1 anchors, 2 anchors, locked axes and "
     "limits",
     &Method::positionTree},
    {"position-velocity",
     "The part of a body's velocity whose motion the position pass took back is removed (on/off; rigid backend)",
     &Method::positionVelocity},
    {"multipoint-contacts", "Full contact manifolds at first touch (on/off)", &Method::multipointContacts},
    {"speculative-contacts", "Contacts kept from as far as a body travels in a substep (on/off)",
     &Method::speculativeContacts},
    {"self-contact-cap",
     "Warm start of a contact within one ragdoll at most this many times the pair's weight per step (0: no "
     "bound; needs a RagdollSolver)",
     &Method::selfContactCap},
    {"speculative-limits", "Limit rows active before the limit is reached (on/off)", &Method::speculativeLimits},
    {"ccd", "Continuous collision: off or fast-bodies", &Method::ccd},
    {"joint-warm-starting", "Joint rows start from their last impulse (on/off; needs a RagdollSolver)",
     &Method::jointWarmStarting},
    {"limit-warm-starting", "Limit rows start from their last impulse too (on/off; needs a RagdollSolver)",
     &Method::limitWarmStarting},
    {"direct-joints",
     "Joints solved exactly per ragdoll each iteration; contacts and limits move the whole ragdoll "
     "(on/off; needs a RagdollSolver)",
     &Method::directJoints},
    {"figure-iterations",
     "Block mode of the direct joint solve: its iterations, each ending with the ragdolls' contacts and limits "
     "solved together (0: off; needs direct-joints)",
     &Method::figureIterations},
    {"figure-sweeps", "Sweeps over the ragdolls' contacts and limits in each iteration of block mode",
     &Method::figureSweeps},
    {"merge-fixed", "Bodies joined by fixed constraints simulated as one rigid body (on/off)", &Method::mergeFixed},
    {"exempt-overlapping", "Self-collision pairs that overlap at the load pose do not collide (on/off)",
     &Method::exemptOverlapping},
    {"constant-velocity-universal",
     "Universal joints as a constant-velocity constraint whose twist row always exists, not btConeTwist (on/off)",
     &Method::constantVelocityUniversal},
    {"friction-through-figure",
     "Contact friction moves the whole ragdoll as its joints let it, not one body (on/off; needs direct-joints)",
     &Method::frictionThroughFigure},
    {"joint-space",
     "The direct joint solve eliminates each joint's free motions (the articulated-body recursion) rather than its "
     "rows; the same solve, cheaper (on/off; needs direct-joints)",
     &Method::jointSpace},
    {"separated-pairs",
     "Convex pairs apart along the line between their centres skip GJK: the same contacts, cheaper (on/off)",
     &Method::separatedPairs},
}};

// Bounds that keep a method simulable (a solver with 10^6 iterations or an ERP of 5 is a typo, not a method).
struct Range {
    double lo, hi;
};
Range rangeOf(std::string_view knob) {
    if (knob == "substeps") return {1, 64};
    if (knob == "impact-substeps") return {1, 64};
    if (knob == "iterations") return {1, 1000};
    if (knob == "joint-iterations") return {0, 1000};
    if (knob == "figure-iterations") return {0, 1000};
    if (knob == "figure-sweeps") return {1, 1000};
    if (knob == "position-iterations") return {0, 100};
    if (knob == "position-tree") return {0, 2};
    if (knob == "friction-directions") return {1, 2};
    if (knob == "solver-tolerance") return {0, 1e6};
    if (knob == "self-contact-cap") return {0, 1000};
    return {0, 1}; // ERPs and the warm-starting factor
}

std::string formatReal(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    return buf;
}

} // namespace

std::string_view toString(Backend b) {
    switch (b) {
    case Backend::Rigid: return "rigid";
    case Backend::Multibody: return "multibody";
    }
    return "rigid";
}

std::string_view toString(CcdPolicy c) { return c == CcdPolicy::Off ? "off" : "fast-bodies"; }

std::span<const std::string_view> methodPresetNames() { return kPresetNames; }

// The presets (docs/methods.md gives their measured numbers and the reason for each knob):
//  - every preset solves contacts as many times as joints (a joint solved after the contacts stop pushes light
//    feet into the ground), fills contact manifolds at first touch, keeps speculative contacts and limit rows
//    (without them, three of the four figures of the 10 m drop exceed the 0.1 m anchor bound) and runs the
//    position pass;
//  - every preset but legacy warm-starts joint rows (RagdollSolver) and takes plane contacts from the polytope's
//    vertices;
//  - the default (and exact, the same method) solves the joints directly; balanced is the same solve in block mode,
//    fast in block mode with fewer iterations and position steps; accurate is Bullet's iterative solve with our rows
//    in substeps (the lever that cuts the iterative solve's impact error most per unit of cost);
//  - fast, balanced, default and exact merge fixed joints into one body (Method::mergeFixed; docs/performance.md).
Method iterativeJoints(Method method) {
    method.directJoints = false;
    method.figureIterations = 0;
    method.positionTree = 0;
    method.frictionDirections = 1;
    method.constantVelocityUniversal = false;
    method.frictionThroughFigure = false;
    return method;
}

namespace {

// The iterative solve (the previous default): Bullet's sequential impulse over the joint rows, one
// friction direction, the sweeps alone as the position pass.
Method iterative(std::string_view name) {
    Method m = iterativeJoints(Method{});
    m.name = std::string(name);
    m.selfContactCap = 10;
    return m;
}

// afbullet 0.1: Bullet's solver with none of the techniques (a reference).
Method legacyPreset(std::string_view name) {
    Method m = iterative(name);
    m.iterations = 10;
    m.jointIterations = 20;
    m.positionIterations = 0;
    m.multipointContacts = m.speculativeContacts = m.speculativeLimits = m.jointWarmStarting = false;
    m.limitWarmStarting = false;
    m.positionVelocity = false;
    m.selfContactCap = 0;
    m.mergeFixed = false;
    m.exemptOverlapping = false;
    m.constantVelocityUniversal = false;
    m.impactSubsteps = 1;
    m.separatedPairs = false;
    return m;
}

Method fastPreset(std::string_view name) {
    // The default's direct joint solve in block mode (each iteration: the joints exactly, then the ragdolls'
    // contacts and limits together), two iterations, two position sweeps and a tree step over the anchors.
    // Against Bullet's iterative solve with our rows and two sweeps (`iterative:position-iterations=2`, the
    // previous fast): humanoid 46.7 k → 48.9 k instructions, anchors 21 mm → 0.1 mm and limits 14° → 1.9° at
    // 1 m, stress 116 → 136 of 136 runs. The tree step over the limits too (position-tree 2) holds them to 0.6°
    // for 4 % more; without a tree step the anchors open 20 mm at 10 m (docs/methods.md).
    Method m;
    m.name = std::string(name);
    m.figureIterations = 2;
    m.positionIterations = 2;
    m.positionTree = 1;
    return m;
}

Method balancedPreset(std::string_view name) {
    // The default's solve and position pass in block mode, three iterations. Against the default: humanoid
    // 70.5 k → 52.5 k instructions per awake body-step, zsec figures 84 k → 56 k; worst over the humanoid and
    // the three zsec figures at 4 yaws, 1 m 0.1 mm / 0.1° / 5 mm → 0.1 mm / 0.7° / 7 mm, 10 m 0.1 mm / 1.1° /
    // 25 mm → 0.8 mm / 0.5° / 9 mm; stress 135 → 136 of 136 runs. Its few passes over the rows taken in turn
    // leave joint friction less converged: a humanoid dropped upright from 1 m stands 0.9 s where the default
    // and converged solves stand 1.7–2.2 s, so 160 of them come to rest lying rather than standing (0.35× plain
    // Bullet's CPU per body-step against the default's 0.12×; dropped tumbled, both about a third).
    // Two iterations cost 1.2 k less but leave more penetration (9 / 12 / 30 mm at 1 / 10 / 100 m against
    // 7 / 9 / 22); four fail 12 stress runs (docs/methods.md).
    Method m;
    m.name = std::string(name);
    m.figureIterations = 3;
    return m;
}

// The iterative solve in 2 substeps.
Method accuratePreset(std::string_view name) {
    Method m = iterative(name);
    m.substeps = 2;
    m.jointIterations = 0; // the world's 20
    // The constant-velocity universal joint: stress 124 → 135 of 136 runs, humanoid rows at 24 yaws 150 → 188
    // of 192 (docs/stability.md).
    m.constantVelocityUniversal = true;
    m.positionIterations = 2;
    // Merged, a humanoid's forearm went into its torso at the 1 m drop (right shoulder 15.5 mm / 8.5° against
    // 8.8 mm / 4.5°), though the stress matrix gains (docs/performance.md).
    m.mergeFixed = false;
    return m;
}

Method defaultPreset(std::string_view name) {
    // The direct joint solve (RagdollSolver): joints exact at the velocity level, and contacts and limits
    // against the whole ragdoll's mass (Method's defaults). The iterative default it replaced
    // left 20 mm / 11° at 1 m; four substeps of ten iterations reached 11 mm / 9° at 1 m and 60 mm / 54° at
    // 10 m for 0.94× this cost's predecessor (docs/methods.md). The velocity-exact joints still drift at the
    // position level (rotation is integrated, not linear: about ½·ω²·r·dt² per step, 25 mm at impact without
    // a position pass); the sweeps leave 3.6 mm, the tree step after them 0.1 mm. The tree step also puts
    // limits back (positionTree 2: the ankle stayed 3.8° past its stop at 1 m with anchors only), moving
    // what is above the ground rather than a foot into it (bodies in contact count 100× heavier there). Both
    // tangents of every contact are held by friction: with Bullet's one sliding direction, a limb resting on
    // the ground or on the figure was kicked every few steps through the other tangent and never rested
    // (stress matrix 96 → 124 of 136 runs). Fewer iterations cost less but rest less often (15: 71.6 k
    // instructions against 77.7 k, 124 stress runs against 134).
    Method m;
    m.name = std::string(name);
    return m;
}

Method multibodyPreset(std::string_view name) {
    // Reduced coordinates: no joint rows to iterate, warm-start or project; contacts as the rigid default's
    // (20 iterations, vertex contacts, speculative, warm-started), limits our own speculative rows, then 4
    // position sweeps over the limits and contacts (docs/methods.md). Continuous collision is
    // the rigid backend's (Bullet's multibody world has none).
    Method m = iterative(name);
    m.backend = Backend::Multibody;
    m.jointIterations = 0;
    m.positionIterations = 4;
    m.jointWarmStarting = m.limitWarmStarting = false;
    m.positionVelocity = false;
    m.ccd = CcdPolicy::Off;
    m.selfContactCap = 0;     // Bullet's multibody solver, not a RagdollSolver
    m.mergeFixed = false;     // a rigid-backend layout
    m.frictionDirections = 2; // what btMultiBodyDynamicsWorld itself sets (SOLVER_USE_2_FRICTION_DIRECTIONS)
    return m;
}

} // namespace

std::optional<Method> methodPreset(std::string_view name) {
    if (name == "legacy") return legacyPreset(name);
    // The previous default, and what a world without a RagdollSolver runs (methodInForce).
    if (name == "iterative") return iterative(name);
    if (name == "fast") return fastPreset(name);
    if (name == "balanced") return balancedPreset(name);
    if (name == "accurate") return accuratePreset(name);
    if (name == "default" || name == "exact") return defaultPreset(name);
    if (name == "multibody") return multibodyPreset(name);
    return std::nullopt;
}

std::span<const MethodKnob> methodKnobs() { return kKnobs; }

const MethodKnob* findKnob(std::string_view name) {
    for (const MethodKnob& k : kKnobs)
        if (k.name == name) return &k;
    return nullptr;
}

std::string knobValue(const Method& m, const MethodKnob& knob) {
    struct Visitor {
        const Method& m;
        std::string operator()(int Method::*f) const { return std::to_string(m.*f); }
        std::string operator()(double Method::*f) const { return formatReal(m.*f); }
        std::string operator()(bool Method::*f) const { return m.*f ? "on" : "off"; }
        std::string operator()(CcdPolicy Method::*f) const { return std::string(toString(m.*f)); }
        std::string operator()(Backend Method::*f) const { return std::string(toString(m.*f)); }
    };
    return std::visit(Visitor{m}, knob.field);
}

std::string setKnob(Method& m, const MethodKnob& knob, std::string_view value) {
    const std::string what = "--" + std::string(knob.name) + " " + std::string(value) + ": ";
    struct Visitor {
        Method& m;
        std::string_view value;
        const std::string& what;
        Range range;
        std::string operator()(int Method::*f) const {
            int v = 0;
            const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), v);
            if (ec != std::errc() || end != value.data() + value.size()) return what + "not an integer";
            if (v < range.lo || v > range.hi)
                return what + "out of range [" + formatReal(range.lo) + ", " + formatReal(range.hi) + "]";
            m.*f = v;
            return {};
        }
        std::string operator()(double Method::*f) const {
            const std::string text(value);
            char* end = nullptr;
            const double v = std::strtod(text.c_str(), &end);
            if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(v)) return what + "not a number";
            if (v < range.lo || v > range.hi)
                return what + "out of range [" + formatReal(range.lo) + ", " + formatReal(range.hi) + "]";
            m.*f = v;
            return {};
        }
        std::string operator()(bool Method::*f) const {
            if (value == "on" || value == "true" || value == "1") m.*f = true;
            else if (value == "off" || value == "false" || value == "0") m.*f = false;
            else return what + "expected on or off";
            return {};
        }
        std::string operator()(CcdPolicy Method::*f) const {
            if (value == "off") m.*f = CcdPolicy::Off;
            else if (value == "fast-bodies") m.*f = CcdPolicy::FastBodies;
            else return what + "expected off or fast-bodies";
            return {};
        }
        std::string operator()(Backend Method::*f) const {
            if (value == "rigid") m.*f = Backend::Rigid;
            else if (value == "multibody") m.*f = Backend::Multibody;
            else return what + "expected rigid or multibody";
            return {};
        }
    };
    return std::visit(Visitor{m, value, what, rangeOf(knob.name)}, knob.field);
}

std::string describe(const Method& m) {
    std::string out = m.name + " (";
    for (std::size_t i = 0; i < kKnobs.size(); ++i) {
        if (i > 0) out += ", ";
        out += std::string(kKnobs[i].name) + " " + knobValue(m, kKnobs[i]);
    }
    return out + ")";
}

} // namespace afb::bullet
