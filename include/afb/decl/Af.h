#pragma once
// Value types for `.af` decls (docs/format.md §1): what the file says, nothing more. The figure layer applies
// the engine's meaning (defaults captured in block order, the origin body swap, contents bits, …).
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "afb/text/Diagnostics.h"

/// The decl layer: idTech4 text files (.af, .def, .md5mesh, .md5anim) parsed into plain values that say what
/// the file says, in Doom units, and written back; a content folder indexed by decl name (Library).
namespace afb::decl {

/// Where a decl or statement was written (the text layer's type, used by every decl).
using text::SourceLocation;

/// Three numbers as written, in Doom units/conventions (no conversion happens in the decl layer).
struct Vec3 {
    double x = 0; ///< first number (Doom X: forward)
    double y = 0; ///< second number (Doom Y: left)
    double z = 0; ///< third number (Doom Z: up)
    /// Equal when every field is.
    bool operator==(const Vec3&) const = default;
};

/// A vector expression (docs/format.md §1.2): a literal or a joint-based form, optionally negated.
struct AfVector {
    /// Which form the file used.
    enum class Form : std::uint8_t {
        Literal,    ///< `( x, y, z )`
        Joint,      ///< `joint( "j" )`: the joint's load-pose position
        BoneCenter, ///< `bonecenter( "a", "b" )`: the midpoint of two joints
        BoneDir,    ///< `bonedir( "a", "b" )`: the unit direction from joint a to joint b
    };
    Form form = Form::Literal; ///< which of the fields below hold the vector
    bool negated = false;      ///< a leading '-' (applied once, when the figure is built)
    Vec3 literal;              ///< Form::Literal: the three numbers
    std::string joint1;        ///< Joint: J; BoneCenter/BoneDir: A (as written; looked up case-insensitively)
    std::string joint2;        ///< BoneCenter/BoneDir: B
    /// Equal when every field is.
    bool operator==(const AfVector&) const = default;

    /// `( x, y, z )`.
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

/// The shape keywords after `model` (docs/format.md §1.5). `custom` is rejected by the parser, as by the engine.
enum class ShapeKind : std::uint8_t {
    Box,          ///< `box( min, max )`
    Octahedron,   ///< `octahedron( min, max )`
    Dodecahedron, ///< `dodecahedron( min, max )`
    Cylinder,     ///< `cylinder( min, max, sides )`
    Cone,         ///< `cone( min, max, sides )`
    Bone,         ///< `bone( p1, p2, width )`: a double pyramid on a triangle between two points
};

/// A body's `model` (docs/format.md §1.5, §3.1).
struct AfShape {
    ShapeKind kind = ShapeKind::Box;                      ///< the keyword; decides which fields below count
    AfVector v1 = AfVector::fromLiteral({-10, -10, -10}); ///< min bound (bone: first point)
    AfVector v2 = AfVector::fromLiteral({10, 10, 10});    ///< max bound (bone: second point)
    std::int64_t numSides = 3;                            ///< cylinder and cone only, as written (clamped later)
    double width = 0;                                     ///< bone only, Doom units
    /// Equal when every field is.
    bool operator==(const AfShape&) const = default;
};

/// A contents list as written (docs/format.md §1.6); `contentsBits` gives the engine's meaning.
struct ContentsList {
    std::vector<std::string> names; ///< the names in file order, as written
    /// Equal when every name is.
    bool operator==(const ContentsList&) const = default;
};

/// Contents bits (neo/renderer/Material.h) that `.af` files can name.
enum ContentsBit : std::uint32_t {
    kContentsSolid = 1u << 0,        ///< `solid`: world geometry and anything that blocks everything
    kContentsPlayerClip = 1u << 3,   ///< `playerclip`: blocks players
    kContentsMonsterClip = 1u << 4,  ///< `monsterclip`: blocks monsters
    kContentsMoveableClip = 1u << 5, ///< always OR-ed into a body's clipMask; not nameable
    kContentsBody = 1u << 8,         ///< `body`: a living actor's body
    kContentsCorpse = 1u << 10,      ///< `corpse`: a dead body (a ragdoll's default contents)
};

/// Bits of one contents name (case-insensitive), or nullopt for a name the engine does not know.
/// `none` yields 0 and resets the accumulated value.
std::optional<std::uint32_t> contentsBitsOfName(std::string_view name);

/// The engine's value of a list: names are OR-ed left to right, `none` resets, and the first unknown name
/// silently ends the list (docs/format.md §1.6). `firstUnknown` receives the index of that name, if any.
std::uint32_t contentsBits(const ContentsList& list, std::optional<std::size_t>* firstUnknown = nullptr);

/// `friction lin, ang, contact` of a body (docs/format.md §1.4).
struct BodyFriction {
    double linear = 0;  ///< fraction of linear velocity lost per engine step
    double angular = 0; ///< fraction of angular velocity lost per engine step
    double contact = 0; ///< Coulomb coefficient of the body's contacts
    /// Equal when every field is.
    bool operator==(const BodyFriction&) const = default;
};

/// `friction lin, ang, contact [, constraint]` of a settings block (docs/format.md §1.3).
struct SettingsFriction {
    double linear = 0;                ///< default fraction of linear velocity lost per engine step
    double angular = 0;               ///< default fraction of angular velocity lost per engine step
    double contact = 0;               ///< default Coulomb coefficient of contacts
    std::optional<double> constraint; ///< the optional 4th value; it has no effect (docs/format.md §1.7)
    /// Equal when every field is.
    bool operator==(const SettingsFriction&) const = default;
};

/// One `settings { }` block: only the keys it wrote.
struct AfSettings {
    SourceLocation location;                           ///< where the block starts
    std::optional<std::string> model;                  ///< `model`: the model decl the figure was made for
    std::optional<std::string> skin;                   ///< `skin`: the skin decl to render it with
    std::optional<std::string> mesh;                   ///< legacy key, read and ignored by the engine
    std::optional<std::string> anim;                   ///< legacy key, read and ignored by the engine
    std::optional<SettingsFriction> friction;          ///< `friction`: defaults for the bodies after this block
    std::optional<std::array<double, 4>> suspendSpeed; ///< linVel, angVel (rad/s), linAcc, angAcc (rad/s²)
    std::optional<double> noMoveTime;                  ///< `noMoveTime`, seconds still before rest
    std::optional<double> noMoveTranslation;           ///< `noMoveTranslation`, Doom units per noMoveTime
    std::optional<double> noMoveRotation;              ///< `noMoveRotation`, degrees per noMoveTime
    std::optional<double> minMoveTime;                 ///< `minMoveTime`, seconds before rest may start; -1: none
    std::optional<double> maxMoveTime;                 ///< `maxMoveTime`, seconds after which it rests; -1: never
    std::optional<double> totalMass;                   ///< `totalMass`: the figure's mass after scaling; -1: as built
    std::optional<ContentsList> contents;              ///< `contents`: defaults for the bodies after this block
    std::optional<ContentsList> clipMask;              ///< `clipMask`: defaults for the bodies after this block
    std::optional<bool> selfCollision;                 ///< `selfCollision`: the figure-wide switch
    /// Equal when they say the same thing; source locations never count.
    bool operator==(const AfSettings&) const = default;
};

/// The engine's settings values with every default filled in (docs/format.md §1.3).
/// Units as in AfSettings.
struct AfSettingsValues {
    std::string model;                                  ///< the model decl; empty when never set
    std::string skin;                                   ///< the skin decl; empty when never set
    BodyFriction friction{0.01, 0.01, 0.8};             ///< the bodies' defaults
    double constraintFriction = 0.5;                    ///< the 4th friction value (no effect; docs/format.md §1.7)
    std::array<double, 4> suspendSpeed{20, 30, 40, 60}; ///< linVel, angVel (rad/s), linAcc, angAcc (rad/s²)
    double noMoveTime = 1;                              ///< seconds still before rest
    double noMoveTranslation = 10;                      ///< Doom units per noMoveTime
    double noMoveRotation = 10;                         ///< degrees per noMoveTime
    double minMoveTime = -1;                            ///< seconds before rest may start; -1: none
    double maxMoveTime = -1;                            ///< seconds after which the figure rests; -1: never
    double totalMass = -1;                              ///< the figure's mass after scaling; -1: as built
    ContentsList contents{{"corpse"}};                  ///< the bodies' default contents
    ContentsList clipMask{{"solid", "corpse"}};         ///< the bodies' default clip mask
    bool selfCollision = true;                          ///< the figure-wide self-collision switch
    /// Equal when every field is.
    bool operator==(const AfSettingsValues&) const = default;

    /// Overwrites the values a block wrote, as the engine does when it parses that block.
    void apply(const AfSettings& block);
};

/// One `body "name" { }` block (docs/format.md §1.4): only the keys it wrote (`joint` is mandatory).
struct AfBody {
    std::string name;               ///< the body's name as written
    SourceLocation location;        ///< where the block starts
    std::string joint;              ///< `joint`: the md5 joint the body drives
    std::optional<std::string> mod; ///< as written; orientation/position/both, anything else means orientation
    std::optional<AfShape> model;   ///< `model`: the collision shape
    std::optional<AfVector> origin; ///< `origin`: the shape's centre in model space, Doom units
    std::optional<AfVector> angles; ///< (pitch, yaw, roll) degrees; the engine ignores '-' and joint forms here
    std::optional<double> density;  ///< `density`: mass per cubic Doom unit
    std::optional<std::array<double, 9>> inertiaScale; ///< row-major, nine numbers without commas
    std::optional<BodyFriction> friction;              ///< `friction`
    std::optional<ContentsList> contents;              ///< `contents`: what the body is to others
    std::optional<ContentsList> clipMask;              ///< `clipMask`: what the body collides with
    std::optional<bool> selfCollision;                 ///< `selfCollision`: the body's own switch
    std::optional<std::string> containedJoints;        ///< `containedJoints`: joint list (`*name` for a subtree)
    std::optional<AfVector> frictionDirection;         ///< `frictionDirection`: single-direction friction
    std::optional<AfVector> contactMotorDirection;     ///< `contactMotorDirection`: a contact motor's direction
    /// Equal when they say the same thing; source locations never count.
    bool operator==(const AfBody&) const = default;
};

/// The constraint block keywords (docs/format.md §1.7).
enum class ConstraintType : std::uint8_t {
    Fixed,         ///< `fixed`: no relative motion
    BallAndSocket, ///< `ballAndSocketJoint`: a shared anchor, free rotation up to its limit
    Universal,     ///< `universalJoint`: a shared anchor, two shafts that cannot twist about each other
    Hinge,         ///< `hinge`: a shared anchor, rotation about one axis
    Slider,        ///< `slider`: translation along one axis, no rotation
    Spring,        ///< `spring`: a force between two anchors, no kinematic constraint
};

/// The block keyword of a constraint type (`ballAndSocketJoint`, …).
const char* keywordOf(ConstraintType type);

/// `coneLimit axis, angle[, shaft]` (ball-and-socket has the shaft, universal does not).
struct ConeLimit {
    AfVector axis;                 ///< the cone's axis (fixed in body2)
    double angleDeg = 0;           ///< full apex angle
    std::optional<AfVector> shaft; ///< the shaft kept inside the cone (fixed in body1)
    /// Equal when every field is.
    bool operator==(const ConeLimit&) const = default;
};

/// `pyramidLimit axis, a1, a2, roll[, shaft]`.
struct PyramidLimit {
    AfVector axis;                 ///< the pyramid's axis (fixed in body2)
    double angle1Deg = 0;          ///< full apex angle in the first plane
    double angle2Deg = 0;          ///< full apex angle in the second plane
    double rollDeg = 0;            ///< turns the pyramid's planes about its axis
    std::optional<AfVector> shaft; ///< the shaft kept inside the pyramid (fixed in body1)
    /// Equal when every field is.
    bool operator==(const PyramidLimit&) const = default;
};

/// Hinge `limit a0, a1, a2` (orientation, width, angle; docs/format.md §4.5).
struct HingeLimit {
    double orientationDeg = 0; ///< a0: the range is centred on angleDeg − orientationDeg
    double widthDeg = 0;       ///< a1: the range's full width; 360 or more: no limit
    double angleDeg = 0;       ///< a2: see orientationDeg
    /// Equal when every field is.
    bool operator==(const HingeLimit&) const = default;
};

/// A constraint's limit: none (monostate), or the last one the block wrote.
using AfLimit = std::variant<std::monostate, ConeLimit, PyramidLimit, HingeLimit>;

/// One constraint block (docs/format.md §1.7): only the keys it wrote.
struct AfConstraint {
    ConstraintType type = ConstraintType::Fixed;   ///< the block keyword
    std::string name;                              ///< the constraint's name as written
    SourceLocation location;                       ///< where the block starts
    std::optional<std::string> body1;              ///< `body1`; when absent, see AfDecl::defaultBody1
    std::optional<std::string> body2;              ///< `body2`; "world" or absent: attached to the world
    std::optional<AfVector> anchor;                ///< `anchor`, or a spring's `anchor1`
    std::optional<AfVector> anchor2;               ///< spring only
    std::optional<std::array<AfVector, 2>> shafts; ///< universal only
    std::optional<AfVector> axis;                  ///< hinge and slider
    std::optional<double> friction;                ///< `friction`: joint friction coefficient
    AfLimit limit;                                 ///< the last limit given wins
    std::optional<double> stretch;                 ///< spring only: stiffness when longer than the rest length
    std::optional<double> compress;                ///< spring only: stiffness when shorter than the rest length
    std::optional<double> damping;                 ///< spring only: damping along the spring
    std::optional<double> restLength;              ///< spring only, Doom units
    std::optional<double> minLength;               ///< spring only, Doom units
    std::optional<double> maxLength;               ///< spring only, Doom units
    /// Equal when they say the same thing; source locations never count.
    bool operator==(const AfConstraint&) const = default;
};

/// Which block came where (docs/format.md §1.8: order decides defaults and `body1`).
struct AfBlockRef {
    /// Which list the block is in.
    enum class Kind : std::uint8_t {
        Settings,   ///< AfDecl::settings
        Body,       ///< AfDecl::bodies
        Constraint, ///< AfDecl::constraints
    };
    Kind kind = Kind::Settings; ///< which list index refers to
    std::size_t index = 0;      ///< into settings, bodies or constraints
    /// Equal when every field is.
    bool operator==(const AfBlockRef&) const = default;
};

/// One `articulatedFigure name { }` decl, blocks in the order the file gave them.
struct AfDecl {
    std::string name;                      ///< the decl's name as written
    SourceLocation location;               ///< where the decl starts
    std::vector<AfSettings> settings;      ///< `settings` blocks in file order
    std::vector<AfBody> bodies;            ///< `body` blocks in file order
    std::vector<AfConstraint> constraints; ///< constraint blocks in file order
    std::vector<AfBlockRef> order;         ///< every block, in file order
    /// Equal when they say the same thing; source locations never count.
    bool operator==(const AfDecl&) const = default;

    /// The settings in force after every settings block (what the figure-wide values are).
    AfSettingsValues finalSettings() const;
    /// The settings in force when body `bodyIndex` was parsed (its defaults; docs/format.md §1.8).
    AfSettingsValues settingsForBody(std::size_t bodyIndex) const;
    /// The body name a constraint without `body1` gets: the first body parsed before it, else "world".
    std::string defaultBody1(std::size_t constraintIndex) const;
};

/// Everything in one `.af` file.
struct AfFile {
    std::vector<AfDecl> decls; ///< `articulatedFigure` decls in file order
    /// Equal when they say the same thing; source locations never count.
    bool operator==(const AfFile&) const = default;
};

} // namespace afb::decl
