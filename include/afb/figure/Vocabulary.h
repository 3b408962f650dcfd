#pragma once
// The figure layer's own words for what a body is shaped like, how two bodies are joined and which contents
// bits they carry. The layers below (bullet, sim, the tools) speak these, never the decl's: the figure
// builder maps the decl's keywords onto them once (ARCHITECTURE.md "one conversion point").
#include <cstdint>

namespace afb::figure {

/// A body's trace-model shape (af-format §3.1).
enum class ShapeType : std::uint8_t { Box, Octahedron, Dodecahedron, Cylinder, Cone, Bone };

/// What a constraint does (af-format §4.2–§4.7).
enum class JointType : std::uint8_t { Fixed, BallAndSocket, Universal, Hinge, Slider, Spring };

/// The shape's `.af` keyword: "box", "octahedron", "dodecahedron", "cylinder", "cone" or "bone".
const char* toString(ShapeType type);

/// The constraint's `.af` block keyword: "fixed", "ballAndSocketJoint", "universalJoint", "hinge", "slider"
/// or "spring".
const char* toString(JointType type);

/// Contents bits of a body (neo/renderer/Material.h; af-format §1.6), as FigureBody::contents and clipMask
/// hold them.
inline constexpr std::uint32_t kContentsSolid = 1u << 0;
inline constexpr std::uint32_t kContentsPlayerClip = 1u << 3;
inline constexpr std::uint32_t kContentsMonsterClip = 1u << 4;
inline constexpr std::uint32_t kContentsMoveableClip = 1u << 5; ///< always OR-ed into a body's clipMask
inline constexpr std::uint32_t kContentsBody = 1u << 8;
inline constexpr std::uint32_t kContentsCorpse = 1u << 10;

} // namespace afb::figure
