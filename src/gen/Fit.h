#pragma once
// Internal to afb gen: grouping bones into bodies and fitting one of Doom's shapes to each group's vertices.
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "afb/decl/Af.h"
#include "afb/gen/Generate.h"

namespace afb::gen::detail {

/// One body as fitted, in the rig's model space (Doom units, bind pose).
struct BodyFit {
    int head = 0;                        ///< the group's first joint (the joint the body drives; 0 for the base body)
    int mainJoint = 0;                   ///< the group's joint with the most vertices (names the base body)
    int parentBody = -1;                 ///< the body holding the head's parent joint; -1 for the base body
    std::vector<int> joints;             ///< every joint of the group, ascending
    std::vector<Eigen::Vector3d> points; ///< the vertices it was fitted to
    Eigen::Matrix3d frame = Eigen::Matrix3d::Identity();   ///< columns: the fit's axes (Z along the bone)
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();      ///< the shape's centre (its centre of mass)
    Eigen::Vector3d halfExtents = Eigen::Vector3d::Ones(); ///< box-like shapes: bounds half extents in `frame`
    decl::ShapeKind shape = decl::ShapeKind::Box;
    int sides = 0;                                        ///< cylinder sides
    double boneLength = 0, boneWidth = 0;                 ///< bone shape: length along frame Z, width
    double volume = 0;                                    ///< Doom units³
    Eigen::Vector3d direction = Eigen::Vector3d::UnitZ(); ///< from the head joint toward the body (unit)
};

/// Vertices left out of every fit, per surface and vertex (strayVertices).
using VertexMask = std::vector<std::vector<bool>>;

/// Groups the rig's joints into bodies (merge rules, size rules, the base body) and fits a shape to each, to every
/// vertex but those set in `stray`.
std::vector<BodyFit> fitBodies(const Rig& rig, const GenRules& rules, const VertexMask& stray);

} // namespace afb::gen::detail
