#pragma once
// A built articulated figure: everything the engine means by an `.af` decl on a given skeleton, in SI units
// and standard (column-vector) math, ready for any physics backend. A plain value, built once and shared by
// every live ragdoll made from it: values in, values out.
#include <cstdint>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "afb/decl/Af.h"
#include "afb/figure/Skeleton.h"
#include "afb/figure/Transform.h"
#include "afb/figure/Vocabulary.h"
#include "afb/text/Diagnostics.h"

/// The figure layer: an `.af` decl on an md5 skeleton, built into a Figure in SI units with the engine's meaning,
/// and the placement, mass, limit and level-of-detail helpers that work on it. Bullet-free.
namespace afb::figure {

/// The one unit conversion, applied where the figure is built: Doom units and steps to SI.
struct UnitSystem {
    double metresPerUnit = 0.0254;    ///< length of one Doom unit (1 inch by default)
    double gravityMps2 = 9.81;        ///< gravity magnitude along −Z, m/s² (Doom: 1066 units/s² ≈ 27.08 m/s²)
    double engineStepSeconds = 0.016; ///< the engine's fixed step (USERCMD_MSEC = 16 ms) for per-step friction

    /// Doom's own gravity, 1066 units/s², in m/s² for this unit length.
    double doomGravityMps2() const { return 1066.0 * metresPerUnit; }
};

/// How a body drives its md5 joint (docs/format.md §2.3, §5.1).
enum class JointMod : std::uint8_t {
    Orientation, ///< the body sets the joint's rotation only (the engine's fallback for an unknown `mod`)
    Position,    ///< the body sets the joint's position only
    Both,        ///< the body sets the joint's rotation and position
};

/// A body's collision geometry in its body frame (centre of mass, principal axes), metres.
struct BodyShape {
    ShapeType kind = ShapeType::Box;       ///< what the polytope was built as
    std::vector<Eigen::Vector3d> vertices; ///< the engine's exact polytope, body frame, metres
    std::vector<std::vector<int>> faces;   ///< outward counter-clockwise vertex loops
    /// Set when the shape is a box whose axes are the principal axes: its half extents, metres.
    std::optional<Eigen::Vector3d> boxHalfExtents;
    int sidesUsed = 0; ///< cylinder/cone: sides after the engine's clamps; 0 otherwise
};

/// One rigid body of the figure.
struct FigureBody {
    std::string name;                     ///< as written in the decl
    text::SourceLocation location;        ///< the body block
    int joint = -1;                       ///< md5 joint this body drives (origin body: first child of "origin")
    std::string jointName;                ///< the decl's joint name
    JointMod mod = JointMod::Orientation; ///< what the body drives of its joint (pose::driveSkeleton)
    BodyShape shape;                      ///< collision geometry, body frame, metres
    double volumeM3 = 0;                  ///< polytope volume
    double massKg = 0; ///< after density, the invalid-mass rule and totalMass scaling (docs/format.md §3.3)
    Eigen::Vector3d inertiaKgM2 = Eigen::Vector3d::Ones(); ///< principal moments about the body frame axes
    /// Body frame (centre of mass, principal axes) in model space at the load pose, metres.
    Transform loadPose;
    /// The driven joint's load-pose frame expressed in the body frame (inverse of the docs/format.md §2.3 joint→body
    /// offset).
    Transform jointInBody;
    /// The engine's per-step linear velocity loss fraction (docs/format.md §3.4); see UnitSystem::engineStepSeconds.
    double linearFrictionPerStep = 0.01;
    /// The engine's per-step angular velocity loss fraction (docs/format.md §3.4).
    double angularFrictionPerStep = 0.01;
    double linearDamping = 0;                 ///< the same loss per second as Bullet damping: 1 − (1 − f)^(1/step)
    double angularDamping = 0;                ///< likewise for angular velocity
    double contactFriction = 0.8;             ///< Coulomb coefficient; pairs combine by minimum (docs/format.md §4.8)
    bool selfCollision = true;                ///< the body's own flag (docs/format.md §6.2)
    std::uint32_t contents = kContentsCorpse; ///< contents bits (docs/format.md §1.6)
    std::uint32_t clipMask = kContentsSolid | kContentsCorpse | kContentsMoveableClip; ///< contents it collides with
    /// md5 joints whose impacts this body takes (docs/format.md §5.3), ascending.
    std::vector<int> containedJoints;
    std::optional<Eigen::Vector3d> frictionDirection;     ///< body frame, unit; single-direction friction
    std::optional<Eigen::Vector3d> contactMotorDirection; ///< body frame, unit
};

/// Cone limit: the shaft (fixed in body1) stays within `halfAngleRad` of the axis (fixed in body2) (docs/format.md
/// §4.3).
struct ConeLimit {
    Eigen::Vector3d axisInBody2;  ///< unit; model space when body2 is the world
    Eigen::Vector3d shaftInBody1; ///< unit
    double halfAngleRad = 0;      ///< half of the decl's full apex angle
};

/// True pyramid limit (docs/format.md §4.3): the shaft's angle from f, projected onto span(f, l), is at most
/// halfAngle1Rad, and projected onto span(f, f×l), at most halfAngle2Rad.
struct PyramidLimit {
    Eigen::Matrix3d basisInBody2; ///< columns f, l, f×l (unit, right-handed); model space for the world
    Eigen::Vector3d shaftInBody1; ///< unit
    double halfAngle1Rad = 0;     ///< half of the decl's first apex angle, in span(f, l)
    double halfAngle2Rad = 0;     ///< half of the decl's second apex angle, in span(f, f×l)
};

/// Hinge range: φ, the right-handed rotation of body1 relative to body2 about the hinge axis measured from the
/// load pose, stays in [lowerRad, upperRad] (docs/format.md §4.5).
struct HingeRange {
    double lowerRad = 0; ///< least φ allowed
    double upperRad = 0; ///< greatest φ allowed
};

/// Spring parameters in SI (docs/format.md §4.7): F = k·ΔL² (stretch or compress) minus the damping term, along the
/// anchors.
struct SpringParams {
    double stretchNPerM2 = 0;  ///< k for L > rest, N/m²
    double compressNPerM2 = 0; ///< k for L < rest, N/m²
    double dampingNs = 0;      ///< D = damping·|relative speed along n| (scaled to SI), N per (m/s)
    double restLengthM = 0;    ///< anchor distance at which the spring exerts no force, m
    double minLengthM = 0;     ///< a length row pushes the anchors apart below this
    double maxLengthM = 0;     ///< > 0: a length row pulls them together above this
};

/// One constraint. Frames coincide (position and orientation) at the load pose, so every constraint is exactly
/// satisfied at spawn. The frame's meaning per type: ball/universal: origin = anchor; fixed: body1's frame;
/// universal: X = shaft 1 at the load pose (= −shaft 2 for the usual opposite shafts); hinge: Z = axis; slider:
/// X = axis.
struct FigureConstraint {
    std::string name;                  ///< as written in the decl
    text::SourceLocation location;     ///< the constraint block
    JointType type = JointType::Fixed; ///< what the constraint does
    int body1 = 0;                     ///< index into Figure::bodies
    int body2 = -1;                    ///< index into Figure::bodies, or −1 for the world
    Transform frameInBody1;            ///< constraint frame in body1's frame, metres
    Transform frameInBody2;            ///< in body2's frame, or in model space when body2 is the world
    double friction = 0; ///< joint friction coefficient (docs/format.md §4.8); 0 where the engine applies none
    std::variant<std::monostate, ConeLimit, PyramidLimit, HingeRange> limit; ///< none, or the limit the decl gave
    SpringParams spring;           ///< type Spring only; frames' origins are anchor1 (body1) and anchor2 (body2)
    bool disablesCollision = true; ///< the two bodies never collide (every type but spring; docs/format.md §4.1)
};

/// Rest rules in SI (docs/format.md §6.1).
struct RestRules {
    double linearSpeedMps = 0;     ///< suspendSpeed[0]: a body faster than this keeps the figure awake, m/s
    double angularSpeedRadps = 0;  ///< suspendSpeed[1]: likewise for angular speed, rad/s
    double linearAccelMps2 = 0;    ///< suspendSpeed[2]: likewise for linear acceleration, m/s²
    double angularAccelRadps2 = 0; ///< suspendSpeed[3]: likewise for angular acceleration, rad/s²
    double noMoveTimeS = 1;        ///< how long the figure must stay within the two bounds below to rest, s
    double noMoveTranslationM = 0; ///< the most a body may move within noMoveTimeS and still rest, m
    double noMoveRotationRad = 0;  ///< the most a body may turn within noMoveTimeS and still rest, rad
    double minMoveTimeS = -1;      ///< the figure never rests before it has moved this long, s; ≤ 0: disabled
    double maxMoveTimeS = -1;      ///< the figure rests after moving this long, whatever its motion, s; ≤ 0: disabled
};

/// A whole built figure.
struct Figure {
    std::string name; ///< the articulatedFigure decl's name
    UnitSystem units; ///< the conversion it was built with
    /// The md5 skeleton, kept in Doom units as the md5 files give it (see Skeleton; converting it is out of
    /// scope). For joints in metres use figure::jointsInMetres and figure::jointsFromAnimation (Placement.h).
    Skeleton skeleton;
    std::vector<FigureBody> bodies;            ///< body 0 is the origin body
    std::vector<FigureConstraint> constraints; ///< in decl order
    bool selfCollision = true;                 ///< the settings switch (docs/format.md §6.2)
    RestRules rest;                            ///< when the figure comes to rest
    std::vector<int> jointBody; ///< per md5 joint: the body that contains it, −1 if none (docs/format.md §5.3)
    double totalMassKg = 0;     ///< sum of the bodies' masses, kg
};

/// What the figure is built from.
struct FigureInput {
    const decl::AfDecl* decl = nullptr; ///< the parsed figure
    const Skeleton* skeleton = nullptr; ///< the mesh skeleton with its af_pose load pose
    UnitSystem units;                   ///< Doom units and steps to SI
    /// Refuse instead of repair: every value outside Bounds.h that the builder would repair (with a warning)
    /// is an error instead.
    bool strict = false;
};

/// Builds a figure, reporting findings (docs/format.md §1–§6 silent engine fallbacks, id's "behave weird or explode"
/// list) as warnings and errors located at the decl. Returns nullopt when any error was found.
std::optional<Figure> buildFigure(const FigureInput& input, text::Diagnostics& findings);

} // namespace afb::figure
