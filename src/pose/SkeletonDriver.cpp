#include "afb/pose/SkeletonDriver.h"

namespace afb::pose {

std::vector<Transform> SkeletonPose::world() const {
    std::vector<Transform> out;
    out.reserve(model.size());
    for (const Transform& t : model) out.push_back(entity * t);
    return out;
}

SkeletonPose driveSkeleton(const figure::Figure& figure, std::span<const Transform> bodies) {
    const figure::Skeleton& skel = figure.skeleton;
    const double s = figure.units.metresPerUnit;
    const std::size_t n = static_cast<std::size_t>(skel.jointCount());
    SkeletonPose out;

    // docs/format.md §5.1 step 1: the entity follows body 0: R_ent = R_b0·R_base0ᵀ, p_ent = p_b0 − R_ent·p_base0.
    if (!bodies.empty() && !figure.bodies.empty()) {
        const Transform& b0 = bodies[0];
        const Transform& base0 = figure.bodies[0].loadPose;
        out.entity.rotation = b0.rotation * base0.rotation.transpose();
        out.entity.position = b0.position - out.entity.rotation * base0.position;
    }
    const Transform entityInverse = out.entity.inverse();

    // §5.1 step 2: each body's joint target in model space (the later body wins a shared joint).
    enum Drive : unsigned char { kNone = 0, kRotation = 1, kPosition = 2 };
    std::vector<unsigned char> drive(n, kNone);
    std::vector<Transform> target(n);
    for (std::size_t i = 0; i < figure.bodies.size() && i < bodies.size(); ++i) {
        const figure::FigureBody& b = figure.bodies[i];
        if (b.joint <= 0 || static_cast<std::size_t>(b.joint) >= n) continue; // joint 0 is never driven
        const std::size_t j = static_cast<std::size_t>(b.joint);
        target[j] = entityInverse * bodies[i] * b.jointInBody;
        drive[j] = b.mod == figure::JointMod::Orientation ? kRotation
                   : b.mod == figure::JointMod::Position  ? kPosition
                                                          : (kRotation | kPosition);
    }

    // §5.1 step 3: forward kinematics from the af_pose baseframe, parents first.
    const std::vector<Transform>& afLocal = skel.afPoseLocal();
    out.model.resize(n);
    out.local.resize(n);
    for (std::size_t j = 0; j < n; ++j) {
        const Transform local{afLocal[j].rotation, afLocal[j].position * s};
        const int parent = skel.parent(static_cast<int>(j));
        const Transform parentModel = parent >= 0 ? out.model[static_cast<std::size_t>(parent)] : Transform{};
        Transform m = parentModel * local;
        if (drive[j] & kRotation) m.rotation = target[j].rotation;
        if (drive[j] & kPosition) m.position = target[j].position;
        out.model[j] = m;
        out.local[j] = parent >= 0 ? parentModel.inverse() * m : m;
    }
    return out;
}

std::vector<std::vector<Eigen::Vector3d>> skin(const decl::Md5Mesh& mesh, std::span<const Transform> jointsModel,
                                               double metresPerUnit) {
    std::vector<std::vector<Eigen::Vector3d>> out;
    out.reserve(mesh.meshes.size());
    for (const decl::Md5SubMesh& sub : mesh.meshes) {
        std::vector<Eigen::Vector3d> verts;
        verts.reserve(sub.verts.size());
        for (const decl::Md5Vert& v : sub.verts) {
            Eigen::Vector3d p = Eigen::Vector3d::Zero();
            for (int k = 0; k < v.weightCount; ++k) {
                const decl::Md5Weight& w = sub.weights[static_cast<std::size_t>(v.firstWeight + k)];
                const Transform& j = jointsModel[static_cast<std::size_t>(w.joint)];
                p += w.bias * j.apply(Eigen::Vector3d(w.offset.x, w.offset.y, w.offset.z) * metresPerUnit);
            }
            verts.push_back(p);
        }
        out.push_back(std::move(verts));
    }
    return out;
}

} // namespace afb::pose
