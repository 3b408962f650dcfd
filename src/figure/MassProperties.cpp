// Exact polyhedral mass properties (docs/format.md §3.2). Each face is fanned into triangles; each triangle with
// the reference point r spans a signed tetrahedron (0, a, b, c) in coordinates relative to r, whose integrals
// are closed-form:
//   ∫ dV        = D/6,                                     D = a · (b × c)
//   ∫ x dV      = D/24 · (a + b + c)
//   ∫ x xᵀ dV   = D/120 · (a aᵀ + b bᵀ + c cᵀ + s sᵀ),     s = a + b + c
// Summed over a closed, consistently oriented surface these give the solid's integrals exactly (the
// divergence theorem); the engine's Mirtich integrals compute the same quantities.
#include "afb/figure/MassProperties.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <Eigen/Eigenvalues>

namespace afb::figure {

namespace {

/// Raw integrals about the reference point: 6·volume, 24·first moment, 120·second moment.
struct Moments {
    double volume6 = 0;
    Eigen::Vector3d first24 = Eigen::Vector3d::Zero();
    Eigen::Matrix3d second120 = Eigen::Matrix3d::Zero();
};

// Adds the tetrahedron (r, v[i], v[j], v[k]). The three indices are put in ascending order first (flipping
// the sign for an odd permutation), so a triangle and its reverse contribute exact negatives: a flat shape
// such as the 2-sided cone, whose two side faces are one triangle seen from both sides, then sums to exactly
// 0 volume, which the engine's zero-volume rule needs.
void addTetrahedron(Moments& m, const std::vector<Eigen::Vector3d>& v, const Eigen::Vector3d& r,
                    std::array<int, 3> idx) {
    double sign = 1.0;
    for (int pass = 0; pass < 2; ++pass)
        for (int q = 0; q + 1 < 3 - pass; ++q)
            if (idx[q] > idx[q + 1]) {
                std::swap(idx[q], idx[q + 1]);
                sign = -sign;
            }
    const Eigen::Vector3d a = v[idx[0]] - r;
    const Eigen::Vector3d b = v[idx[1]] - r;
    const Eigen::Vector3d c = v[idx[2]] - r;
    const double det = sign * a.dot(b.cross(c));
    const Eigen::Vector3d s = a + b + c;
    m.volume6 += det;
    m.first24 += det * s;
    m.second120 += det * (a * a.transpose() + b * b.transpose() + c * c.transpose() + s * s.transpose());
}

} // namespace

MassProperties computeMassProperties(const Polytope& polytope, double density) {
    MassProperties result;
    const auto& v = polytope.vertices;
    if (v.empty()) return result;

    // A vertex as reference keeps coordinates small and makes shapes flat along an axis exactly flat (all
    // relative coordinates on that axis are exactly 0), so their volume is exactly 0.
    const Eigen::Vector3d r = v.front();
    Moments m;
    for (const auto& face : polytope.faces)
        for (std::size_t t = 1; t + 1 < face.size(); ++t) addTetrahedron(m, v, r, {face[0], face[t], face[t + 1]});

    result.volume = m.volume6 / 6.0;
    if (result.volume == 0.0) {
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        for (const auto& p : v) mean += p;
        result.centerOfMass = mean / static_cast<double>(v.size());
        return result;
    }
    result.mass = density * result.volume;
    const Eigen::Vector3d comFromRef = m.first24 / (24.0 * result.volume);
    result.centerOfMass = r + comFromRef;
    // Parallel-axis shift of the second moment from r to the centre of mass: C_com = C_r − V·g·gᵀ.
    const Eigen::Matrix3d secondAtCom = m.second120 / 120.0 - result.volume * (comFromRef * comFromRef.transpose());
    // I = ρ (tr(C)·1 − C): diagonal ∫(y² + z²), off-diagonal −∫xy.
    result.inertia = density * (secondAtCom.trace() * Eigen::Matrix3d::Identity() - secondAtCom);
    return result;
}

MassProperties computeClipModelMassProperties(const Polytope& polytope, double density) {
    MassProperties result = computeMassProperties(polytope, density);
    if (result.volume == 0.0) {
        // docs/format.md §3.2: idTraceModel returns volume 1, COM 0, inertia identity; idClipModel scales by
        // density.
        result.mass = density;
        result.centerOfMass = Eigen::Vector3d::Zero();
        result.inertia = density * Eigen::Matrix3d::Identity();
        result.zeroVolumeFallback = true;
    }
    return result;
}

RigidPart combineRigidParts(std::span<const RigidPart> parts) {
    if (parts.size() == 1) return parts.front();
    RigidPart out;
    Eigen::Vector3d moment = Eigen::Vector3d::Zero();
    for (const RigidPart& p : parts) {
        out.massKg += p.massKg;
        moment += p.massKg * p.pose.position;
    }
    const Eigen::Vector3d com = out.massKg != 0 ? Eigen::Vector3d(moment / out.massKg) : Eigen::Vector3d::Zero();
    // Each part's tensor turned into the common frame (R I Rᵀ), moved to the union's centre of mass
    // (parallel axes: + m (|d|² 1 − d dᵀ)).
    Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
    for (const RigidPart& p : parts) {
        const Eigen::Vector3d d = p.pose.position - com;
        inertia += p.pose.rotation * p.inertiaKgM2.asDiagonal() * p.pose.rotation.transpose() +
                   p.massKg * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
    }
    Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
    Eigen::Vector3d moments = inertia.diagonal();
    const double offDiagonal = std::abs(inertia(0, 1)) + std::abs(inertia(0, 2)) + std::abs(inertia(1, 2));
    if (offDiagonal > 1e-15 * inertia.diagonal().cwiseAbs().maxCoeff()) {
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(inertia);
        axes = eig.eigenvectors();
        if (axes.determinant() < 0) axes.col(2) = -axes.col(2);
        moments = eig.eigenvalues();
    }
    out.inertiaKgM2 = moments;
    out.pose = Transform{axes, com};
    return out;
}

} // namespace afb::figure
