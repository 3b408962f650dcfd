#pragma once
// The figure layer's own words for what a body is shaped like, how two bodies are joined and which contents
// bits they carry. The layers below (bullet, sim, the tools) speak these, never the decl's: the figure
// builder maps the decl's keywords onto them once, the one place where decl words become figure words.
#include <cstdint>

namespace afb::figure {

/// A body's trace-model shape (docs/format.md §3.1).
enum class ShapeType : std::uint8_t {
    Box,          ///< a box between two corners
    Octahedron,   ///< the octahedron inscribed in a box's bounds
    Dodecahedron, ///< the dodecahedron inscribed in a box's bounds
    Cylinder,     ///< a prism of n sides inscribed in a box's bounds, axis along Z
    Cone,         ///< a pyramid of n sides inscribed in a box's bounds, pointing along +Z
    Bone,         ///< a double pyramid on a triangle between two points, with a width
};

/// What a constraint does (docs/format.md §4.2–§4.7).
enum class JointType : std::uint8_t {
    Fixed,         ///< no relative motion
    BallAndSocket, ///< shared anchor; free rotation within an optional cone or pyramid limit
    Universal,     ///< shared anchor; the two shafts may bend but not twist about each other
    Hinge,         ///< shared anchor; rotation about one axis within an optional range
    Slider,        ///< translation along one axis, no rotation
    Spring,        ///< a quadratic force between two anchors, no kinematic constraint
};

/// What a joint keeps its two bodies' anchors to: one shared point, a line through body2's anchor along the joint's
/// axis (a slider), or nothing (a spring pulls them together by force alone).
enum class AnchorHold : std::uint8_t { Point, Line, None };

/// Which relative rotations a joint forbids: none (a ball), the twist about the two shafts (a universal joint),
/// every rotation but about its axis (a hinge), or all (fixed, slider, docs/format.md §4.2–§4.6). A spring forbids
/// none.
enum class RotationHold : std::uint8_t { None, Twist, AllButAxis, All };

/// The relative motions a joint type forbids: every layer that treats joint types alike (the rigid and multibody
/// backends, the position pass, the pruning of self-collision pairs) reads them here.
struct JointFreedom {
    AnchorHold anchor;     ///< what the two anchors are held to
    RotationHold rotation; ///< which relative rotations are forbidden
};

/// The freedoms of a joint type (JointFreedom).
constexpr JointFreedom freedomOf(JointType type) {
    switch (type) {
    case JointType::Fixed: return {AnchorHold::Point, RotationHold::All};
    case JointType::BallAndSocket: return {AnchorHold::Point, RotationHold::None};
    case JointType::Universal: return {AnchorHold::Point, RotationHold::Twist};
    case JointType::Hinge: return {AnchorHold::Point, RotationHold::AllButAxis};
    case JointType::Slider: return {AnchorHold::Line, RotationHold::All};
    case JointType::Spring: return {AnchorHold::None, RotationHold::None};
    }
    return {AnchorHold::None, RotationHold::None};
}

/// The shape's `.af` keyword: "box", "octahedron", "dodecahedron", "cylinder", "cone" or "bone".
const char* toString(ShapeType type);

/// The constraint's `.af` block keyword: "fixed", "ballAndSocketJoint", "universalJoint", "hinge", "slider"
/// or "spring".
const char* toString(JointType type);

/// Contents bit `solid` (neo/renderer/Material.h; docs/format.md §1.6), as FigureBody::contents and clipMask hold
/// the bits: world geometry and anything that blocks everything.
inline constexpr std::uint32_t kContentsSolid = 1u << 0;
/// Contents bit `playerclip`: blocks players.
inline constexpr std::uint32_t kContentsPlayerClip = 1u << 3;
/// Contents bit `monsterclip`: blocks monsters.
inline constexpr std::uint32_t kContentsMonsterClip = 1u << 4;
/// Contents bit of moveable objects; always OR-ed into a body's clipMask, not nameable in a file.
inline constexpr std::uint32_t kContentsMoveableClip = 1u << 5;
/// Contents bit `body`: a living actor's body.
inline constexpr std::uint32_t kContentsBody = 1u << 8;
/// Contents bit `corpse`: a dead body (a ragdoll body's default contents).
inline constexpr std::uint32_t kContentsCorpse = 1u << 10;

} // namespace afb::figure
