#pragma once
// Value types for `.af` decls (af-format §1): what the file says, nothing more. The figure layer applies
// the engine's meaning (defaults captured in block order, the origin body swap, contents bits, …).
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "afb/text/Diagnostics.h"

namespace afb::decl {

using text::SourceLocation;

/// Three numbers as written, in Doom units/conventions (no conversion happens in the decl layer).
struct Vec3 {
    double x = 0, y = 0, z = 0;
    bool operator==(const Vec3&) const = default;
};

/// A vector expression (af-format §1.2): a literal or a joint-based form, optionally negated.
struct AfVector {
    enum class Form : std::uint8_t { Literal, Joint, BoneCenter, BoneDir };
    Form form = Form::Literal;
    bool negated = false; ///< a leading '-' (applied once, when the figure is built)
    Vec3 literal;         ///< Form::Literal: the three numbers
    std::string joint1;   ///< Joint: J; BoneCenter/BoneDir: A (as written; looked up case-insensitively)
    std::string joint2;   ///< BoneCenter/BoneDir: B
    bool operator==(const AfVector&) const = default;

    static AfVector fromLiteral(Vec3 v) { return AfVector{Form::Literal, false, v, {}, {}}; }
    /// `joint( j )`.
    static AfVector fromJoint(std::string j) { return AfVector{Form::Joint, false, {}, std::move(j), {}}; }
    /// `bonecenter( a, b )`.
    static AfVector fromBoneCenter(std::string a, std::string b) {
        return AfVector{Form::BoneCenter, false, {}, std::move(a), std::move(b)};
    }
    /// `bonedir( a, b )`, negated when `negated`.
    static AfVector fromBoneDir(std::string a, std::string b, bool negated = false) {
        return AfVector{Form::BoneDir, negated, {}, std::move(a), std::move(b)};
    }
};

/// The shape keywords after `model` (af-format §1.5). `custom` is rejected by the parser, as by the engine.
enum class ShapeKind : std::uint8_t { Box, Octahedron, Dodecahedron, Cylinder, Cone, Bone };

/// A body's `model` (af-format §1.5, §3.1).
struct AfShape {
    ShapeKind kind = ShapeKind::Box;
    AfVector v1 = AfVector::fromLiteral({-10, -10, -10}); ///< min bound (bone: first point)
    AfVector v2 = AfVector::fromLiteral({10, 10, 10});    ///< max bound (bone: second point)
    std::int64_t numSides = 3;                            ///< cylinder and cone only, as written (clamped later)
    double width = 0;                                     ///< bone only
    bool operator==(const AfShape&) const = default;
};

/// A contents list as written (af-format §1.6); `contentsBits` gives the engine's meaning.
struct ContentsList {
    std::vector<std::string> names;
    bool operator==(const ContentsList&) const = default;
};

/// Contents bits (neo/renderer/Material.h) that `.af` files can name.
enum ContentsBit : std::uint32_t {
    kContentsSolid = 1u << 0,
    kContentsPlayerClip = 1u << 3,
    kContentsMonsterClip = 1u << 4,
    kContentsMoveableClip = 1u << 5, ///< always OR-ed into a body's clipMask; not nameable
    kContentsBody = 1u << 8,
    kContentsCorpse = 1u << 10,
};

/// Bits of one contents name (case-insensitive), or nullopt for a name the engine does not know.
/// `none` yields 0 and resets the accumulated value.
std::optional<std::uint32_t> contentsBitsOfName(std::string_view name);

/// The engine's value of a list: names are OR-ed left to right, `none` resets, and the first unknown name
/// silently ends the list (af-format §1.6). `firstUnknown` receives the index of that name, if any.
std::uint32_t contentsBits(const ContentsList& list, std::optional<std::size_t>* firstUnknown = nullptr);

/// `friction lin, ang, contact` of a body (af-format §1.4).
struct BodyFriction {
    double linear = 0, angular = 0, contact = 0;
    bool operator==(const BodyFriction&) const = default;
};

/// `friction lin, ang, contact [, constraint]` of a settings block (af-format §1.3).
struct SettingsFriction {
    double linear = 0, angular = 0, contact = 0;
    std::optional<double> constraint; ///< the optional 4th value; it has no effect (af-format §1.7)
    bool operator==(const SettingsFriction&) const = default;
};

/// One `settings { }` block: only the keys it wrote.
struct AfSettings {
    SourceLocation location;
    std::optional<std::string> model, skin;
    std::optional<std::string> mesh, anim; ///< legacy keys, read and ignored by the engine
    std::optional<SettingsFriction> friction;
    std::optional<std::array<double, 4>> suspendSpeed; ///< linVel, angVel (rad/s), linAcc, angAcc (rad/s²)
    std::optional<double> noMoveTime, noMoveTranslation, noMoveRotation;
    std::optional<double> minMoveTime, maxMoveTime, totalMass;
    std::optional<ContentsList> contents, clipMask;
    std::optional<bool> selfCollision;
    bool operator==(const AfSettings&) const = default;
};

/// The engine's settings values with every default filled in (af-format §1.3).
struct AfSettingsValues {
    std::string model, skin;
    BodyFriction friction{0.01, 0.01, 0.8};
    double constraintFriction = 0.5;
    std::array<double, 4> suspendSpeed{20, 30, 40, 60};
    double noMoveTime = 1, noMoveTranslation = 10, noMoveRotation = 10;
    double minMoveTime = -1, maxMoveTime = -1, totalMass = -1;
    ContentsList contents{{"corpse"}};
    ContentsList clipMask{{"solid", "corpse"}};
    bool selfCollision = true;
    bool operator==(const AfSettingsValues&) const = default;

    /// Overwrites the values a block wrote, as the engine does when it parses that block.
    void apply(const AfSettings& block);
};

/// One `body "name" { }` block (af-format §1.4): only the keys it wrote (`joint` is mandatory).
struct AfBody {
    std::string name;
    SourceLocation location;
    std::string joint;
    std::optional<std::string> mod; ///< as written; orientation/position/both, anything else means orientation
    std::optional<AfShape> model;
    std::optional<AfVector> origin;
    std::optional<AfVector> angles; ///< (pitch, yaw, roll) degrees; the engine ignores '-' and joint forms here
    std::optional<double> density;
    std::optional<std::array<double, 9>> inertiaScale; ///< row-major, nine numbers without commas
    std::optional<BodyFriction> friction;
    std::optional<ContentsList> contents, clipMask;
    std::optional<bool> selfCollision;
    std::optional<std::string> containedJoints;
    std::optional<AfVector> frictionDirection, contactMotorDirection;
    bool operator==(const AfBody&) const = default;
};

enum class ConstraintType : std::uint8_t { Fixed, BallAndSocket, Universal, Hinge, Slider, Spring };

/// The block keyword of a constraint type (`ballAndSocketJoint`, …).
const char* keywordOf(ConstraintType type);

/// `coneLimit axis, angle[, shaft]` (ball-and-socket has the shaft, universal does not).
struct ConeLimit {
    AfVector axis;
    double angleDeg = 0; ///< full apex angle
    std::optional<AfVector> shaft;
    bool operator==(const ConeLimit&) const = default;
};

/// `pyramidLimit axis, a1, a2, roll[, shaft]`.
struct PyramidLimit {
    AfVector axis;
    double angle1Deg = 0, angle2Deg = 0, rollDeg = 0;
    std::optional<AfVector> shaft;
    bool operator==(const PyramidLimit&) const = default;
};

/// Hinge `limit a0, a1, a2` (orientation, width, angle; af-format §4.5).
struct HingeLimit {
    double orientationDeg = 0, widthDeg = 0, angleDeg = 0;
    bool operator==(const HingeLimit&) const = default;
};

using AfLimit = std::variant<std::monostate, ConeLimit, PyramidLimit, HingeLimit>;

/// One constraint block (af-format §1.7): only the keys it wrote.
struct AfConstraint {
    ConstraintType type = ConstraintType::Fixed;
    std::string name;
    SourceLocation location;
    std::optional<std::string> body1, body2;
    std::optional<AfVector> anchor;                ///< `anchor`, or a spring's `anchor1`
    std::optional<AfVector> anchor2;               ///< spring only
    std::optional<std::array<AfVector, 2>> shafts; ///< universal only
    std::optional<AfVector> axis;                  ///< hinge and slider
    std::optional<double> friction;
    AfLimit limit;                                                                      ///< the last limit given wins
    std::optional<double> stretch, compress, damping, restLength, minLength, maxLength; ///< spring only
    bool operator==(const AfConstraint&) const = default;
};

/// Which block came where (af-format §1.8: order decides defaults and `body1`).
struct AfBlockRef {
    enum class Kind : std::uint8_t { Settings, Body, Constraint };
    Kind kind = Kind::Settings;
    std::size_t index = 0; ///< into settings, bodies or constraints
    bool operator==(const AfBlockRef&) const = default;
};

/// One `articulatedFigure name { }` decl, blocks in the order the file gave them.
struct AfDecl {
    std::string name;
    SourceLocation location;
    std::vector<AfSettings> settings;
    std::vector<AfBody> bodies;
    std::vector<AfConstraint> constraints;
    std::vector<AfBlockRef> order;
    bool operator==(const AfDecl&) const = default;

    /// The settings in force after every settings block (what the figure-wide values are).
    AfSettingsValues finalSettings() const;
    /// The settings in force when body `bodyIndex` was parsed (its defaults; af-format §1.8).
    AfSettingsValues settingsForBody(std::size_t bodyIndex) const;
    /// The body name a constraint without `body1` gets: the first body parsed before it, else "world".
    std::string defaultBody1(std::size_t constraintIndex) const;
};

/// Everything in one `.af` file.
struct AfFile {
    std::vector<AfDecl> decls;
    bool operator==(const AfFile&) const = default;
};

} // namespace afb::decl
