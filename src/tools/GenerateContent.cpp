// afb_gen_content: generates the project's own bundled content (no id Software data is used or copied).
//
// What it writes into OUTDIR (same layout as the repository root):
//   models/md5/humanoid/humanoid.md5mesh, af_pose.md5anim, walk.md5anim  a rigged, skinned humanoid (~71 units)
//   af/humanoid.af                                                        its 15-body ragdoll
//   models/md5/props/props.md5mesh, props_af_pose.md5anim + af/props.af  one body per shape type, joined by springs
//   models/md5/props/lamp/*  + af/lamp.af                                a lamp shade hanging on a short chain
//   models/md5/props/buggy/* + af/buggy.af                               a chassis with four sprung wheels
//   def/humanoid.def, def/props.def                                      model decls and entityDefs
//
// Re-run from the repository root:   afb_gen_content .
// The output is deterministic (no randomness, no time; numbers are rounded to a fixed number of decimals and
// the .af files are printed by decl::writeAf, so they are canonical). tests/cli/content.cmake checks that a
// fresh run reproduces the committed files byte for byte.
//
// Licence: the generated content is MIT licensed, like the code of this project.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "afb/decl/Af.h"
#include "afb/decl/AfParser.h"

namespace {

using Eigen::Quaterniond;
using Eigen::Vector3d;
namespace fs = std::filesystem;
using namespace afb::decl;

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;

// --- number formatting ---------------------------------------------------------------------------------------

/// Fixed-point with `decimals` decimals, trailing zeros stripped, never "-0".
std::string num(double v, int decimals = 4) {
    const double scale = std::pow(10.0, decimals);
    double r = std::round(v * scale) / scale;
    if (r == 0.0) r = 0.0; // drops the sign of -0
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", decimals, r);
    std::string s = buf;
    if (s.find('.') != std::string::npos) {
        while (!s.empty() && s.back() == '0') s.pop_back();
        if (!s.empty() && s.back() == '.') s.pop_back();
    }
    if (s == "-0") s = "0";
    return s;
}

/// A value rounded to `decimals` decimals, so that writeAf prints it short and the same everywhere.
double rnd(double v, int decimals = 4) {
    const double scale = std::pow(10.0, decimals);
    const double r = std::round(v * scale) / scale;
    return r == 0.0 ? 0.0 : r;
}

// --- skeletons and meshes ------------------------------------------------------------------------------------

struct Joint {
    std::string name;
    int parent = -1;
    Vector3d pos = Vector3d::Zero(); ///< model space, bind pose (all bind orientations are the identity)
};

struct Skeleton {
    std::vector<Joint> joints;
    int add(const std::string& name, const std::string& parent, Vector3d pos) {
        int p = -1;
        if (!parent.empty()) p = index(parent);
        joints.push_back({name, p, pos});
        return static_cast<int>(joints.size()) - 1;
    }
    int index(const std::string& name) const {
        for (std::size_t i = 0; i < joints.size(); ++i)
            if (joints[i].name == name) return static_cast<int>(i);
        throw std::runtime_error("no joint " + name);
    }
    Vector3d pos(const std::string& name) const { return joints[static_cast<std::size_t>(index(name))].pos; }
};

struct Weight {
    int joint = 0;
    double bias = 1;
    Vector3d offset = Vector3d::Zero();
};

struct Vert {
    double s = 0, t = 0;
    int firstWeight = 0, count = 0;
    Vector3d pos = Vector3d::Zero();
};

struct Mesh {
    std::string name, shader;
    std::vector<Vert> verts;
    std::vector<std::array<int, 3>> tris;
    std::vector<Weight> weights;

    /// Adds a vertex at model-space `p` skinned to `influences` (joint, bias). Bind orientations are the
    /// identity, so a weight's offset R_jointᵀ(p − p_joint) is simply p − p_joint.
    int vertex(const Skeleton& sk, Vector3d p, double s, double t, const std::vector<std::pair<int, double>>& infl) {
        Vert v;
        v.s = s;
        v.t = t;
        v.pos = p;
        v.firstWeight = static_cast<int>(weights.size());
        for (const auto& [j, b] : infl) weights.push_back({j, b, p - sk.joints[static_cast<std::size_t>(j)].pos});
        v.count = static_cast<int>(infl.size());
        verts.push_back(v);
        return static_cast<int>(verts.size()) - 1;
    }
};

/// A capsule-like tube from a to b: `rings` rings of `sides` vertices; `radius(t)` gives the two half-axes
/// (across u, across v) at t in [0, 1]. Vertices are weighted to `joint`, blended with `blendJoint` near a.
void tube(Mesh& m, const Skeleton& sk, Vector3d a, Vector3d b, const std::function<Eigen::Vector2d(double)>& radius,
          int joint, int blendJoint, int rings, int sides, bool capA, bool capB) {
    const Vector3d d = (b - a).normalized();
    const Vector3d ref = std::abs(d.z()) > 0.7 ? Vector3d::UnitX() : Vector3d::UnitZ();
    const Vector3d u = (ref - d * d.dot(ref)).normalized();
    const Vector3d v = d.cross(u);
    auto influences = [&](double t) {
        std::vector<std::pair<int, double>> w;
        if (blendJoint >= 0 && t < 0.25) {
            const double k = rnd(0.5 + 2.0 * t, 4);
            w = {{joint, k}, {blendJoint, rnd(1.0 - k, 4)}};
        } else {
            w = {{joint, 1.0}};
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
    if (capA) {
        const int c = m.vertex(sk, a, 0.5, 0, influences(0));
        for (int i = 0; i < sides; ++i) m.tris.push_back({c, first + i, first + (i + 1) % sides});
    }
    if (capB) {
        const int c = m.vertex(sk, b, 0.5, 1, influences(1));
        const int last = first + (rings - 1) * sides;
        for (int i = 0; i < sides; ++i) m.tris.push_back({c, last + (i + 1) % sides, last + i});
    }
}

std::function<Eigen::Vector2d(double)> linear(double ru0, double rv0, double ru1, double rv1) {
    return [=](double t) { return Eigen::Vector2d(ru0 + (ru1 - ru0) * t, rv0 + (rv1 - rv0) * t); };
}

/// A closed box of 8 vertices and 12 triangles, all weighted to one joint.
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

std::string vec(const Vector3d& v, int decimals = 4) {
    return "( " + num(v.x(), decimals) + " " + num(v.y(), decimals) + " " + num(v.z(), decimals) + " )";
}

/// The md5 way to write a standard rotation: (−x, −y, −z) of the quaternion with w ≥ 0 (af-format §7.3).
Vector3d md5Quat(Quaterniond q) {
    q.normalize();
    if (q.w() < 0) q.coeffs() *= -1.0;
    return Vector3d(-q.x(), -q.y(), -q.z());
}

std::string writeMesh(const Skeleton& sk, const std::vector<Mesh>& meshes, const std::string& commandline) {
    std::string out = "MD5Version 10\ncommandline \"" + commandline + "\"\n\n";
    out += "numJoints " + std::to_string(sk.joints.size()) + "\nnumMeshes " + std::to_string(meshes.size()) + "\n\n";
    out += "joints {\n";
    for (const Joint& j : sk.joints)
        out += "\t\"" + j.name + "\"\t" + std::to_string(j.parent) + " " + vec(j.pos) + " ( 0 0 0 )\n";
    out += "}\n";
    for (const Mesh& m : meshes) {
        out += "\nmesh {\n";
        if (!m.name.empty()) out += "\tname \"" + m.name + "\"\n";
        out += "\tshader \"" + m.shader + "\"\n\n";
        out += "\tnumverts " + std::to_string(m.verts.size()) + "\n";
        for (std::size_t i = 0; i < m.verts.size(); ++i) {
            const Vert& v = m.verts[i];
            out += "\tvert " + std::to_string(i) + " ( " + num(v.s) + " " + num(v.t) + " ) " +
                   std::to_string(v.firstWeight) + " " + std::to_string(v.count) + "\n";
        }
        out += "\n\tnumtris " + std::to_string(m.tris.size()) + "\n";
        for (std::size_t i = 0; i < m.tris.size(); ++i)
            out += "\ttri " + std::to_string(i) + " " + std::to_string(m.tris[i][0]) + " " +
                   std::to_string(m.tris[i][1]) + " " + std::to_string(m.tris[i][2]) + "\n";
        out += "\n\tnumweights " + std::to_string(m.weights.size()) + "\n";
        for (std::size_t i = 0; i < m.weights.size(); ++i) {
            const Weight& w = m.weights[i];
            out += "\tweight " + std::to_string(i) + " " + std::to_string(w.joint) + " " + num(w.bias) + " " +
                   vec(w.offset) + "\n";
        }
        out += "}\n";
    }
    return out;
}

/// One pose: parent-relative translation and rotation (standard) per joint.
struct Pose {
    std::vector<Vector3d> t;
    std::vector<Quaterniond> q;
};

Pose bindPose(const Skeleton& sk) {
    Pose p;
    for (const Joint& j : sk.joints) {
        p.t.push_back(j.parent < 0 ? Vector3d::Zero() : Vector3d(j.pos - sk.joints[static_cast<std::size_t>(j.parent)].pos));
        p.q.push_back(Quaterniond::Identity());
    }
    return p;
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
            R[i] = R[static_cast<std::size_t>(p)] * local;
            P[i] = P[static_cast<std::size_t>(p)] + R[static_cast<std::size_t>(p)] * pose.t[i];
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

/// An md5anim. `frames` are full poses; `animated[j]` holds the component flags (bit 0..5 = Tx..Qz) per joint.
std::string writeAnim(const Skeleton& sk, const std::vector<Mesh>& meshes, const std::vector<Pose>& frames,
                      const std::vector<int>& animated, int frameRate, const std::string& commandline) {
    int numComponents = 0;
    std::vector<int> start(sk.joints.size(), 0);
    for (std::size_t j = 0; j < sk.joints.size(); ++j) {
        start[j] = animated[j] ? numComponents : 0;
        for (int b = 0; b < 6; ++b) numComponents += (animated[j] >> b) & 1;
    }
    std::string out = "MD5Version 10\ncommandline \"" + commandline + "\"\n\n";
    out += "numFrames " + std::to_string(frames.size()) + "\nnumJoints " + std::to_string(sk.joints.size()) +
           "\nframeRate " + std::to_string(frameRate) + "\nnumAnimatedComponents " + std::to_string(numComponents) +
           "\n\n";
    out += "hierarchy {\n";
    for (std::size_t j = 0; j < sk.joints.size(); ++j)
        out += "\t\"" + sk.joints[j].name + "\"\t" + std::to_string(sk.joints[j].parent) + " " +
               std::to_string(animated[j]) + " " + std::to_string(start[j]) + "\n";
    out += "}\n\nbounds {\n";
    for (const Pose& f : frames) {
        const auto [lo, hi] = skinnedBounds(sk, meshes, f);
        out += "\t" + vec(lo) + " " + vec(hi) + "\n";
    }
    out += "}\n\nbaseframe {\n";
    const Pose& base = frames.front();
    for (std::size_t j = 0; j < sk.joints.size(); ++j)
        out += "\t" + vec(base.t[j]) + " " + vec(md5Quat(base.q[j]), 6) + "\n";
    out += "}\n";
    for (std::size_t f = 0; f < frames.size(); ++f) {
        out += "\nframe " + std::to_string(f) + " {\n";
        for (std::size_t j = 0; j < sk.joints.size(); ++j) {
            if (!animated[j]) continue;
            const Vector3d q = md5Quat(frames[f].q[j]);
            std::string line = "\t";
            for (int b = 0; b < 6; ++b) {
                if (!((animated[j] >> b) & 1)) continue;
                const double value = b < 3 ? frames[f].t[j][b] : q[b - 3];
                line += num(value, b < 3 ? 4 : 6) + " ";
            }
            line.pop_back();
            out += line + "\n";
        }
        out += "}\n";
    }
    return out;
}

std::string writeAfPose(const Skeleton& sk, const std::vector<Mesh>& meshes, const std::string& commandline) {
    return writeAnim(sk, meshes, {bindPose(sk)}, std::vector<int>(sk.joints.size(), 0), 24, commandline);
}

// --- .af building helpers ------------------------------------------------------------------------------------

AfVector lit(double x, double y, double z) { return AfVector::fromLiteral({rnd(x, 6), rnd(y, 6), rnd(z, 6)}); }
AfVector lit(const Vector3d& v) { return lit(v.x(), v.y(), v.z()); }
AfVector jointV(const std::string& j) { return AfVector::fromJoint(j); }
AfVector boneCenter(const std::string& a, const std::string& b) { return AfVector::fromBoneCenter(a, b); }
AfVector boneDir(const std::string& a, const std::string& b, bool negated = false) {
    return AfVector::fromBoneDir(a, b, negated);
}

AfShape shape(ShapeKind kind, Vector3d lo, Vector3d hi, std::int64_t sides = 3) {
    AfShape s;
    s.kind = kind;
    s.v1 = lit(lo);
    s.v2 = lit(hi);
    s.numSides = sides;
    return s;
}
AfShape boneShape(const std::string& a, const std::string& b, double width) {
    AfShape s;
    s.kind = ShapeKind::Bone;
    s.v1 = jointV(a);
    s.v2 = jointV(b);
    s.width = rnd(width);
    return s;
}

/// Volume at density 1 of a shape (af-format §3.2 closed forms); bone length from the skeleton.
double volumeOf(const AfShape& s, const Skeleton& sk) {
    if (s.kind == ShapeKind::Bone) return s.width * s.width * (sk.pos(s.v2.joint1) - sk.pos(s.v1.joint1)).norm() / 8.0;
    const Vector3d e(s.v2.literal.x - s.v1.literal.x, s.v2.literal.y - s.v1.literal.y, s.v2.literal.z - s.v1.literal.z);
    const double n = static_cast<double>(s.numSides);
    switch (s.kind) {
    case ShapeKind::Box: return e.x() * e.y() * e.z();
    case ShapeKind::Octahedron: return e.x() * e.y() * e.z() / 6.0;
    case ShapeKind::Dodecahedron: return (3 * std::sqrt(5.0) - 5) / 4 * e.x() * e.y() * e.z();
    case ShapeKind::Cylinder: return n / 2 * std::sin(2 * kPi / n) * e.x() / 2 * e.y() / 2 * e.z();
    case ShapeKind::Cone: return n / 6 * std::sin(2 * kPi / n) * e.x() / 2 * e.y() / 2 * e.z();
    default: return 1;
    }
}

struct AfBuilder {
    AfDecl decl;
    const Skeleton& sk;

    AfBuilder(const std::string& name, const Skeleton& skel) : sk(skel) { decl.name = name; }

    void settings(const std::string& model, double totalMass) {
        AfSettings s;
        s.model = model;
        s.friction = SettingsFriction{0.01, 0.01, 0.8, std::nullopt};
        s.suspendSpeed = std::array<double, 4>{20, 30, 40, 60};
        s.noMoveTime = 1;
        s.noMoveTranslation = 10;
        s.noMoveRotation = 10;
        s.minMoveTime = -1;
        s.maxMoveTime = -1;
        s.totalMass = totalMass;
        s.contents = ContentsList{{"corpse"}};
        s.clipMask = ContentsList{{"solid", "corpse"}};
        s.selfCollision = true;
        decl.order.push_back({AfBlockRef::Kind::Settings, decl.settings.size()});
        decl.settings.push_back(s);
    }

    /// A body whose density gives it `mass` (before the settings' totalMass rescaling).
    AfBody& body(const std::string& name, const std::string& joint, AfShape model, AfVector origin, double mass,
                 const std::string& contained, bool selfCollision = true) {
        AfBody b;
        b.name = name;
        b.joint = joint;
        b.mod = "orientation";
        b.density = rnd(mass / volumeOf(model, sk), 6);
        b.model = model;
        b.origin = origin;
        b.selfCollision = selfCollision;
        b.containedJoints = contained;
        decl.order.push_back({AfBlockRef::Kind::Body, decl.bodies.size()});
        decl.bodies.push_back(b);
        return decl.bodies.back();
    }

    AfConstraint& constraint(ConstraintType type, const std::string& name, const std::string& body1,
                             const std::string& body2) {
        AfConstraint c;
        c.type = type;
        c.name = name;
        c.body1 = body1;
        c.body2 = body2;
        decl.order.push_back({AfBlockRef::Kind::Constraint, decl.constraints.size()});
        decl.constraints.push_back(c);
        return decl.constraints.back();
    }

    AfConstraint& spring(const std::string& name, const std::string& body1, const std::string& body2, AfVector a1,
                         AfVector a2, double rest, double minL, double maxL) {
        AfConstraint& c = constraint(ConstraintType::Spring, name, body1, body2);
        c.anchor = a1;
        c.anchor2 = a2;
        c.stretch = 20;
        c.compress = 10;
        c.damping = 50;
        c.restLength = rnd(rest);
        c.minLength = rnd(minL);
        c.maxLength = rnd(maxL);
        return c;
    }
};

// --- output --------------------------------------------------------------------------------------------------

struct Output {
    fs::path root;
    std::vector<std::string> written;
    void write(const std::string& rel, const std::string& text) {
        const fs::path p = root / rel;
        fs::create_directories(p.parent_path());
        std::ofstream f(p, std::ios::binary | std::ios::trunc);
        if (!f) throw std::runtime_error("cannot write " + p.string());
        f << text;
        if (!f) throw std::runtime_error("cannot write " + p.string());
        written.push_back(rel);
    }
};

// --- the humanoid ----------------------------------------------------------------------------------------------

Skeleton humanoidSkeleton() {
    Skeleton s;
    const double c = std::cos(45 * kDeg), sn = std::sin(45 * kDeg);
    s.add("origin", "", {0, 0, 0});
    s.add("pelvis", "origin", {0, 0, 38});
    s.add("spine", "pelvis", {0, 0, 43});
    s.add("chest", "spine", {0, 0, 50});
    s.add("neck", "chest", {0, 0, 59});
    s.add("head", "neck", {0, 0, 62.5});
    s.add("head_end", "head", {0, 0, 71});
    s.add("jaw", "head", {1.5, 0, 61.5});
    for (const char* side : {"l", "r"}) {
        const std::string p = side;
        const double sy = p == "l" ? 1 : -1;
        const Vector3d d(0, sy * c, -sn); // the arm hangs 45 degrees below horizontal
        const Vector3d shoulder(0, sy * 7.5, 57);
        s.add(p + "_clavicle", "chest", {0, sy * 2, 57});
        s.add(p + "_upperarm", p + "_clavicle", shoulder);
        s.add(p + "_forearm", p + "_upperarm", shoulder + 11 * d);
        s.add(p + "_hand", p + "_forearm", shoulder + 21 * d);
        s.add(p + "_finger1", p + "_hand", shoulder + 24.5 * d);
        s.add(p + "_finger2", p + "_finger1", shoulder + 26.5 * d);
        s.add(p + "_thumb", p + "_hand", shoulder + 22.5 * d + Vector3d(1.2, 0, 0));
    }
    for (const char* side : {"l", "r"}) {
        const std::string p = side;
        const double sy = p == "l" ? 1 : -1;
        s.add(p + "_thigh", "pelvis", {0, sy * 4, 37});
        s.add(p + "_shin", p + "_thigh", {0, sy * 5, 20});
        s.add(p + "_foot", p + "_shin", {0, sy * 6, 3});
        s.add(p + "_toe", p + "_foot", {5, sy * 6, 1});
    }
    return s;
}

std::vector<Mesh> humanoidMeshes(const Skeleton& sk) {
    Mesh body;
    body.name = "body";
    body.shader = "models/humanoid/body";
    Mesh head;
    head.name = "head";
    head.shader = "models/humanoid/head";
    const int N = 12;
    auto J = [&](const std::string& n) { return sk.index(n); };
    auto P = [&](const std::string& n) { return sk.pos(n); };
    // Torso: hips, abdomen, chest (elliptic: deeper across Y than across X).
    tube(body, sk, {0, 0, 32}, {0, 0, 43}, linear(4.8, 7.2, 4.4, 6.4), J("pelvis"), -1, 6, N, true, false);
    tube(body, sk, {0, 0, 43}, {0, 0, 50}, linear(4.4, 6.4, 5.2, 7.6), J("spine"), J("pelvis"), 5, N, false, false);
    tube(body, sk, {0, 0, 50}, {0, 0, 59}, linear(5.2, 7.6, 3.6, 6.6), J("chest"), J("spine"), 6, N, false, true);
    tube(body, sk, {0, 0, 58}, {0, 0, 62.5}, linear(2.1, 2.1, 2.0, 2.0), J("neck"), J("chest"), 3, N, false, false);
    // Head: a bulging tube with caps, plus the jaw.
    tube(head, sk, {0.5, 0, 60.8}, {0.5, 0, 71},
         [](double t) {
             const double k = std::pow(std::sin(kPi * (0.1 + 0.8 * t)), 0.6);
             return Eigen::Vector2d(4.2 * k, 3.6 * k);
         },
         J("head"), J("neck"), 8, N, true, true);
    tube(head, sk, P("jaw"), P("jaw") + Vector3d(2.6, 0, -1.2), linear(1.6, 2.2, 1.0, 1.4), J("jaw"), -1, 3, N, true,
         true);
    for (const char* side : {"l", "r"}) {
        const std::string p = side;
        tube(body, sk, P(p + "_upperarm"), P(p + "_forearm"), linear(2.2, 2.2, 1.7, 1.7), J(p + "_upperarm"),
             J(p + "_clavicle"), 7, N, true, false);
        tube(body, sk, P(p + "_forearm"), P(p + "_hand"), linear(1.7, 1.7, 1.3, 1.3), J(p + "_forearm"),
             J(p + "_upperarm"), 6, N, false, false);
        tube(body, sk, P(p + "_hand"), P(p + "_finger1"), linear(1.3, 0.8, 1.6, 0.6), J(p + "_hand"),
             J(p + "_forearm"), 3, N, false, true);
        tube(body, sk, P(p + "_finger1"), P(p + "_finger2"), linear(0.5, 0.5, 0.45, 0.45), J(p + "_finger1"), -1, 3,
             N, true, false);
        const Vector3d tip = P(p + "_finger2") + (P(p + "_finger2") - P(p + "_finger1"));
        tube(body, sk, P(p + "_finger2"), tip, linear(0.45, 0.45, 0.35, 0.35), J(p + "_finger2"), J(p + "_finger1"),
             3, N, false, true);
        const Vector3d thumbTip = P(p + "_thumb") + Vector3d(1.6, 0, -0.6);
        tube(body, sk, P(p + "_thumb"), thumbTip, linear(0.45, 0.45, 0.35, 0.35), J(p + "_thumb"), -1, 3, N, true,
             true);
        tube(body, sk, P(p + "_thigh"), P(p + "_shin"), linear(3.3, 3.3, 2.3, 2.3), J(p + "_thigh"), J("pelvis"), 8,
             N, false, false);
        tube(body, sk, P(p + "_shin"), P(p + "_foot"), linear(2.3, 2.3, 1.5, 1.5), J(p + "_shin"), J(p + "_thigh"), 8,
             N, false, true);
        const Vector3d heel = P(p + "_foot") + Vector3d(-2, 0, -1.5);
        tube(body, sk, heel, P(p + "_toe"), linear(1.5, 1.8, 1.1, 1.8), J(p + "_foot"), -1, 5, N, true, false);
        tube(body, sk, P(p + "_toe"), P(p + "_toe") + Vector3d(3, 0, -0.2), linear(1.1, 1.8, 0.7, 1.5),
             J(p + "_toe"), J(p + "_foot"), 3, N, false, true);
    }
    return {body, head};
}

std::string humanoidAf(const Skeleton& sk) {
    AfBuilder af("humanoid", sk);
    af.settings("model_humanoid", 70);
    const double s45 = rnd(std::sin(45 * kDeg), 6);

    af.body("pelvis", "origin", shape(ShapeKind::Box, {-4.5, -6.5, -4}, {4.5, 6.5, 4}), lit(0, 0, 38), 10,
            "*origin -*spine -*l_thigh -*r_thigh")
        .friction = BodyFriction{0.01, 0.01, 0.8};
    af.body("torso", "spine", shape(ShapeKind::Box, {-4, -6.5, -7.5}, {4, 6.5, 7.5}), boneCenter("spine", "neck"), 14,
            "*spine -*neck -*l_upperarm -*r_upperarm")
        .friction = BodyFriction{0.01, 0.01, 0.8};
    af.body("head", "neck", shape(ShapeKind::Dodecahedron, {-4, -3.8, -1.5}, {4.5, 3.8, 8.5}), jointV("head"), 5,
            "*neck")
        .friction = BodyFriction{0.02, 0.02, 0.6};
    for (const char* side : {"l", "r"}) {
        const std::string p = side;
        const bool left = p == "l";
        af.body(p + "_upperarm", p + "_upperarm", boneShape(p + "_upperarm", p + "_forearm", 4),
                boneCenter(p + "_upperarm", p + "_forearm"), 3.5, "*" + p + "_upperarm -*" + p + "_forearm");
        af.body(p + "_forearm", p + "_forearm", boneShape(p + "_forearm", p + "_hand", 3.5),
                boneCenter(p + "_forearm", p + "_hand"), 2.5, "*" + p + "_forearm -*" + p + "_hand");
        // The hand box runs along the arm: roll turns its local Y onto the arm direction.
        AfBody& hand = af.body(p + "_hand", p + "_hand",
                               left ? shape(ShapeKind::Box, {-1, 0.5, -2}, {1, 5.5, 2})
                                    : shape(ShapeKind::Box, {-1, -5.5, -2}, {1, -0.5, 2}),
                               jointV(p + "_hand"), 1.5, "*" + p + "_hand", false);
        hand.angles = lit(0, 0, left ? -45 : 45);
        hand.friction = BodyFriction{0.02, 0.02, 0.9};
    }
    for (const char* side : {"l", "r"}) {
        const std::string p = side;
        af.body(p + "_thigh", p + "_thigh", boneShape(p + "_thigh", p + "_shin", 5.5),
                boneCenter(p + "_thigh", p + "_shin"), 9, "*" + p + "_thigh -*" + p + "_shin");
        AfBody& shin = af.body(p + "_shin", p + "_shin", boneShape(p + "_shin", p + "_foot", 4.5),
                               boneCenter(p + "_shin", p + "_foot"), 5, "*" + p + "_shin -*" + p + "_foot");
        shin.inertiaScale = std::array<double, 9>{1, 0, 0, 0, 1, 0, 0, 0, 2}; // more spin inertia: a steadier bone
        af.body(p + "_foot", p + "_foot", shape(ShapeKind::Box, {-2.5, -1.8, -3}, {8, 1.8, 1}), jointV(p + "_foot"),
                2, "*" + p + "_foot")
            .friction = BodyFriction{0.01, 0.01, 1};
    }

    {
        AfConstraint& c = af.constraint(ConstraintType::Universal, "waist", "torso", "pelvis");
        c.anchor = jointV("spine");
        c.shafts = std::array<AfVector, 2>{lit(0, 0, 1), lit(0, 0, -1)};
        c.friction = 0.5;
        c.limit = PyramidLimit{lit(0, 0, 1), 60, 50, 0, std::nullopt};
    }
    {
        AfConstraint& c = af.constraint(ConstraintType::BallAndSocket, "neck", "head", "torso");
        c.anchor = jointV("neck");
        c.friction = 0.3;
        c.limit = ConeLimit{lit(0, 0, 1), 90, lit(0, 0, 1)};
    }
    for (const char* side : {"l", "r"}) {
        const std::string p = side;
        const double sy = p == "l" ? 1 : -1;
        {
            AfConstraint& c = af.constraint(ConstraintType::Universal, p + "_shoulder", p + "_upperarm", "torso");
            c.anchor = jointV(p + "_upperarm");
            c.shafts = std::array<AfVector, 2>{boneDir(p + "_upperarm", p + "_forearm"),
                                               boneDir(p + "_upperarm", p + "_forearm", true)};
            c.friction = 0.4;
            c.limit = ConeLimit{lit(0.2, sy * 1, -1.5), 160, std::nullopt};
        }
        {
            // Elbow: axis d × X (unit), so positive angles bring the hand forward; range [-5, 140] degrees.
            AfConstraint& c = af.constraint(ConstraintType::Hinge, p + "_elbow", p + "_forearm", p + "_upperarm");
            c.anchor = jointV(p + "_forearm");
            c.axis = lit(0, -s45, -sy * s45);
            c.friction = 0.4;
            c.limit = HingeLimit{-67.5, 145, 0};
        }
        af.constraint(ConstraintType::Fixed, p + "_wrist", p + "_hand", p + "_forearm");
    }
    for (const char* side : {"l", "r"}) {
        const std::string p = side;
        const double sy = p == "l" ? 1 : -1;
        {
            AfConstraint& c = af.constraint(ConstraintType::Universal, p + "_hip", p + "_thigh", "pelvis");
            c.anchor = jointV(p + "_thigh");
            c.shafts = std::array<AfVector, 2>{boneDir(p + "_thigh", p + "_shin"),
                                               boneDir(p + "_thigh", p + "_shin", true)};
            c.friction = 0.5;
            c.limit = ConeLimit{lit(0.5, sy * 0.15, -1), 110, std::nullopt};
        }
        {
            // Knee: about +Y positive angles swing the shin backwards; range [-5, 140] degrees (off-centre).
            AfConstraint& c = af.constraint(ConstraintType::Hinge, p + "_knee", p + "_shin", p + "_thigh");
            c.anchor = jointV(p + "_shin");
            c.axis = lit(0, 1, 0);
            c.friction = 0.5;
            c.limit = HingeLimit{0, 145, 67.5};
        }
        {
            AfConstraint& c = af.constraint(ConstraintType::BallAndSocket, p + "_ankle", p + "_foot", p + "_shin");
            c.anchor = jointV(p + "_foot");
            c.friction = 0.5;
            c.limit = PyramidLimit{lit(1, 0, 0), 30, 70, 0, lit(1, 0, 0)};
        }
    }
    return writeAf(af.decl);
}

std::string humanoidWalk(const Skeleton& sk, const std::vector<Mesh>& meshes) {
    const int numFrames = 25; // 24 distinct frames plus the first again, so the cycle loops (1 s at 24 fps)
    std::vector<int> animated(sk.joints.size(), 0);
    const int TZ = 4, QALL = 8 | 16 | 32, QY = 16;
    animated[static_cast<std::size_t>(sk.index("pelvis"))] = TZ;
    for (const char* side : {"l", "r"}) {
        const std::string p = side;
        animated[static_cast<std::size_t>(sk.index(p + "_upperarm"))] = QALL;
        animated[static_cast<std::size_t>(sk.index(p + "_thigh"))] = QY;
        animated[static_cast<std::size_t>(sk.index(p + "_shin"))] = QY;
        animated[static_cast<std::size_t>(sk.index(p + "_foot"))] = QY;
    }
    auto aa = [](double deg, const Vector3d& axis) { return Quaterniond(Eigen::AngleAxisd(deg * kDeg, axis)); };
    std::vector<Pose> frames;
    for (int f = 0; f < numFrames; ++f) {
        const double phase = 2 * kPi * (f % 24) / 24.0;
        Pose pose = bindPose(sk);
        pose.t[static_cast<std::size_t>(sk.index("pelvis"))].z() = 38 - 0.8 + 0.8 * std::cos(2 * phase);
        for (const char* side : {"l", "r"}) {
            const std::string p = side;
            const double sy = p == "l" ? 1 : -1;
            const double ph = p == "l" ? phase : phase + kPi;
            // Negative angles about +Y swing a limb forward (-Z towards +X).
            const double thigh = -25 * std::sin(ph);
            const double knee = 5 + 45 * std::pow(std::max(0.0, std::cos(ph)), 2);
            pose.q[static_cast<std::size_t>(sk.index(p + "_thigh"))] = aa(thigh, Vector3d::UnitY());
            pose.q[static_cast<std::size_t>(sk.index(p + "_shin"))] = aa(knee, Vector3d::UnitY());
            pose.q[static_cast<std::size_t>(sk.index(p + "_foot"))] = aa(-0.6 * (thigh + knee), Vector3d::UnitY());
            // Arms: lowered from the 45-degree rest to about 80 degrees, swinging against the legs.
            const Quaterniond lower = aa(-sy * 35, Vector3d::UnitX());
            pose.q[static_cast<std::size_t>(sk.index(p + "_upperarm"))] = aa(20 * std::sin(ph), Vector3d::UnitY()) * lower;
            const double s45 = std::sin(45 * kDeg);
            pose.q[static_cast<std::size_t>(sk.index(p + "_forearm"))] = aa(20, Vector3d(0, -s45, -sy * s45));
        }
        frames.push_back(pose);
    }
    return writeAnim(sk, meshes, frames, animated, 24, "afb_gen_content: humanoid walk cycle");
}

// --- props -----------------------------------------------------------------------------------------------------

void props(Output& out) {
    Skeleton sk;
    sk.add("origin", "", {0, 0, 0});
    sk.add("prop_box", "origin", {0, 0, 6});
    sk.add("prop_octahedron", "origin", {0, 20, 6});
    sk.add("prop_dodecahedron", "origin", {0, 40, 6});
    sk.add("prop_cylinder", "origin", {0, 60, 6});
    sk.add("prop_cone", "origin", {0, 80, 12});
    sk.add("prop_bone", "origin", {-6, 100, 4});
    sk.add("prop_bone_tip", "prop_bone", {6, 100, 4});

    Mesh m;
    m.shader = "models/props/props";
    const Vector3d h(6, 6, 6);
    for (const char* j : {"prop_box", "prop_octahedron", "prop_dodecahedron", "prop_cylinder"})
        boxMesh(m, sk, sk.pos(j) - h, sk.pos(j) + h, sk.index(j));
    boxMesh(m, sk, sk.pos("prop_cone") - Vector3d(6, 6, 12), sk.pos("prop_cone") + Vector3d(6, 6, 0),
            sk.index("prop_cone"));
    boxMesh(m, sk, sk.pos("prop_bone") - Vector3d(0, 2, 2), sk.pos("prop_bone_tip") + Vector3d(0, 2, 2),
            sk.index("prop_bone"));
    const std::vector<Mesh> meshes{m};
    out.write("models/md5/props/props.md5mesh", writeMesh(sk, meshes, "afb_gen_content: one prop per shape type"));
    out.write("models/md5/props/props_af_pose.md5anim", writeAfPose(sk, meshes, "afb_gen_content: props af_pose"));

    AfBuilder af("props", sk);
    af.settings("model_props", 30);
    const Vector3d lo(-6, -6, -6), hi(6, 6, 6);
    af.body("box", "origin", shape(ShapeKind::Box, lo, hi), jointV("prop_box"), 5, "origin prop_box");
    af.body("octahedron", "prop_octahedron", shape(ShapeKind::Octahedron, lo, hi), jointV("prop_octahedron"), 5,
            "*prop_octahedron");
    af.body("dodecahedron", "prop_dodecahedron", shape(ShapeKind::Dodecahedron, lo, hi), jointV("prop_dodecahedron"),
            5, "*prop_dodecahedron");
    af.body("cylinder", "prop_cylinder", shape(ShapeKind::Cylinder, {-5, -5, -6}, {5, 5, 6}, 10),
            jointV("prop_cylinder"), 5, "*prop_cylinder");
    // A cone's apex is at its origin and it extends 12 units down to its base.
    af.body("cone", "prop_cone", shape(ShapeKind::Cone, {-6, -6, 0}, {6, 6, 12}, 12), jointV("prop_cone"), 5,
            "*prop_cone");
    af.body("bone", "prop_bone", boneShape("prop_bone", "prop_bone_tip", 4), boneCenter("prop_bone", "prop_bone_tip"),
            5, "*prop_bone");
    const std::vector<std::pair<std::string, std::string>> links{{"octahedron", "box"},
                                                                 {"dodecahedron", "octahedron"},
                                                                 {"cylinder", "dodecahedron"},
                                                                 {"cone", "cylinder"},
                                                                 {"bone", "cone"}};
    auto jointOf = [](const std::string& body) { return body == "box" ? std::string("prop_box") : "prop_" + body; };
    for (const auto& [b1, b2] : links) {
        const Vector3d p1 = b1 == "bone" ? Vector3d(0, 100, 4) : sk.pos(jointOf(b1));
        const Vector3d p2 = sk.pos(jointOf(b2));
        const double rest = (p2 - p1).norm();
        af.spring(b2 + "_" + b1, b1, b2, b1 == "bone" ? boneCenter("prop_bone", "prop_bone_tip") : jointV(jointOf(b1)),
                  jointV(jointOf(b2)), rest, 0.6 * rest, 1.5 * rest);
    }
    out.write("af/props.af", writeAf(af.decl));
}

// --- lamp ------------------------------------------------------------------------------------------------------

void lamp(Output& out) {
    Skeleton sk;
    sk.add("origin", "", {0, 0, 0});
    sk.add("link1", "origin", {0, 0, 100});
    sk.add("link2", "link1", {0, 0, 92});
    sk.add("link3", "link2", {0, 0, 84});
    sk.add("shade", "link3", {0, 0, 76});
    sk.add("bulb", "shade", {0, 0, 70});

    Mesh m;
    m.shader = "models/props/lamp";
    const int N = 10;
    tube(m, sk, sk.pos("link1"), sk.pos("link2"), linear(0.6, 0.6, 0.6, 0.6), sk.index("link1"), -1, 2, N, true, false);
    tube(m, sk, sk.pos("link2"), sk.pos("link3"), linear(0.6, 0.6, 0.6, 0.6), sk.index("link2"), sk.index("link1"), 3,
         N, false, false);
    tube(m, sk, sk.pos("link3"), sk.pos("shade"), linear(0.6, 0.6, 0.6, 0.6), sk.index("link3"), sk.index("link2"), 3,
         N, false, false);
    tube(m, sk, sk.pos("shade"), sk.pos("shade") - Vector3d(0, 0, 8), linear(2.5, 2.5, 8, 8), sk.index("shade"), -1, 4,
         N, true, false);
    tube(m, sk, sk.pos("bulb") + Vector3d(0, 0, 3), sk.pos("bulb") - Vector3d(0, 0, 1), linear(1.5, 1.5, 1.2, 1.2),
         sk.index("bulb"), -1, 3, N, true, true);
    const std::vector<Mesh> meshes{m};
    out.write("models/md5/props/lamp/lamp.md5mesh", writeMesh(sk, meshes, "afb_gen_content: a hanging lamp"));
    out.write("models/md5/props/lamp/af_pose.md5anim", writeAfPose(sk, meshes, "afb_gen_content: lamp af_pose"));

    AfBuilder af("lamp", sk);
    af.settings("model_lamp", 8);
    af.body("link1", "origin", boneShape("link1", "link2", 2.5), boneCenter("link1", "link2"), 1.5, "*origin -*link2");
    af.body("link2", "link2", boneShape("link2", "link3", 2.5), boneCenter("link2", "link3"), 1.5, "*link2 -*link3");
    af.body("link3", "link3", boneShape("link3", "shade", 2.5), boneCenter("link3", "shade"), 1.5, "*link3 -*shade");
    af.body("shade", "shade", shape(ShapeKind::Cylinder, {-8, -8, -8}, {8, 8, 0}, 10), jointV("shade"), 4, "*shade");
    {
        AfConstraint& c = af.constraint(ConstraintType::BallAndSocket, "hook", "link1", "world");
        c.anchor = jointV("link1");
        c.friction = 0.1;
    }
    {
        AfConstraint& c = af.constraint(ConstraintType::BallAndSocket, "link1_link2", "link2", "link1");
        c.anchor = jointV("link2");
        c.friction = 0.1;
        c.limit = ConeLimit{lit(0, 0, -1), 90, lit(0, 0, -1)};
    }
    {
        AfConstraint& c = af.constraint(ConstraintType::Universal, "link2_link3", "link3", "link2");
        c.anchor = jointV("link3");
        c.shafts = std::array<AfVector, 2>{lit(0, 0, -1), lit(0, 0, 1)};
        c.friction = 0.1;
        c.limit = ConeLimit{lit(0, 0, -1), 90, std::nullopt};
    }
    {
        AfConstraint& c = af.constraint(ConstraintType::Universal, "link3_shade", "shade", "link3");
        c.anchor = jointV("shade");
        c.shafts = std::array<AfVector, 2>{lit(0, 0, -1), lit(0, 0, 1)};
        c.friction = 0.2;
        c.limit = ConeLimit{lit(0, 0, -1), 60, std::nullopt};
    }
    out.write("af/lamp.af", writeAf(af.decl));
}

// --- buggy -----------------------------------------------------------------------------------------------------

void buggy(Output& out) {
    Skeleton sk;
    sk.add("origin", "", {0, 0, 0});
    sk.add("chassis", "origin", {0, 0, 18});
    struct Wheel {
        std::string id;
        double x, y;
    };
    const std::vector<Wheel> wheels{{"fl", 14, 16}, {"fr", 14, -16}, {"rl", -14, 16}, {"rr", -14, -16}};
    for (const Wheel& w : wheels) {
        sk.add("hub_" + w.id, "chassis", {w.x, w.y, 8});
        sk.add("wheel_" + w.id, "hub_" + w.id, {w.x, w.y, 8});
    }

    Mesh m;
    m.shader = "models/props/buggy";
    boxMesh(m, sk, {-20, -12, 14}, {20, 12, 22}, sk.index("chassis"));
    for (const Wheel& w : wheels) {
        const double sy = w.y > 0 ? 1 : -1;
        tube(m, sk, {w.x, w.y - sy * 2, 8}, {w.x, w.y + sy * 2, 8}, linear(8, 8, 8, 8), sk.index("wheel_" + w.id), -1,
             2, 10, true, true);
        boxMesh(m, sk, {w.x - 1, w.y - sy * 4 - 1, 7}, {w.x + 1, w.y - sy * 4 + 1, 19}, sk.index("hub_" + w.id));
    }
    const std::vector<Mesh> meshes{m};
    out.write("models/md5/props/buggy/buggy.md5mesh", writeMesh(sk, meshes, "afb_gen_content: a sprung buggy"));
    out.write("models/md5/props/buggy/af_pose.md5anim", writeAfPose(sk, meshes, "afb_gen_content: buggy af_pose"));

    AfBuilder af("buggy", sk);
    af.settings("model_buggy", 80);
    af.body("chassis", "origin", shape(ShapeKind::Box, {-20, -12, -4}, {20, 12, 4}), jointV("chassis"), 40,
            "origin chassis");
    for (const Wheel& w : wheels) {
        AfBody& hub = af.body("hub_" + w.id, "hub_" + w.id, shape(ShapeKind::Box, {-1.5, -1.5, -1.5}, {1.5, 1.5, 1.5}),
                              jointV("hub_" + w.id), 5, "hub_" + w.id);
        hub.mod = "both"; // the hub slides: its joint takes its position from the body, not from the chassis
        AfBody& wheel = af.body("wheel_" + w.id, "wheel_" + w.id,
                                shape(ShapeKind::Cylinder, {-8, -8, -2}, {8, 8, 2}, 10), jointV("wheel_" + w.id), 6,
                                "*wheel_" + w.id);
        wheel.angles = lit(0, 0, 90); // the cylinder's axis (local Z) turned onto the axle (-Y)
        wheel.friction = BodyFriction{0.01, 0.01, 1};
    }
    for (const Wheel& w : wheels) {
        AfConstraint& slider = af.constraint(ConstraintType::Slider, "suspension_" + w.id, "hub_" + w.id, "chassis");
        slider.axis = lit(0, 0, 1);
        af.spring("spring_" + w.id, "hub_" + w.id, "chassis", jointV("hub_" + w.id), lit(w.x, w.y, 20), 12, 6, 16);
        AfConstraint& axle = af.constraint(ConstraintType::Hinge, "axle_" + w.id, "wheel_" + w.id, "hub_" + w.id);
        axle.anchor = jointV("wheel_" + w.id);
        axle.axis = lit(0, 1, 0);
        axle.friction = 0.05;
    }
    out.write("af/buggy.af", writeAf(af.decl));
}

// --- defs ------------------------------------------------------------------------------------------------------

const char* kHumanoidDef = R"(// Generated by afb_gen_content (src/tools/GenerateContent.cpp); MIT licensed. Do not edit by hand: re-run
// `afb_gen_content .` from the repository root.

model model_humanoid {
	mesh							models/md5/humanoid/humanoid.md5mesh
	anim af_pose					models/md5/humanoid/af_pose.md5anim
	anim walk						models/md5/humanoid/walk.md5anim
}

// An actor whose ragdoll is af/humanoid.af.
entityDef humanoid {
	"spawnclass"					"idActor"
	"model"							"model_humanoid"
	"ragdoll"						"humanoid"
}

// The same figure spawned at rest until touched ("sleep" is the seed document's key, "nodrop" the engine's).
entityDef humanoid_sleeping {
	"inherit"						"humanoid"
	"sleep"							"1"
	"nodrop"						"1"
}

// The figure as a posable ragdoll prop.
entityDef humanoid_prop {
	"spawnclass"					"idAFEntity_Generic"
	"model"							"model_humanoid"
	"articulatedFigure"				"humanoid"
}
)";

const char* kPropsDef = R"(// Generated by afb_gen_content (src/tools/GenerateContent.cpp); MIT licensed. Do not edit by hand: re-run
// `afb_gen_content .` from the repository root.

model model_props {
	mesh							models/md5/props/props.md5mesh
	anim af_pose					models/md5/props/props_af_pose.md5anim
}

// One body per shape type, held together by springs.
entityDef props {
	"spawnclass"					"idAFEntity_Generic"
	"model"							"model_props"
	"articulatedFigure"				"props"
}

model model_lamp {
	mesh							models/md5/props/lamp/lamp.md5mesh
	anim af_pose					models/md5/props/lamp/af_pose.md5anim
}

// A shade hanging on three links from a hook in the world.
entityDef lamp {
	"spawnclass"					"idAFEntity_Generic"
	"model"							"model_lamp"
	"articulatedFigure"				"lamp"
}

model model_buggy {
	mesh							models/md5/props/buggy/buggy.md5mesh
	anim af_pose					models/md5/props/buggy/af_pose.md5anim
}

// A chassis with four wheels, each on a hub that slides vertically against a spring.
entityDef buggy {
	"spawnclass"					"idAFEntity_Generic"
	"model"							"model_buggy"
	"articulatedFigure"				"buggy"
}
)";

} // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::cerr << "usage: afb_gen_content OUTDIR   (run `afb_gen_content .` from the repository root)\n";
        return 2;
    }
    try {
        Output out{fs::path(argv[1]), {}};
        const Skeleton sk = humanoidSkeleton();
        const std::vector<Mesh> meshes = humanoidMeshes(sk);
        out.write("models/md5/humanoid/humanoid.md5mesh",
                  writeMesh(sk, meshes, "afb_gen_content: humanoid (procedural tubes), MIT licensed"));
        out.write("models/md5/humanoid/af_pose.md5anim",
                  writeAfPose(sk, meshes, "afb_gen_content: humanoid af_pose (arms 45 degrees down, legs apart)"));
        out.write("models/md5/humanoid/walk.md5anim", humanoidWalk(sk, meshes));
        out.write("af/humanoid.af", humanoidAf(sk));
        props(out);
        lamp(out);
        buggy(out);
        out.write("def/humanoid.def", kHumanoidDef);
        out.write("def/props.def", kPropsDef);
        for (const std::string& f : out.written) std::cout << f << "\n";
    } catch (const std::exception& e) {
        std::cerr << "afb_gen_content: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
