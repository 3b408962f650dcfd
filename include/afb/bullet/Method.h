#pragma once
// How a ragdoll is simulated: one plain value holding every knob that trades speed against accuracy, chosen per
// world (the world-level knobs) and per ragdoll (the rest), and recorded with every result (drop reports,
// goldens, charts). Named presets go from fast to exact; docs/methods.md describes each knob and preset.
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

/// The Bullet layer: a Figure as a live ragdoll in a btDiscreteDynamicsWorld (Ragdoll), its shared shapes
/// (RagdollAsset), how it is stepped (Method) and the world-level parts of that (RagdollWorld, RagdollSolver).
namespace afb::bullet {

/// Which representation simulates the figure.
enum class Backend {
    Rigid, ///< one btRigidBody per body, joined by btTypedConstraints (maximal coordinates)
    /// one btMultiBody per connected part of the figure (reduced coordinates, Featherstone): its joints cannot
    /// separate. Needs a btMultiBodyDynamicsWorld. Knobs that apply: substeps, iterations, solver-tolerance,
    /// contact-erp, joint-erp (loop joints and universal joints' twist), limit-erp, speculative-limits,
    /// position-iterations (limits and contacts), warm-starting (contacts, limits and loop joints),
    /// warm-starting-factor, multipoint-contacts and speculative-contacts; the rest are the rigid backend's and
    /// are ignored.
    Multibody,
};

/// Which bodies Bullet sweeps continuously between steps.
enum class CcdPolicy {
    Off,        ///< discrete collision only
    FastBodies, ///< a body moving more than its inner radius in a step is swept as a sphere of that radius
};

/// The closing distance per substep between a ragdoll body and another object's dynamic body above which
/// Method::impactSubsteps divides a frame further, metres.
inline constexpr double kImpactTravelM = 0.05;

/// Every knob of how a figure is stepped. A plain, comparable value: copy it, change a field, pass it on.
/// Default-constructed, it is the "default" preset.
struct Method {
    /// The preset the value started from ("default", "fast", …), for reports; overrides do not rename it.
    std::string name = "default";
    Backend backend = Backend::Rigid; ///< which representation simulates the figure (chosen at spawn)

    // --- world-level knobs (applied to the world by RagdollWorld; shared by everything in that world) -----------
    /// Substeps per frame: each frame of dt is stepped as `substeps` steps of dt / substeps.
    int substeps = 1;
    /// The most substeps a frame may take while a ragdoll body and a dynamic body of another object (another
    /// ragdoll, a game's body) close on each other fast: a frame whose contacts of the last step close faster than
    /// kImpactTravelM per substep is stepped in as many more substeps as keep it under that, up to this number
    /// (1: off; `substeps` stays the least). A single ragdoll (its own bodies, the ground, static objects) never
    /// takes more. Substeps are the world's: the frame's other objects take them too. It keeps colliding ragdolls
    /// out of each other for far less CPU than more substeps on every frame (docs/stability.md). On in every
    /// preset but legacy (afbullet 0.1's method).
    int impactSubsteps = 4;
    /// Sequential-impulse iterations of the world's solver (contacts, and joints without their own count).
    int iterations = 20;
    /// The solver stops iterating early once no row's velocity changes by more than sqrt(this) in an iteration
    /// (the largest squared change, m²/s² or rad²/s²; btContactSolverInfo::m_leastSquaresResidualThreshold).
    /// 0: always run every iteration. A converged step (free fall, rest, warm-started load) then costs a few
    /// iterations, and an impact gets them all.
    double solverTolerance = 0;
    /// Bullet's split impulse: contact penetration is recovered by a separate position-only impulse that adds
    /// no velocity (no bounce out of the ground); off, penetration is recovered by Baumgarte velocity.
    bool splitImpulse = true;
    /// Error reduction per step of contact penetration (btContactSolverInfo::m_erp2).
    double contactErp = 0.2;
    /// Error reduction per step of Bullet's joint rows (btContactSolverInfo::m_erp): anchor separation and
    /// locked axes of point-to-point, hinge, cone-twist, slider and fixed constraints.
    double jointErp = 0.2;
    /// Warm starting: each contact row starts from a fraction of its last impulse (joint rows too where
    /// jointWarmStarting is on; Bullet itself starts them from zero).
    bool warmStarting = true;
    /// That fraction (btContactSolverInfo::m_warmstartingFactor).
    double warmStartingFactor = 0.85;
    /// Friction rows per contact point: 1 (Bullet's default: one row along the sliding direction, or along an
    /// arbitrary tangent when the point barely moves, so nothing holds the other tangent) or 2 (both tangents,
    /// SOLVER_USE_2_FRICTION_DIRECTIONS). With one, nothing holds a resting limb under `directJoints` along the
    /// other tangent, and it does not come to rest (docs/methods.md). 2 in default, exact and multibody (Bullet's
    /// multibody world sets it itself); 1 in the iterative presets.
    int frictionDirections = 2;
    /// Nonlinear Gauss–Seidel position sweeps after each substep over every ragdoll's joints, limits and
    /// contacts (Jolt's position steps, "post-stabilisation"): bodies are moved, velocities are left as the
    /// velocity solve made them. 0 = off. Runs where a RagdollWorld manages the world. A multibody ragdoll
    /// (Backend::Multibody) runs its own sweeps over its limits and contacts, in any world, from its
    /// SpawnOptions::method.
    int positionIterations = 4;
    /// After the sweeps, Newton steps over each ragdoll's joint tree (its bodies' masses, Baraff's factorisation,
    /// as the direct velocity solve uses), which close every joint at once instead of one after another:
    /// 0 = off; 1 = the anchors (to 0.1 mm); 2 = also the locked axes and the limit rows past their limit. The
    /// step does not include contacts: 2 holds limits closely but can push limbs deeper into the ground
    /// (docs/methods.md). Joints that close a loop and sliders are left to the sweeps.
    int positionTree = 2;
    /// Velocities follow the position pass: a body the pass moved back against the motion its velocity made in the
    /// substep loses that part of its velocity (the fraction of v·dt the pass undid along v, and the same for ω).
    /// Without it a velocity the pass reverts every substep lives on: a limb keeps spinning while its pose stands
    /// still, and the figure never comes to rest (docs/methods.md). Only ever reduces a speed along its own
    /// direction. Rigid backend; the multibody backend's sweeps ignore it.
    bool positionVelocity = true;
    /// Full contact manifolds on planes: hulls and boxes against a static plane take their contact points from
    /// the (up to four) vertices that come nearest the plane within the step, kept from step to step by vertex
    /// (afbullet's own polytope–plane algorithm; Bullet's finds one point per step, and its manifold merges
    /// speculative points into one another), so a body landing flat or rolling onto a face is held at its
    /// corners; other convex shapes get Bullet's perturbed points. Registered in the world's dispatcher, so it
    /// applies to every hull and box against a plane in that world, the game's too.
    bool multipointContacts = true;
    /// Speculative contacts: Bullet keeps a ragdoll body's contacts from as far as the body can travel in one
    /// substep, so the solver stops an approaching body at the surface instead of finding it inside one step
    /// later (Bullet treats contacts at a positive distance as speculative). Runs where a RagdollWorld manages
    /// the world; the engine's restitution then applies only to touching contacts.
    bool speculativeContacts = true;
    /// Warm start of a contact between two bodies of one ragdoll (self-collision) carries at most this many
    /// times the pair's weight per step (m_a + m_b)·g·dt, g the world's gravity but at least 9.81 m/s² (a
    /// weightless world would otherwise cold-start every self-contact); 0: no bound (Bullet's warm start). A forearm
    /// pressed into the torso closes a loop through shoulder and elbow that Bullet's iterative joint solve cannot
    /// satisfy; warm-started without a bound, the contact's impulse and the elbow's opposing row grow every step
    /// while the forearm sinks into the torso (docs/methods.md). Much lower bounds let a limb lying under the torso
    /// pull off its joint. 10 in iterative and accurate; off (0) in the presets with the direct joint solve, whose
    /// exact joints leave no such fight: there the bound changes no drop and no stress run, and without it the
    /// 160-humanoid pile's deepest contacts are 26–44 mm instead of 30–50 mm (docs/stability.md). Needs a
    /// RagdollSolver; no effect without it.
    double selfContactCap = 0;

    // --- per-ragdoll knobs (SpawnOptions::method) ---------------------------------------------------------------
    /// Solver iterations of the figure's joints and limits (btTypedConstraint's per-constraint override), or 0
    /// for the world's count. Contacts keep the world's count.
    int jointIterations = 20;
    /// Error reduction per step of limit rows (cone, pyramid, hinge range; the engine's LIMIT_ERROR_REDUCTION).
    double limitErp = 0.3;
    /// Speculative limits: a limit row exists before the limit is reached and lets the joint close only the gap
    /// that remains in this step (Box2D v3's joint limits), instead of a row that appears after the overshoot.
    /// Cone and hinge limits then use afbullet's own rows instead of btConeTwist's and btHinge's.
    bool speculativeLimits = true;
    /// Continuous collision policy.
    CcdPolicy ccd = CcdPolicy::FastBodies;
    /// Warm-started joint rows: every row of the figure's joints and joint friction (not of its limits) starts
    /// from the warm-starting factor times its last impulse, as contacts do, instead of from zero (Bullet's solver
    /// rebuilds a joint's impulse from nothing every substep, so a figure carrying its weight sags at its joints and
    /// limits). Needs the world's solver to be a RagdollSolver (sim::Scene's is); with any other solver it has no
    /// effect.
    bool jointWarmStarting = true;
    /// Warm-started limit rows (cone, pyramid and hinge-range rows, speculative or not): they start from the
    /// warm-starting factor times their last impulse too, so a limit carrying a limb's weight does not give a little
    /// every substep. Needs a RagdollSolver; no effect without it.
    bool limitWarmStarting = true;
    /// Direct joint solve: every solver iteration solves the figure's joints (anchors and locked axes) exactly, one
    /// linear system per ragdoll, and each contact, friction and limit row moves the whole ragdoll as its joints
    /// let it (its effective mass is the ragdoll's at that point, not the touching body's alone), so a landing foot
    /// stops the body above it within the iteration instead of one link per iteration. Needs the world's solver to
    /// be a RagdollSolver; set for the world by RagdollWorld from its method (a ragdoll takes part when its own
    /// method has it on; without a RagdollSolver the world falls back to the iterative solve, methodInForce). On in
    /// default and exact.
    bool directJoints = true;
    /// Block mode of the direct joint solve (directJoints only; a world-level knob): the solve of an island holding
    /// a ragdoll takes this many iterations (0: off, the world's iterations as directJoints describes). Each solves
    /// the rows of Bullet's one-body response in turn (contact friction, joint friction, contacts within one ragdoll,
    /// rows of other bodies), then the joints exactly, then every contact and limit row that moves a whole ragdoll
    /// together: figureSweeps Gauss–Seidel sweeps over their couplings (how each row's velocity moves per unit
    /// impulse of the others through the ragdolls), the impulses applied to the bodies once. A sweep costs a
    /// product over those rows instead of a pass over every body of the figure per row, so contacts and limits
    /// converge within each iteration and few iterations are needed. A game's bodies in the same island are solved
    /// in these iterations too; rows between a game's bodies alone then take the rest of the world's iterations.
    /// Motors are soft rows of the same solve. 2 in fast, 3 in balanced, off (0) in the other presets
    /// (docs/methods.md has its measurements).
    int figureIterations = 0;
    /// Gauss–Seidel sweeps over the block in each iteration of block mode (figureIterations); they stop early once
    /// no row's velocity changes by more than the square root of solverTolerance.
    int figureSweeps = 10;
    /// Bodies joined by `fixed` constraints become one btRigidBody (a compound of their shapes, the exact combined
    /// mass properties on principal axes) instead of bodies held together by constraint rows: a fixed joint costs
    /// nothing and cannot give. Every figure body keeps its pose (bodyTransforms, the skeleton). Rigid backend only.
    /// Spawned through a RagdollWorld, each part of a merged body makes the contacts it made unmerged (speculative
    /// reach, self-collision pairs); in a plain world Bullet's compound algorithm runs. On in fast, default and
    /// exact; off in accurate, legacy and multibody (docs/performance.md).
    bool mergeFixed = true;
    /// Self-collision pairs that overlap at the load pose (RagdollAsset::overlappingPairs) do not collide. Their
    /// contact fights the joints from the first step; held by limits that do not let them part (the AF guide's
    /// warning case), it never ends: the figure creeps across the ground and never rests (docs/stability.md).
    /// Jolt does the same for pairs overlapping in a given pose. Off in legacy (the engine's behaviour). Both
    /// backends.
    bool exemptOverlapping = true;
    /// A universal joint is our constant-velocity constraint (UniversalConstraint: the anchors, and no relative
    /// spin about the bisector of the two shafts, a row that always exists) instead of btConeTwistConstraint with a
    /// twist span of 0, whose twist row exists only while the twist is above zero and whose axis turns over with
    /// its sign: at rest the hips, shoulders and waist toggle it, and a leg held by joint friction is kicked every
    /// few steps (docs/stability.md). On in fast, default and accurate; off in iterative and legacy
    /// (iterativeJoints turns it off: under Bullet's iterative joint solve the cone-twist holds the hips better).
    /// Rigid backend.
    bool constantVelocityUniversal = true;
    /// Contact friction rows move the whole ragdoll as its joints let it (the direct joint solve's response, as
    /// its contact and limit rows do) instead of Bullet's one-body response (directJoints only; a contact between
    /// two bodies of one ragdoll keeps Bullet's response either way). With one-body friction, the friction rows
    /// that come last in each iteration leave the joints they disturbed for the next iteration's joint solve: a
    /// humanoid lying still ends every step with its hips and knees turning apart, which the position pass then
    /// takes back. Through the figure the solve converges and figures come to rest sooner, for more work per awake
    /// body-step. Off in every preset (docs/methods.md, docs/performance.md).
    bool frictionThroughFigure = false;
    /// Under the direct joint solve, a ragdoll whose joints are all point joints with locked axes (ball,
    /// universal, hinge), stiff or driven by unbounded motors, is solved in joint space: each joint's free motions are
    /// eliminated from the leaves to the root (the articulated-body recursion), the same system the tree of bodies and
    /// joints solves otherwise, for fewer operations. Results agree to rounding. On in every preset; off exists to
    /// compare the two (docs/methods.md).
    bool jointSpace = true;
    /// Convex pairs whose bounding boxes overlap but whose shapes are apart along the line between their centres
    /// (by more than the manifold keeps points at) skip Bullet's GJK: the contacts are the same bit for bit, found
    /// for less (docs/performance.md). On in every preset but legacy; plain Bullet has no such test.
    bool separatedPairs = true;

    /// Equal when the name and every knob are.
    friend bool operator==(const Method&, const Method&) = default;
};

/// The named presets: "fast" (the default's direct joint solve in block mode: 2 iterations, 2 position sweeps, a tree
/// step over the anchors), "balanced" (the default in block mode, 3 iterations), "iterative" (the default's knobs
/// with Bullet's iterative joint solve, iterativeJoints),
/// "default", "accurate", "exact" (the default's method under its earlier name, which recorded results still carry),
/// "legacy" (afbullet 0.1's method: Bullet's solver with 20 joint iterations and none of the techniques above, kept for
/// comparison) and "multibody" (the reduced-coordinate backend, one step per frame, 20 iterations, speculative limits).
std::span<const std::string_view> methodPresetNames();
/// The preset called `name`, or nullopt for an unknown name.
std::optional<Method> methodPreset(std::string_view name);
/// `method` with Bullet's iterative joint solve in place of the direct one: direct-joints off, position-tree 0,
/// friction-directions 1, universal joints as btConeTwist (constantVelocityUniversal off). Of the default, the
/// preset "iterative", and what a world without a RagdollSolver runs (methodInForce).
Method iterativeJoints(Method method);

/// One knob of a Method, by the name the CLI, JSON reports and goldens use ("substeps", "joint-iterations", …).
struct MethodKnob {
    std::string_view name; ///< kebab-case: the CLI flag without "--", and the JSON key
    std::string_view help; ///< one line for --help
    /// The field: an integer, a real, a flag, or an enum spelled as text.
    std::variant<int Method::*, double Method::*, bool Method::*, CcdPolicy Method::*, Backend Method::*> field;
};

/// Every knob of Method, in a fixed order (the one table that names them; the preset name is not a knob).
std::span<const MethodKnob> methodKnobs();

/// The knob's value in `m`, as text: integers and reals as numbers, flags "on"/"off", enums by name.
std::string knobValue(const Method& m, const MethodKnob& knob);
/// Sets the knob from text (as knobValue writes it; flags also true/false/1/0). Returns an error message, or
/// an empty string on success; `m` is unchanged on error. Reals and integers must be finite and in range.
std::string setKnob(Method& m, const MethodKnob& knob, std::string_view value);
/// The knob called `name`, or nullptr.
const MethodKnob* findKnob(std::string_view name);

/// "default (substeps 1, iterations 10, …)": the preset name and every knob, for reports.
std::string describe(const Method& m);

/// The backend's name as knobs spell it: "rigid" or "multibody".
std::string_view toString(Backend b);
/// The policy's name as knobs spell it: "off" or "fast-bodies".
std::string_view toString(CcdPolicy c);

} // namespace afb::bullet
