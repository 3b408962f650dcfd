// The exact joint solve in joint space (ArticulatedTree.h).
//
// A joint from parent p to child c has three anchor rows, at the child (nᵢ, r_c × nᵢ) and at the parent
// (−nᵢ, −r_p × nᵢ), r the lever arms from the centres of mass to each body's anchor, and locked rows (0, u) and
// (0, −u). The velocities that keep every row at zero are V_c = T V_p + S q̇: T carries the parent's motion to the
// child's centre of mass through both anchors (shift d = r_p − r_c), and S's columns turn the child about its anchor
// along the free axes. With J_p = −J_c T and J_c S = 0, a joint's rows asking e are met by V_c = T V_p + c + S q̇
// for any c with J_c c = e (particular()). Leaves first, each body's articulated inertia I and bias impulse p
// (I V = p + the impulse of its own joint) pass to the parent as Tᵀ Ĩ T and Tᵀ (p̃ − Ĩ c), Ĩ = I − I S D⁻¹ Sᵀ I,
// p̃ = p − I S D⁻¹ Sᵀ p, D = Sᵀ I S; root first, q̇ = D⁻¹ Sᵀ (p − I (T V_p + c)), and the joint's impulse at the
// child is J_cᵀ λ = Ĩ (T V_p + c) − p̃ (Featherstone, "Rigid Body Dynamics Algorithms", 2008, ch. 7, in impulses).
#include "ArticulatedTree.h"

#include <algorithm>
#include <cmath>

namespace afb::bullet {
namespace {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Vec6 = ArticulatedTree::Vec6;
using Mat6 = ArticulatedTree::Mat6;

Mat3 skew(const Vec3& v) {
    Mat3 m;
    m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
    return m;
}

// The lever arm r with ang = r × lin over a point joint's three rows (least squares), and whether every row fits
// it to rounding.
bool leverArm(const Vec3 (&lin)[3], const Vec3 (&ang)[3], Vec3& r) {
    Mat3 a = Mat3::Zero();
    Vec3 b = Vec3::Zero();
    for (int i = 0; i < 3; ++i) {
        a += lin[i].squaredNorm() * Mat3::Identity() - lin[i] * lin[i].transpose();
        b += lin[i].cross(ang[i]);
    }
    const double det = a.determinant();
    if (!(std::abs(det) > 1e-12 * std::pow(a.trace() / 3, 3))) return false;
    r = a.inverse() * b;
    for (int i = 0; i < 3; ++i) {
        const double scale = ang[i].norm() + r.norm() * lin[i].norm() + 1e-12;
        if ((ang[i] - r.cross(lin[i])).norm() > 1e-5 * scale) return false;
    }
    return true;
}

// V ↦ T V: the parent's motion carried by the shift d (v + ω × d, ω).
Vec6 shift(const Vec3& d, const Vec6& v) {
    Vec6 out;
    out.head<3>() = v.head<3>() + v.tail<3>().cross(d);
    out.tail<3>() = v.tail<3>();
    return out;
}

// F ↦ Tᵀ F: an impulse at the child carried to the parent's centre of mass (f, τ + d × f).
Vec6 shiftBack(const Vec3& d, const Vec6& f) {
    Vec6 out;
    out.head<3>() = f.head<3>();
    out.tail<3>() = f.tail<3>() + d.cross(f.head<3>());
    return out;
}

// Tᵀ P T for a symmetric P = [[A, B], [Bᵀ, C]] and T = [[1, E], [0, 1]], E = −[d]×.
Mat6 shiftInertia(const Vec3& d, const Mat6& p) {
    const Mat3 e = -skew(d);
    const Mat3 a = p.topLeftCorner<3, 3>(), b = p.topRightCorner<3, 3>(), c = p.bottomRightCorner<3, 3>();
    const Mat3 b2 = a * e + b;
    Mat6 out;
    out.topLeftCorner<3, 3>() = a;
    out.topRightCorner<3, 3>() = b2;
    out.bottomLeftCorner<3, 3>() = b2.transpose();
    const Mat3 c2 = e.transpose() * b2 + b.transpose() * e + c;
    out.bottomRightCorner<3, 3>() = 0.5 * (c2 + c2.transpose());
    return out;
}

} // namespace

bool ArticulatedTree::build(std::span<const Body> bodies, std::span<const Row> rows) {
    m_joints.clear();
    m_mass.clear();
    m_inertia.clear();
    for (const Body& b : bodies) {
        if (!(b.mass > 0) || !b.inertia.allFinite()) return false;
        m_mass.push_back(b.mass);
        m_inertia.push_back(b.inertia);
    }
    for (const Row& r : rows)
        if (r.a < -1 || r.b < -1 || r.a >= static_cast<int>(bodies.size()) || r.b >= static_cast<int>(bodies.size()) ||
            r.a == r.b || !r.ja.allFinite() || !r.jb.allFinite())
            return false;
    return orient(rows);
}

// The joints from the rows: one per body pair, oriented away from the root (the body held to the world, else the
// heaviest body), in breadth-first order.
bool ArticulatedTree::orient(std::span<const Row> rows) {
    const int n = bodies();
    struct Pair {
        int lo, hi;
        std::vector<int> rows;
    };
    std::vector<Pair> pairs;
    for (int k = 0; k < static_cast<int>(rows.size()); ++k) {
        const int lo = std::min(rows[k].a, rows[k].b), hi = std::max(rows[k].a, rows[k].b);
        auto it = std::find_if(pairs.begin(), pairs.end(), [&](const Pair& p) { return p.lo == lo && p.hi == hi; });
        if (it == pairs.end()) pairs.push_back({lo, hi, {k}});
        else it->rows.push_back(k);
    }
    int world = -1;
    std::vector<std::vector<std::pair<int, int>>> adjacent(static_cast<std::size_t>(n)); // (other body, pair)
    for (int q = 0; q < static_cast<int>(pairs.size()); ++q) {
        const Pair& p = pairs[static_cast<std::size_t>(q)];
        if (p.lo < 0) {
            if (world >= 0) return false;
            world = q;
            continue;
        }
        adjacent[static_cast<std::size_t>(p.lo)].emplace_back(p.hi, q);
        adjacent[static_cast<std::size_t>(p.hi)].emplace_back(p.lo, q);
    }
    if (n == 0 || static_cast<int>(pairs.size()) != n - 1 + (world >= 0 ? 1 : 0)) return false;
    m_root = world >= 0 ? -1 : static_cast<int>(std::max_element(m_mass.begin(), m_mass.end()) - m_mass.begin());
    const int start = world >= 0 ? pairs[static_cast<std::size_t>(world)].hi : m_root;
    m_jointOf.assign(static_cast<std::size_t>(n), -1);
    std::vector<int> parentPair(static_cast<std::size_t>(n), -2);
    parentPair[static_cast<std::size_t>(start)] = world;
    std::vector<int> queue{start};
    auto addJoint = [this](int parent, int child) {
        Joint& j = m_joints.emplace_back();
        j.parent = parent;
        j.child = child;
    };
    if (world >= 0) addJoint(-1, start);
    for (std::size_t at = 0; at < queue.size(); ++at) {
        const int u = queue[at];
        for (const auto& [v, q] : adjacent[static_cast<std::size_t>(u)]) {
            if (q == parentPair[static_cast<std::size_t>(u)]) continue;
            if (parentPair[static_cast<std::size_t>(v)] != -2) return false; // a loop
            parentPair[static_cast<std::size_t>(v)] = q;
            queue.push_back(v);
            addJoint(u, v);
        }
    }
    if (static_cast<int>(queue.size()) != n) return false;
    for (std::size_t k = 0; k < m_joints.size(); ++k) {
        Joint& j = m_joints[k];
        m_jointOf[static_cast<std::size_t>(j.child)] = static_cast<int>(k);
        const int q = parentPair[static_cast<std::size_t>(j.child)];
        if (!shapeJoint(j, rows, pairs[static_cast<std::size_t>(q)].rows)) return false;
    }
    m_ia.resize(static_cast<std::size_t>(n));
    m_p.resize(static_cast<std::size_t>(n));
    m_pt.resize(static_cast<std::size_t>(n));
    m_c.resize(static_cast<std::size_t>(n));
    m_y.resize(static_cast<std::size_t>(n));
    return true;
}

// A joint's geometry from its rows: the anchor rows' directions and both lever arms, the locked axes, the free
// motions of the child.
bool ArticulatedTree::shapeJoint(Joint& j, std::span<const Row> rows, const std::vector<int>& pairRows) {
    Vec3 lin[3], ang[3], linP[3], angP[3];
    int anchors = 0;
    j.locked = 0;
    for (const int k : pairRows) {
        const Row& r = rows[static_cast<std::size_t>(k)];
        const Vec6& jc = r.a == j.child ? r.ja : r.jb;
        const Vec6& jp = r.a == j.child ? r.jb : r.ja;
        const Vec3 lc = jc.head<3>(), ac = jc.tail<3>(), lp = jp.head<3>(), ap = jp.tail<3>();
        const bool parent = j.parent >= 0;
        if (lc.squaredNorm() > 0) {
            if (anchors == 3 || (parent && (lp + lc).norm() > 1e-6 * lc.norm())) return false;
            lin[anchors] = lc;
            ang[anchors] = ac;
            linP[anchors] = lp;
            angP[anchors] = ap;
            j.rows[anchors++] = k;
            continue;
        }
        if (j.locked == 2 || !(ac.squaredNorm() > 0) || (parent && (lp.squaredNorm() > 0 ||
                                                                   (ap + ac).norm() > 1e-6 * ac.norm())))
            return false;
        j.u.col(j.locked) = ac;
        j.rows[3 + j.locked++] = k;
    }
    if (anchors != 3 || !leverArm(lin, ang, j.rc)) return false;
    Vec3 rp = Vec3::Zero();
    if (j.parent >= 0 && !leverArm(linP, angP, rp)) return false;
    j.d = rp - j.rc;
    Mat3 nCols;
    for (int i = 0; i < 3; ++i) nCols.col(i) = lin[i];
    const double det = nCols.determinant();
    if (!(std::abs(det) > 1e-9 * lin[0].norm() * lin[1].norm() * lin[2].norm())) return false;
    j.nInv = nCols.inverse();
    // The free rotations: every axis, those at right angles to the one locked axis, or the one at right angles to
    // both.
    Mat3 axes = Mat3::Identity();
    j.uGram = Eigen::Matrix2d::Identity();
    if (j.locked == 1) {
        const Vec3 u = j.u.col(0).normalized();
        const Vec3 a = (std::abs(u.x()) < 0.6 ? Vec3::UnitX() : Vec3::UnitY()).cross(u).normalized();
        axes.col(0) = a;
        axes.col(1) = u.cross(a);
        j.uGram(0, 0) = 1.0 / j.u.col(0).squaredNorm();
    } else if (j.locked == 2) {
        const Vec3 w = j.u.col(0).cross(j.u.col(1));
        if (!(w.squaredNorm() > 1e-12 * j.u.col(0).squaredNorm() * j.u.col(1).squaredNorm())) return false;
        axes.col(0) = w.normalized();
        j.uGram = (j.u.transpose() * j.u).inverse();
    }
    j.free = 3 - j.locked;
    j.s.setZero();
    for (int i = 0; i < j.free; ++i) {
        j.s.block<3, 1>(0, i) = j.rc.cross(axes.col(i));
        j.s.block<3, 1>(3, i) = axes.col(i);
    }
    return true;
}

bool ArticulatedTree::factor() {
    for (std::size_t i = 0; i < m_mass.size(); ++i) {
        m_ia[i].setZero();
        m_ia[i].topLeftCorner<3, 3>() = m_mass[i] * Mat3::Identity();
        m_ia[i].bottomRightCorner<3, 3>() = m_inertia[i];
    }
    for (auto it = m_joints.rbegin(); it != m_joints.rend(); ++it) {
        Joint& j = *it;
        const Mat6& ia = m_ia[static_cast<std::size_t>(j.child)];
        j.is = ia * j.s;
        // D = Sᵀ I S on the free motions; the unused ones get 1 on the diagonal (and contribute nothing, their
        // columns of S being zero).
        Mat3 d = j.s.transpose() * j.is;
        for (int i = j.free; i < 3; ++i) d(i, i) = 1;
        const Eigen::LLT<Mat3> llt(d);
        if (llt.info() != Eigen::Success) return false;
        j.dInv = llt.solve(Mat3::Identity());
        j.k = j.dInv * j.is.transpose();
        j.passed = ia - j.is * j.k;
        if (j.parent >= 0) m_ia[static_cast<std::size_t>(j.parent)] += shiftInertia(j.d, j.passed);
    }
    if (m_root < 0) return true;
    m_rootFactor.compute(m_ia[static_cast<std::size_t>(m_root)]);
    return m_rootFactor.info() == Eigen::Success;
}

// A child's motion c that meets the joint's rows asking e on their own (J_c c = e): the locked rows by a turn
// along the locked axes, the anchor rows by a velocity of the anchor.
Vec6 ArticulatedTree::particular(const Joint& j, std::span<const double> e) const {
    Vec3 turn = Vec3::Zero();
    if (j.locked == 1) turn = j.u.col(0) * (j.uGram(0, 0) * e[static_cast<std::size_t>(j.rows[3])]);
    if (j.locked == 2)
        turn = j.u * (j.uGram * Eigen::Vector2d(e[static_cast<std::size_t>(j.rows[3])],
                                                e[static_cast<std::size_t>(j.rows[4])]));
    const Vec3 ea(e[static_cast<std::size_t>(j.rows[0])], e[static_cast<std::size_t>(j.rows[1])],
                  e[static_cast<std::size_t>(j.rows[2])]);
    const Vec3 anchor = j.nInv.transpose() * ea;
    Vec6 c;
    c.head<3>() = anchor - turn.cross(j.rc);
    c.tail<3>() = turn;
    return c;
}

// The rows' impulses from the joint's impulse at the child, g = J_cᵀ λ.
void ArticulatedTree::impulses(const Joint& j, const Vec6& g, std::span<double> lambda) const {
    const Vec3 force = g.head<3>();
    const Vec3 a = j.nInv * force;
    for (int i = 0; i < 3; ++i) lambda[static_cast<std::size_t>(j.rows[i])] = a[i];
    if (j.locked == 0) return;
    const Vec3 torque = g.tail<3>() - j.rc.cross(force);
    if (j.locked == 1) {
        lambda[static_cast<std::size_t>(j.rows[3])] = j.uGram(0, 0) * j.u.col(0).dot(torque);
        return;
    }
    const Eigen::Vector2d m = j.uGram * (j.u.transpose() * torque);
    lambda[static_cast<std::size_t>(j.rows[3])] = m[0];
    lambda[static_cast<std::size_t>(j.rows[4])] = m[1];
}

void ArticulatedTree::solve(std::span<const double> f, std::span<const double> e, std::span<double> dv,
                            std::span<double> lambda) const {
    const std::size_t n = m_mass.size();
    for (std::size_t i = 0; i < n; ++i) m_p[i] = Eigen::Map<const Vec6>(f.data() + 6 * i);
    for (auto it = m_joints.rbegin(); it != m_joints.rend(); ++it) {
        const Joint& j = *it;
        const auto c = static_cast<std::size_t>(j.child);
        m_c[c] = particular(j, e);
        m_y[c] = j.dInv * (j.s.transpose() * m_p[c]);
        m_pt[c] = m_p[c] - j.is * m_y[c];
        if (j.parent >= 0)
            m_p[static_cast<std::size_t>(j.parent)] += shiftBack(j.d, m_pt[c] - j.passed * m_c[c]);
    }
    if (m_root >= 0)
        Eigen::Map<Vec6>(dv.data() + 6 * static_cast<std::size_t>(m_root)) =
            m_rootFactor.solve(m_p[static_cast<std::size_t>(m_root)]);
    for (const Joint& j : m_joints) {
        const auto c = static_cast<std::size_t>(j.child);
        Vec6 w = m_c[c];
        if (j.parent >= 0) w += shift(j.d, Eigen::Map<const Vec6>(dv.data() + 6 * static_cast<std::size_t>(j.parent)));
        const Vec3 qd = m_y[c] - j.k * w;
        Eigen::Map<Vec6>(dv.data() + 6 * c) = w + j.s * qd;
        impulses(j, j.passed * w - m_pt[c], lambda);
    }
}

void ArticulatedTree::solveImpulse(int a, const Vec6& f, std::span<double> dv) const {
    Vec6 p = f; // the bias impulse on the path, at its current body
    int body = a;
    while (m_jointOf[static_cast<std::size_t>(body)] >= 0) {
        const Joint& j = m_joints[static_cast<std::size_t>(m_jointOf[static_cast<std::size_t>(body)])];
        const auto c = static_cast<std::size_t>(j.child);
        m_y[c] = j.dInv * (j.s.transpose() * p);
        m_pt[c] = p; // marks the body as on the path (m_y used below)
        if (j.parent < 0) break;
        p = shiftBack(j.d, p - j.is * m_y[c]);
        body = j.parent;
    }
    if (m_root >= 0) Eigen::Map<Vec6>(dv.data() + 6 * static_cast<std::size_t>(m_root)) = m_rootFactor.solve(p);
    // Down: a joint off the path passes the parent's motion on, less what its subtree's inertia holds back.
    std::vector<char> onPath(m_mass.size(), 0);
    for (int b = a; b >= 0;) {
        onPath[static_cast<std::size_t>(b)] = 1;
        const int jj = m_jointOf[static_cast<std::size_t>(b)];
        b = jj < 0 ? -1 : m_joints[static_cast<std::size_t>(jj)].parent;
    }
    for (const Joint& j : m_joints) {
        const auto c = static_cast<std::size_t>(j.child);
        Vec6 w = Vec6::Zero();
        if (j.parent >= 0) w = shift(j.d, Eigen::Map<const Vec6>(dv.data() + 6 * static_cast<std::size_t>(j.parent)));
        const Vec3 qd = (onPath[c] ? m_y[c] : Vec3::Zero()) - j.k * w;
        Eigen::Map<Vec6>(dv.data() + 6 * c) = w + j.s * qd;
    }
}

} // namespace afb::bullet
