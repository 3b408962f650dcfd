#pragma once
// Exact mass properties of a polytope of uniform density (docs/format.md §3.2), and the engine's clip-model rule
// for zero-volume shapes. Units follow the inputs: lengths in the polytope's unit L, density in mass per L³.
#include <span>

#include <Eigen/Geometry>

#include "afb/figure/Polytope.h"
#include "afb/figure/Transform.h"

namespace afb::figure {

/// Volume, mass, centre of mass and inertia of a uniform-density polytope.
struct MassProperties {
    /// Signed volume, L³: negative when the faces wind inward (e.g. box bounds given max-before-min).
    double volume = 0;
    /// density × volume, except under the zero-volume rule (then = density).
    double mass = 0;
    /// Centre of mass in the polytope's frame, L.
    Eigen::Vector3d centerOfMass = Eigen::Vector3d::Zero();
    /// Inertia tensor about the centre of mass, axes of the polytope's frame, mass·L²; standard sign
    /// convention (off-diagonals are negative products of inertia, Ixy = −∫ρxy dV).
    Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
    /// True when the engine's zero-volume rule replaced mass, centre of mass and inertia
    /// (see computeClipModelMassProperties).
    bool zeroVolumeFallback = false;
};

/// Exact integration over the polyhedron (signed tetrahedra, docs/format.md §3.2), shifted to the centre of mass
/// with the parallel-axis theorem. No engine fallbacks: a zero volume gives mass 0, inertia 0 and the vertex
/// mean as centre of mass; a negative volume gives negative mass and inertia.
MassProperties computeMassProperties(const Polytope& polytope, double density);

/// What the engine's idClipModel cache returns (docs/format.md §3.2, §8 item 14): computeMassProperties, except
/// that a volume of exactly 0 (e.g. a 2-sided cone) gives mass = density, centre of mass 0 and inertia
/// density × identity (the trace model's volume-1/identity fallback, scaled by density by the cache), with
/// zeroVolumeFallback set. Negative or otherwise invalid masses are left to the body's SetDensity rule
/// (docs/format.md §3.3).
MassProperties computeClipModelMassProperties(const Polytope& polytope, double density);

/// One rigid body as a part of a rigid union: its mass, its principal moments and its body frame (centre of mass,
/// principal axes) in a frame common to every part.
struct RigidPart {
    double massKg = 0;                                     ///< the part's mass, kg
    Eigen::Vector3d inertiaKgM2 = Eigen::Vector3d::Zero(); ///< principal moments about the body frame's axes
    Transform pose;                                        ///< body frame in the common frame
};

/// Parts joined rigidly (bodies held by `fixed` constraints, merged into one rigid body): total mass, the union's
/// frame (centre of mass, principal axes, right-handed) in the common frame and its principal moments (ascending
/// unless the summed tensor is already diagonal). Parallel-axis theorem in double; one part comes back unchanged.
RigidPart combineRigidParts(std::span<const RigidPart> parts);

} // namespace afb::figure
