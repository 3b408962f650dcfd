// The md5 side of gen::Rig: a rig from an md5mesh, and the md5mesh and af_pose md5anim of a rig (docs/format.md §7.3,
// §7.4), written by the decl writers.
#include <algorithm>
#include <cmath>
#include <limits>

#include "afb/gen/Rig.h"

namespace afb::gen {
namespace {

decl::Vec3 toVec3(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }
Eigen::Vector3d fromVec3(const decl::Vec3& v) { return {v.x, v.y, v.z}; }

bool namesEqualIgnoringCase(const std::string& a, const std::string& b) {
    return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
               return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
           });
}

constexpr double kMaxModelM = 100;

// The largest extent of the mesh's joints and bind-pose vertices, in its own units.
double md5Height(const decl::Md5Mesh& mesh) {
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (const decl::Md5Joint& j : mesh.joints) {
        lo = lo.cwiseMin(fromVec3(j.position));
        hi = hi.cwiseMax(fromVec3(j.position));
    }
    for (const auto& surface : skinnedBindVertices(mesh))
        for (const Eigen::Vector3d& p : surface) {
            lo = lo.cwiseMin(p);
            hi = hi.cwiseMax(p);
        }
    const double extent = (hi - lo).maxCoeff();
    return std::isfinite(extent) ? extent : 0.0;
}

// The mesh scaled by `scale` and turned by `axes` (model → Doom): joints move and turn, weight offsets (in their
// joint's frame) only scale, so every skinned vertex moves as its joints do.
decl::Md5Mesh transformedMd5(decl::Md5Mesh mesh, double scale, const Eigen::Matrix3d& axes) {
    const bool turned = !axes.isIdentity();
    for (decl::Md5Joint& j : mesh.joints) {
        j.position = toVec3(axes * (scale * fromVec3(j.position)));
        if (turned)
            j.orientation = toVec3(
                md5Orientation(axes * figure::rotationFromMd5(j.orientation.x, j.orientation.y, j.orientation.z)));
    }
    for (decl::Md5SubMesh& m : mesh.meshes)
        for (decl::Md5Weight& w : m.weights) w.offset = toVec3(scale * fromVec3(w.offset));
    return mesh;
}

} // namespace

Eigen::Vector3d md5Orientation(const Eigen::Matrix3d& rotation) {
    Eigen::Quaterniond q(rotation);
    q.normalize();
    // The engine applies R(q)ᵀ, so the file holds the conjugate; w is implicit and non-negative (§7.3).
    if (q.w() < 0) q.coeffs() = -q.coeffs();
    return {-q.x(), -q.y(), -q.z()};
}

std::vector<std::vector<Eigen::Vector3d>> skinnedBindVertices(const decl::Md5Mesh& mesh) {
    std::vector<figure::Transform> joints;
    joints.reserve(mesh.joints.size());
    for (const decl::Md5Joint& j : mesh.joints)
        joints.push_back(
            {figure::rotationFromMd5(j.orientation.x, j.orientation.y, j.orientation.z), fromVec3(j.position)});
    std::vector<std::vector<Eigen::Vector3d>> out;
    for (const decl::Md5SubMesh& m : mesh.meshes) {
        std::vector<Eigen::Vector3d> verts;
        verts.reserve(m.verts.size());
        for (const decl::Md5Vert& v : m.verts) {
            Eigen::Vector3d p = Eigen::Vector3d::Zero();
            for (int k = 0; k < v.weightCount; ++k) {
                const decl::Md5Weight& w = m.weights[static_cast<std::size_t>(v.firstWeight + k)];
                p += w.bias * joints[static_cast<std::size_t>(w.joint)].apply(fromVec3(w.offset));
            }
            verts.push_back(p);
        }
        out.push_back(std::move(verts));
    }
    return out;
}

Rig rigFromMd5(const decl::Md5Mesh& source) {
    decl::Md5Mesh mesh = source;
    const bool hasOrigin = !mesh.joints.empty() && namesEqualIgnoringCase(mesh.joints[0].name, "origin");
    if (!hasOrigin) {
        // Doom's base body drives the first child of "origin" (docs/format.md §2.4): give the rig one, at the identity.
        for (decl::Md5Joint& j : mesh.joints) j.parent += 1;
        mesh.joints.insert(mesh.joints.begin(), decl::Md5Joint{"origin", -1, {}, {}});
        for (decl::Md5SubMesh& m : mesh.meshes)
            for (decl::Md5Weight& w : m.weights) w.joint += 1;
    }
    // Every other root hangs under joint 0 (absolute bind positions are unchanged).
    for (std::size_t i = 1; i < mesh.joints.size(); ++i)
        if (mesh.joints[i].parent < 0) mesh.joints[i].parent = 0;

    Rig rig;
    for (const decl::Md5Joint& j : mesh.joints)
        rig.joints.push_back(
            {j.name,
             j.parent,
             {figure::rotationFromMd5(j.orientation.x, j.orientation.y, j.orientation.z), fromVec3(j.position)}});
    const auto positions = skinnedBindVertices(mesh);
    for (std::size_t mi = 0; mi < mesh.meshes.size(); ++mi) {
        const decl::Md5SubMesh& m = mesh.meshes[mi];
        RigSurface surface{m.name, m.shader, {}, {}};
        for (std::size_t vi = 0; vi < m.verts.size(); ++vi) {
            const decl::Md5Vert& v = m.verts[vi];
            RigVertex rv{positions[mi][vi], v.s, v.t, {}};
            double sum = 0;
            for (int k = 0; k < v.weightCount; ++k) {
                const decl::Md5Weight& w = m.weights[static_cast<std::size_t>(v.firstWeight + k)];
                const double bias = std::isfinite(w.bias) ? std::max(w.bias, 0.0) : 0.0;
                sum += bias;
                rv.influences.push_back({w.joint, bias});
            }
            for (RigInfluence& in : rv.influences) in.weight = sum > 0 ? in.weight / sum : 1.0 / v.weightCount;
            std::erase_if(rv.influences, [](const RigInfluence& in) { return in.weight <= 0; });
            surface.vertices.push_back(std::move(rv));
        }
        for (const decl::Md5Tri& t : m.tris) surface.triangles.push_back({t.v[0], t.v[1], t.v[2]});
        rig.surfaces.push_back(std::move(surface));
    }
    rig.md5 = std::move(mesh);
    return rig;
}

std::optional<Rig> rigFromMd5(const decl::Md5Mesh& mesh, const ImportOptions& options, const std::string& label,
                              text::Diagnostics& diagnostics) {
    RigUnits units;
    units.up = options.up.value_or('z');
    units.fileHeight = md5Height(mesh);
    if (options.heightM) {
        if (!(units.fileHeight > 0)) {
            diagnostics.error({label, 0, 0}, "the model has no extent: it cannot be scaled to a height");
            return std::nullopt;
        }
        units.metresPerUnit = *options.heightM / units.fileHeight;
        units.source = RigUnits::Source::Height;
    } else if (options.metresPerUnit) {
        units.metresPerUnit = *options.metresPerUnit;
        units.source = RigUnits::Source::Option;
    } else if (units.fileHeight > 0 && units.fileHeight * kMetresPerDoomUnit < kMd5MetresBelowM) {
        units.metresPerUnit = 1;
        units.source = RigUnits::Source::Detected;
    }
    if (units.fileHeight * units.metresPerUnit > kMaxModelM) {
        diagnostics.error({label, 0, 0}, "the model is " + std::to_string(units.fileHeight * units.metresPerUnit) +
                                             " m large at this scale (at most 100 m): give --unit-m or --height");
        return std::nullopt;
    }
    Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
    if (units.up == 'y') axes << 0, 0, 1, 1, 0, 0, 0, 1, 0; // model Y → Doom Z, model Z → Doom X (as assimp's)
    const double scale = units.metresPerUnit / kMetresPerDoomUnit;
    Rig rig = scale == 1 && units.up == 'z' ? rigFromMd5(mesh) : rigFromMd5(transformedMd5(mesh, scale, axes));
    rig.units = units;
    return rig;
}

decl::Md5Mesh toMd5Mesh(const Rig& rig, const std::string& commandline) {
    if (rig.md5) return *rig.md5;
    decl::Md5Mesh mesh;
    mesh.commandline = commandline;
    for (const RigJoint& j : rig.joints)
        mesh.joints.push_back({j.name, j.parent, toVec3(j.bind.position), toVec3(md5Orientation(j.bind.rotation))});
    for (const RigSurface& s : rig.surfaces) {
        decl::Md5SubMesh m;
        m.name = s.name;
        m.shader = s.material;
        for (const RigVertex& v : s.vertices) {
            m.verts.push_back({v.s, v.t, static_cast<int>(m.weights.size()), static_cast<int>(v.influences.size())});
            for (const RigInfluence& in : v.influences) {
                const figure::Transform& j = rig.joints[static_cast<std::size_t>(in.joint)].bind;
                m.weights.push_back({in.joint, in.weight, toVec3(j.inverse().apply(v.position))});
            }
        }
        for (const auto& t : s.triangles) m.tris.push_back({{t[0], t[1], t[2]}});
        mesh.meshes.push_back(std::move(m));
    }
    return mesh;
}

decl::Md5Anim bindPoseAnim(const Rig& rig, const std::string& commandline) {
    decl::Md5Anim anim;
    anim.commandline = commandline;
    anim.frameRate = 24;
    anim.numAnimatedComponents = 0;
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (const RigSurface& s : rig.surfaces)
        for (const RigVertex& v : s.vertices) {
            lo = lo.cwiseMin(v.position);
            hi = hi.cwiseMax(v.position);
        }
    for (const RigJoint& j : rig.joints) {
        lo = lo.cwiseMin(j.bind.position);
        hi = hi.cwiseMax(j.bind.position);
    }
    for (std::size_t i = 0; i < rig.joints.size(); ++i) {
        const RigJoint& j = rig.joints[i];
        anim.hierarchy.push_back({j.name, j.parent, 0, 0});
        figure::Transform local = j.bind;
        if (j.parent >= 0) local = rig.joints[static_cast<std::size_t>(j.parent)].bind.inverse() * j.bind;
        anim.baseframe.push_back({toVec3(local.position), toVec3(md5Orientation(local.rotation))});
    }
    anim.bounds.push_back({toVec3(lo), toVec3(hi)});
    anim.frames.push_back({});
    return anim;
}

} // namespace afb::gen
