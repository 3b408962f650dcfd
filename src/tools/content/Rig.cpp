#include "Rig.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "Common.h"

namespace afb::gen {

using Eigen::Quaterniond;
using Eigen::Vector3d;

namespace {

decl::Vec3 rounded(const Vector3d& v, int decimals) {
    return {rnd(v.x(), decimals), rnd(v.y(), decimals), rnd(v.z(), decimals)};
}

/// The md5 way to write a standard rotation: (−x, −y, −z) of the quaternion with w ≥ 0 (docs/format.md §7.3).
Vector3d md5Quat(Quaterniond q) {
    q.normalize();
    if (q.w() < 0) q.coeffs() *= -1.0;
    return Vector3d(-q.x(), -q.y(), -q.z());
}

/// Bounds of the skinned meshes in `pose` (forward kinematics, then the weights).
std::pair<Vector3d, Vector3d> skinnedBounds(const Skeleton& sk, const std::vector<Mesh>& meshes, const Pose& pose) {
    std::vector<Eigen::Matrix3d> R(sk.joints.size());
    std::vector<Vector3d> P(sk.joints.size());
    for (std::size_t i = 0; i < sk.joints.size(); ++i) {
        const int p = sk.joints[i].parent;
        const Eigen::Matrix3d local = pose.q[i].normalized().toRotationMatrix();
        if (p < 0) {
            R[i] = local;
            P[i] = Vector3d::Zero(); // the md5anim loader zeroes the root translation
        } else {
            const auto parent = static_cast<std::size_t>(p);
            R[i] = R[parent] * local;
            P[i] = P[parent] + R[parent] * pose.t[i];
        }
    }
    Vector3d lo = Vector3d::Constant(1e30), hi = Vector3d::Constant(-1e30);
    for (const Mesh& m : meshes)
        for (const Vert& v : m.verts) {
            Vector3d x = Vector3d::Zero();
            for (int k = 0; k < v.count; ++k) {
                const Weight& w = m.weights[static_cast<std::size_t>(v.firstWeight + k)];
                const auto j = static_cast<std::size_t>(w.joint);
                x += w.bias * (P[j] + R[j] * w.offset);
            }
            lo = lo.cwiseMin(x);
            hi = hi.cwiseMax(x);
        }
    return {lo, hi};
}

} // namespace

int Skeleton::add(const std::string& name, const std::string& parent, Vector3d pos) {
    const int p = parent.empty() ? -1 : index(parent);
    joints.push_back({name, p, pos});
    return static_cast<int>(joints.size()) - 1;
}

int Skeleton::index(const std::string& name) const {
    for (std::size_t i = 0; i < joints.size(); ++i)
        if (joints[i].name == name) return static_cast<int>(i);
    throw std::runtime_error("no joint " + name);
}

Vector3d Skeleton::pos(const std::string& name) const { return joints[static_cast<std::size_t>(index(name))].pos; }

int Mesh::vertex(const Skeleton& sk, Vector3d p, double s, double t,
                 const std::vector<std::pair<int, double>>& influences) {
    Vert v;
    v.s = s;
    v.t = t;
    v.firstWeight = static_cast<int>(weights.size());
    // Bind orientations are the identity, so a weight's offset R_jointᵀ(p − p_joint) is simply p − p_joint.
    for (const auto& [j, b] : influences) weights.push_back({j, b, p - sk.joints[static_cast<std::size_t>(j)].pos});
    v.count = static_cast<int>(influences.size());
    verts.push_back(v);
    return static_cast<int>(verts.size()) - 1;
}

TubeRadius linear(double ru0, double rv0, double ru1, double rv1) {
    return [=](double t) { return Eigen::Vector2d(ru0 + (ru1 - ru0) * t, rv0 + (rv1 - rv0) * t); };
}

void tube(Mesh& m, const Skeleton& sk, Vector3d a, Vector3d b, const TubeRadius& radius, const TubeSpec& spec) {
    const int rings = spec.rings, sides = spec.sides;
    const Vector3d d = (b - a).normalized();
    const Vector3d ref = std::abs(d.z()) > 0.7 ? Vector3d::UnitX() : Vector3d::UnitZ();
    const Vector3d u = (ref - d * d.dot(ref)).normalized();
    const Vector3d v = d.cross(u);
    auto influences = [&](double t) {
        std::vector<std::pair<int, double>> w;
        if (spec.blendJoint >= 0 && t < 0.25) {
            const double k = rnd(0.5 + 2.0 * t, 4);
            w = {{spec.joint, k}, {spec.blendJoint, rnd(1.0 - k, 4)}};
        } else {
            w = {{spec.joint, 1.0}};
        }
        return w;
    };
    const int first = static_cast<int>(m.verts.size());
    for (int r = 0; r < rings; ++r) {
        const double t = rings > 1 ? double(r) / (rings - 1) : 0.0;
        const Eigen::Vector2d rad = radius(t);
        const Vector3d c = a + (b - a) * t;
        for (int i = 0; i < sides; ++i) {
            const double th = 2 * kPi * i / sides;
            const Vector3d p = c + u * (rad.x() * std::cos(th)) + v * (rad.y() * std::sin(th));
            m.vertex(sk, p, double(i) / sides, t, influences(t));
        }
    }
    for (int r = 0; r + 1 < rings; ++r)
        for (int i = 0; i < sides; ++i) {
            const int i1 = (i + 1) % sides;
            const int p00 = first + r * sides + i, p01 = first + r * sides + i1;
            const int p10 = first + (r + 1) * sides + i, p11 = first + (r + 1) * sides + i1;
            m.tris.push_back({p00, p10, p01});
            m.tris.push_back({p01, p10, p11});
        }
    if (spec.capA) {
        const int c = m.vertex(sk, a, 0.5, 0, influences(0));
        for (int i = 0; i < sides; ++i) m.tris.push_back({c, first + i, first + (i + 1) % sides});
    }
    if (spec.capB) {
        const int c = m.vertex(sk, b, 0.5, 1, influences(1));
        const int last = first + (rings - 1) * sides;
        for (int i = 0; i < sides; ++i) m.tris.push_back({c, last + (i + 1) % sides, last + i});
    }
}

void boxMesh(Mesh& m, const Skeleton& sk, Vector3d lo, Vector3d hi, int joint) {
    const int first = static_cast<int>(m.verts.size());
    for (int i = 0; i < 8; ++i) {
        const Vector3d p((i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(), (i & 4) ? hi.z() : lo.z());
        m.vertex(sk, p, (i & 1) ? 1 : 0, (i & 2) ? 1 : 0, {{joint, 1.0}});
    }
    static const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& f : faces) {
        m.tris.push_back({first + f[0], first + f[1], first + f[2]});
        m.tris.push_back({first + f[0], first + f[2], first + f[3]});
    }
}

Pose bindPose(const Skeleton& sk) {
    Pose p;
    for (const Joint& j : sk.joints) {
        p.t.push_back(j.parent < 0 ? Vector3d::Zero()
                                   : Vector3d(j.pos - sk.joints[static_cast<std::size_t>(j.parent)].pos));
        p.q.push_back(Quaterniond::Identity());
    }
    return p;
}

decl::Md5Mesh toMd5Mesh(const Skeleton& sk, const std::vector<Mesh>& meshes, const std::string& commandline) {
    decl::Md5Mesh out;
    out.commandline = commandline;
    for (const Joint& j : sk.joints) out.joints.push_back({j.name, j.parent, rounded(j.pos, 4), {0, 0, 0}});
    for (const Mesh& m : meshes) {
        decl::Md5SubMesh sub;
        sub.name = m.name;
        sub.shader = m.shader;
        for (const Vert& v : m.verts) sub.verts.push_back({rnd(v.s), rnd(v.t), v.firstWeight, v.count});
        for (const auto& t : m.tris) sub.tris.push_back({{t[0], t[1], t[2]}});
        for (const Weight& w : m.weights) sub.weights.push_back({w.joint, rnd(w.bias), rounded(w.offset, 4)});
        out.meshes.push_back(std::move(sub));
    }
    return out;
}

decl::Md5Anim toMd5Anim(const Skeleton& sk, const std::vector<Mesh>& meshes, const std::vector<Pose>& frames,
                        const std::vector<int>& animated, int frameRate, const std::string& commandline) {
    decl::Md5Anim out;
    out.commandline = commandline;
    out.frameRate = frameRate;
    int numComponents = 0;
    for (std::size_t j = 0; j < sk.joints.size(); ++j) {
        const int flags = animated[j];
        out.hierarchy.push_back({sk.joints[j].name, sk.joints[j].parent, flags, flags ? numComponents : 0});
        numComponents += decl::animatedComponentCount(flags);
    }
    out.numAnimatedComponents = numComponents;
    for (const Pose& f : frames) {
        const auto [lo, hi] = skinnedBounds(sk, meshes, f);
        out.bounds.push_back({rounded(lo, 4), rounded(hi, 4)});
    }
    const Pose& base = frames.front();
    for (std::size_t j = 0; j < sk.joints.size(); ++j)
        out.baseframe.push_back({rounded(base.t[j], 4), rounded(md5Quat(base.q[j]), 6)});
    for (const Pose& f : frames) {
        std::vector<double> values;
        for (std::size_t j = 0; j < sk.joints.size(); ++j) {
            const Vector3d q = md5Quat(f.q[j]);
            for (int b = 0; b < 6; ++b)
                if ((animated[j] >> b) & 1) values.push_back(b < 3 ? rnd(f.t[j][b], 4) : rnd(q[b - 3], 6));
        }
        out.frames.push_back(std::move(values));
    }
    return out;
}

decl::Md5Anim afPoseAnim(const Skeleton& sk, const std::vector<Mesh>& meshes, const std::string& commandline) {
    return toMd5Anim(sk, meshes, {bindPose(sk)}, std::vector<int>(sk.joints.size(), 0), 24, commandline);
}

} // namespace afb::gen
