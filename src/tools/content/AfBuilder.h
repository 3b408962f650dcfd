#pragma once
// Building .af decls for afb_gen_content: vector and shape shorthands and an AfBuilder that keeps the blocks
// in order and derives each body's density from the mass it should have.
#include <cstdint>
#include <string>

#include <Eigen/Geometry>

#include "Rig.h"
#include "afb/decl/Af.h"

namespace afb::gen {

/// A literal vector, each component rounded to 6 decimals.
decl::AfVector lit(double x, double y, double z);
decl::AfVector lit(const Eigen::Vector3d& v);
/// `joint( "j" )`.
decl::AfVector jointV(const std::string& j);
/// `bonecenter( "a", "b" )`.
decl::AfVector boneCenter(const std::string& a, const std::string& b);
/// `bonedir( "a", "b" )`, or its negation.
decl::AfVector boneDir(const std::string& a, const std::string& b, bool negated = false);

/// A box-like shape (box, octahedron, dodecahedron, cylinder, cone) from literal bounds.
decl::AfShape shape(decl::ShapeKind kind, Eigen::Vector3d lo, Eigen::Vector3d hi, std::int64_t sides = 3);
/// A bone from joint `a` to joint `b`.
decl::AfShape boneShape(const std::string& a, const std::string& b, double width);

/// Appends settings, bodies and constraints to one AfDecl in the order they are added.
struct AfBuilder {
    decl::AfDecl decl;
    const Skeleton& sk; ///< resolves bone lengths

    AfBuilder(const std::string& name, const Skeleton& skel);

    /// The project's usual settings block for `model`, with the figure's total mass.
    void settings(const std::string& model, double totalMass);

    /// A body whose density gives it `mass` (before the settings' totalMass rescaling).
    decl::AfBody& body(const std::string& name, const std::string& joint, decl::AfShape model, decl::AfVector origin,
                       double mass, const std::string& contained, bool selfCollision = true);

    decl::AfConstraint& constraint(decl::ConstraintType type, const std::string& name, const std::string& body1,
                                   const std::string& body2);

    /// A spring between anchors `a1` on body1 and `a2` on body2, with the project's stiffness and damping.
    decl::AfConstraint& spring(const std::string& name, const std::string& body1, const std::string& body2,
                               decl::AfVector a1, decl::AfVector a2, double rest, double minL, double maxL);
};

} // namespace afb::gen
