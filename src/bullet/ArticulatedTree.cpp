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
//
// A soft row (0, u) / (0, −u) with compliance γ asks u·(ω_c − ω_p) + γλ = e: its impulse λ = (e − u·(c + S q̇))/γ
// is an implicit spring and damper on the free motions. Eliminated with them, it adds Sᵀ u uᵀ S / γ to D and
// Sᵀ u (e − u·c)/γ to the free part of the bias (D⁻¹ of it added to y); every other formula keeps its form. In the
// iterations the bodies' momentum already holds the impulse λ the row took so far, so a projection asks e − γλ of
// it and adds what it finds: λ′ = (e − u·(ω_c − ω_p))/γ after the projection.
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

// The lever arm r with ang = r × lin over a point joint's three rows (least squares; with orthonormal directions
// r = ½ Σ lin × ang), and whether every row fits it to rounding.
bool leverArm(const Vec3 (&lin)[3], const Vec3 (&ang)[3], bool orthonormal, Vec3& r) {
    Vec3 b = Vec3::Zero();
    for (int i = 0; i < 3; ++i) b += lin[i].cross(ang[i]);
    if (orthonormal) {
        r = 0.5 * b;
    } else {
        Mat3 a = Mat3::Zero();
        for (int i = 0; i < 3; ++i) a += lin[i].squaredNorm() * Mat3::Identity() - lin[i] * lin[i].transpose();
        const double det = a.determinant();
        if (!(std::abs(det) > 1e-12 * std::pow(a.trace() / 3, 3))) return false;
        r = a.inverse() * b;
    }
    for (int i = 0; i < 3; ++i) {
        const double scale = ang[i].squaredNorm() + r.squaredNorm() * lin[i].squaredNorm() + 1e-24;
        if ((ang[i] - r.cross(lin[i])).squaredNorm() > 1e-10 * scale) return false;
    }
    return true;
}

// F ↦ Tᵀ F: an impulse at the child carried to the parent's centre of mass (f, τ + d × f).
[[gnu::always_inline]] inline Vec6 shiftBack(const Vec3& d, const Vec6& f) {
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
    m_hasTargets = false;
    m_target.clear();
    m_softRows = 0;
    m_mass.clear();
    m_inertia.clear();
    for (const Body& b : bodies) {
        if (!(b.mass > 0) || !b.inertia.allFinite()) return false;
        m_mass.push_back(b.mass);
        m_inertia.push_back(b.inertia);
    }
    const int n = static_cast<int>(bodies.size());
    bool same = m_valid && m_key.size() == 1 + 2 * rows.size() && m_key[0] == n;
    for (std::size_t k = 0; k < rows.size(); ++k) {
        const Row& r = rows[k];
        // 0·x is NaN exactly when x is not finite: one test for all thirteen numbers.
        if (r.a < -1 || r.b < -1 || r.a >= n || r.b >= n || r.a == r.b || !(r.cfm >= 0) ||
            !std::isfinite(0 * (r.ja.sum() + r.jb.sum() + r.cfm)))
            return m_valid = false;
        if (r.cfm > 0) ++m_softRows;
        same = same && m_key[1 + 2 * k] == r.a && m_key[2 + 2 * k] == r.b;
    }
    if (!same) {
        m_key.assign(1, n);
        for (const Row& r : rows) m_key.insert(m_key.end(), {r.a, r.b});
        m_joints.clear();
        m_valid = orient(rows);
        if (!m_valid) return false;
    }
    // The same layout as last time: the same joints, reshaped from this step's rows.
    for (Joint& j : m_joints)
        if (!shapeJoint(j, rows)) return m_valid = false;
    return true;
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
        const std::vector<int>& mine =
            pairs[static_cast<std::size_t>(parentPair[static_cast<std::size_t>(j.child)])].rows;
        if (mine.size() > 8) return false;
        j.pairCount = static_cast<int>(mine.size());
        std::copy(mine.begin(), mine.end(), j.pairRows);
    }
    m_ia.resize(static_cast<std::size_t>(n));
    m_p.resize(static_cast<std::size_t>(n));
    m_pt.resize(static_cast<std::size_t>(n));
    m_y.resize(static_cast<std::size_t>(n));
    m_softY.resize(static_cast<std::size_t>(n));
    return true;
}

// A joint's geometry from its rows: the anchor rows' directions and both lever arms, the locked axes, the soft rows'
// axes, the free motions of the child.
bool ArticulatedTree::shapeJoint(Joint& j, std::span<const Row> rows) {
    Vec3 lin[3], ang[3], linP[3], angP[3];
    int anchors = 0;
    j.locked = 0;
    j.softCount = 0;
    for (int q = 0; q < j.pairCount; ++q) {
        const int k = j.pairRows[q];
        const Row& r = rows[static_cast<std::size_t>(k)];
        const Vec6& jc = r.a == j.child ? r.ja : r.jb;
        const Vec6& jp = r.a == j.child ? r.jb : r.ja;
        const Vec3 lc = jc.head<3>(), ac = jc.tail<3>(), lp = jp.head<3>(), ap = jp.tail<3>();
        const bool parent = j.parent >= 0;
        if (lc.squaredNorm() > 0) {
            if (anchors == 3 || r.cfm > 0 || (parent && (lp + lc).norm() > 1e-6 * lc.norm())) return false;
            lin[anchors] = lc;
            ang[anchors] = ac;
            linP[anchors] = lp;
            angP[anchors] = ap;
            j.rows[anchors++] = k;
            continue;
        }
        if (!(ac.squaredNorm() > 0) || (parent && (lp.squaredNorm() > 0 || (ap + ac).norm() > 1e-6 * ac.norm())))
            return false;
        if (r.cfm > 0) {
            if (j.softCount == 3) return false;
            j.softAxis.col(j.softCount) = ac;
            j.softCfm[j.softCount] = r.cfm;
            j.soft[j.softCount++] = k;
            continue;
        }
        if (j.locked == 2) return false;
        j.u.col(j.locked) = ac;
        j.rows[3 + j.locked++] = k;
    }
    if (anchors != 3) return false;
    Mat3 nCols;
    for (int i = 0; i < 3; ++i) nCols.col(i) = lin[i];
    const bool orthonormal = (nCols.transpose() * nCols - Mat3::Identity()).cwiseAbs().maxCoeff() < 1e-6;
    if (!leverArm(lin, ang, orthonormal, j.rc)) return false;
    Vec3 rp = Vec3::Zero();
    if (j.parent >= 0 && !leverArm(linP, angP, orthonormal, rp)) return false;
    j.d = rp - j.rc;
    if (orthonormal) {
        j.nInv = nCols.transpose();
    } else {
        const double det = nCols.determinant();
        if (!(std::abs(det) > 1e-9 * lin[0].norm() * lin[1].norm() * lin[2].norm())) return false;
        j.nInv = nCols.inverse();
    }
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

// One joint's elimination, over its F free motions: I·S, D⁻¹, K = D⁻¹ (I S)ᵀ and the inertia it passes on.
template <int F>
bool ArticulatedTree::factorJoint(Joint& j) {
    using MatS = Eigen::Matrix<double, 6, F>;
    const Eigen::Map<const MatS> s(j.s.data());
    const Mat6& ia = m_ia[static_cast<std::size_t>(j.child)];
    const MatS is = ia * s;
    Eigen::Matrix<double, F, F> d = s.transpose() * is;
    for (int k = 0; k < j.softCount; ++k) { // a soft row's spring on the free motions: Sᵀ u uᵀ S / γ
        const Eigen::Matrix<double, F, 1> w = s.template bottomRows<3>().transpose() * j.softAxis.col(k);
        d.noalias() += w * w.transpose() / j.softCfm[k];
    }
    Eigen::Matrix<double, F, F> dInv;
    bool invertible = d(0, 0) > 0;
    if constexpr (F == 1) dInv(0, 0) = 1.0 / d(0, 0);
    else d.computeInverseWithCheck(dInv, invertible);
    if (!invertible || !(dInv.diagonal().minCoeff() > 0)) return false;
    const Eigen::Matrix<double, F, 6> k = dInv * is.transpose();
    j.passed = ia;
    j.passed.noalias() -= is * k;
    // The solves' kernels, row-major: y = (D⁻¹ Sᵀ) p, p̃ = p − (I S) y, q̇ = y − K w, Δv = w + S q̇.
    const Eigen::Matrix<double, F, 6> kp = dInv * s.transpose();
    for (int i = 0; i < F; ++i)
        for (int q = 0; q < 6; ++q) {
            j.kernels.kp[q][i] = kp(i, q);
            j.kernels.k[q][i] = k(i, q);
            j.kernels.is[i][q] = is(q, i);
            j.kernels.s[i][q] = s(q, i);
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
        const bool ok = j.free == 1 ? factorJoint<1>(j) : j.free == 2 ? factorJoint<2>(j) : factorJoint<3>(j);
        if (!ok) return false;
        if (j.parent >= 0) m_ia[static_cast<std::size_t>(j.parent)] += shiftInertia(j.d, j.passed);
    }
    if (m_root < 0) return true;
    // The root's inverse, kept whole: every solve then multiplies by it (a 6×6 product, no division).
    const Eigen::LLT<Mat6> llt(m_ia[static_cast<std::size_t>(m_root)]);
    if (llt.info() != Eigen::Success) return false;
    m_rootInverse = llt.solve(Mat6::Identity());
    return m_rootInverse.allFinite();
}

// Leaves to root: the joint's free part of its child's bias impulse (y = D⁻¹ Sᵀ p), the rest passed to the parent.
template <int F, bool Soft>
[[gnu::always_inline]] inline void ArticulatedTree::upJoint(const Joint& j, const Vec6* passedOffset,
                                                            const Eigen::Vector3d* yOffset) const {
    const auto c = static_cast<std::size_t>(j.child);
    const Joint::Kernels& kn = j.kernels;
    const double* p = m_p[c].data();
    double* y = m_y[c].data();
    double* pt = m_pt[c].data();
    // Each sum in the order of its terms (y_i = Σ_q (D⁻¹Sᵀ)[i][q] p_q, q ascending), a column at a time: the
    // compiler takes neighbouring entries together.
    double yi[F] = {};
    for (int q = 0; q < 6; ++q)
        for (int i = 0; i < F; ++i) yi[i] += kn.kp[q][i] * p[q];
    if constexpr (Soft)
        if (j.softCount > 0)
            for (int i = 0; i < F; ++i) yi[i] += yOffset[c][i];
    for (int i = 0; i < F; ++i) y[i] = yi[i];
    double acc[6];
    for (int q = 0; q < 6; ++q) acc[q] = p[q];
    for (int i = 0; i < F; ++i)
        for (int q = 0; q < 6; ++q) acc[q] -= kn.is[i][q] * y[i];
    for (int q = 0; q < 6; ++q) pt[q] = acc[q];
    if (j.parent < 0) return;
    Vec6 passed = m_pt[c];
    if (passedOffset) passed -= passedOffset[c];
    // Tᵀ: the force as it is, its moment about the parent's centre added to the torque.
    double* pp = m_p[static_cast<std::size_t>(j.parent)].data();
    const double* d = j.d.data();
    pp[0] += passed[0];
    pp[1] += passed[1];
    pp[2] += passed[2];
    pp[3] += passed[3] + d[1] * passed[2] - d[2] * passed[1];
    pp[4] += passed[4] + d[2] * passed[0] - d[0] * passed[2];
    pp[5] += passed[5] + d[0] * passed[1] - d[1] * passed[0];
}

// Root to leaves: the child's motion from the parent's carried one w (q̇ = y − K w), written to `out`.
template <int F>
[[gnu::always_inline]] inline void ArticulatedTree::downJoint(const Joint& j, const double* w, double* out) const {
    const Joint::Kernels& kn = j.kernels;
    const double* y = m_y[static_cast<std::size_t>(j.child)].data();
    double qd[F];
    for (int i = 0; i < F; ++i) qd[i] = y[i];
    for (int q = 0; q < 6; ++q)
        for (int i = 0; i < F; ++i) qd[i] -= kn.k[q][i] * w[q];
    double acc[6];
    for (int q = 0; q < 6; ++q) acc[q] = w[q];
    for (int i = 0; i < F; ++i)
        for (int q = 0; q < 6; ++q) acc[q] += kn.s[i][q] * qd[i];
    for (int q = 0; q < 6; ++q) out[q] = acc[q];
}

// A child's motion c that meets the joint's rows asking e on their own (J_c c = e): the locked rows by a turn
// along the locked axes, the anchor rows by a velocity of the anchor.
Vec6 ArticulatedTree::particular(const Joint& j, std::span<const double> e) const {
    Vec3 turn = Vec3::Zero();
    if (j.locked == 1) turn = j.u.col(0) * (j.uGram(0, 0) * e[static_cast<std::size_t>(j.rows[3])]);
    if (j.locked == 2)
        turn = j.u * (j.uGram *
                      Eigen::Vector2d(e[static_cast<std::size_t>(j.rows[3])], e[static_cast<std::size_t>(j.rows[4])]));
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

template <bool Soft>
void ArticulatedTree::up(const Joint& j, const std::vector<Vec6>* passedOffsets,
                         const std::vector<Eigen::Vector3d>* yOffsets) const {
    const Vec6* po = passedOffsets ? passedOffsets->data() : nullptr;
    const Vec3* yo = Soft ? yOffsets->data() : nullptr;
    if (j.free == 1) upJoint<1, Soft>(j, po, yo);
    else if (j.free == 2) upJoint<2, Soft>(j, po, yo);
    else upJoint<3, Soft>(j, po, yo);
}

// Root first: each body's motion from its parent's (with the joints' `offsets` when there are targets).
void ArticulatedTree::down(std::span<double> dv, const std::vector<Vec6>* offsets) const {
    if (m_root >= 0)
        Eigen::Map<Vec6>(dv.data() + 6 * static_cast<std::size_t>(m_root)) =
            m_rootInverse * m_p[static_cast<std::size_t>(m_root)];
    for (const Joint& j : m_joints) {
        const auto c = static_cast<std::size_t>(j.child);
        // w = T Δv_parent (+ the joint's offset): v + ω × d, ω.
        double w[6] = {0, 0, 0, 0, 0, 0};
        if (offsets)
            for (int q = 0; q < 6; ++q) w[q] = (*offsets)[c][q];
        if (j.parent >= 0) {
            const double* v = dv.data() + 6 * static_cast<std::size_t>(j.parent);
            const double* d = j.d.data();
            w[0] += v[0] + v[4] * d[2] - v[5] * d[1];
            w[1] += v[1] + v[5] * d[0] - v[3] * d[2];
            w[2] += v[2] + v[3] * d[1] - v[4] * d[0];
            w[3] += v[3];
            w[4] += v[4];
            w[5] += v[5];
        }
        double* out = dv.data() + 6 * c;
        if (j.free == 1) downJoint<1>(j, w, out);
        else if (j.free == 2) downJoint<2>(j, w, out);
        else downJoint<3>(j, w, out);
    }
}

void ArticulatedTree::setTargets(std::span<const double> e) {
    m_hasTargets = std::any_of(e.begin(), e.end(), [](double v) { return v != 0; });
    if (m_hasTargets) {
        m_target.resize(m_mass.size());
        m_targetPassed.resize(m_mass.size());
    }
    for (Joint& j : m_joints) {
        const auto c = static_cast<std::size_t>(j.child);
        if (m_hasTargets) {
            m_target[c] = particular(j, e);
            m_targetPassed[c].noalias() = j.passed * m_target[c];
        }
        j.softBias.setZero();
        for (int k = 0; k < j.softCount; ++k) {
            j.softTarget[k] = e[static_cast<std::size_t>(j.soft[k])];
            if (!m_hasTargets) continue;
            const Vec3 u = j.softAxis.col(k);
            j.softBias += u * (u.dot(m_target[c].tail<3>()) / j.softCfm[k]);
        }
    }
}

void ArticulatedTree::softOffsets(std::span<const double> lambda) const {
    for (const Joint& j : m_joints) {
        if (j.softCount == 0) continue;
        Vec3 b = -j.softBias;
        for (int k = 0; k < j.softCount; ++k)
            b += j.softAxis.col(k) *
                 ((j.softTarget[k] - j.softCfm[k] * lambda[static_cast<std::size_t>(j.soft[k])]) / j.softCfm[k]);
        Vec3& y = m_softY[static_cast<std::size_t>(j.child)];
        y.setZero();
        for (int i = 0; i < j.free; ++i)
            for (int q = 0; q < 3; ++q) y[i] += j.kernels.kp[3 + q][i] * b[q];
    }
}

void ArticulatedTree::softImpulses(std::span<const double> dv, std::span<double> lambda) const {
    for (const Joint& j : m_joints) {
        if (j.softCount == 0) continue;
        Vec3 turn = Eigen::Map<const Vec3>(dv.data() + 6 * static_cast<std::size_t>(j.child) + 3);
        if (j.parent >= 0) turn -= Eigen::Map<const Vec3>(dv.data() + 6 * static_cast<std::size_t>(j.parent) + 3);
        for (int k = 0; k < j.softCount; ++k)
            lambda[static_cast<std::size_t>(j.soft[k])] =
                (j.softTarget[k] - j.softAxis.col(k).dot(turn)) / j.softCfm[k];
    }
}

void ArticulatedTree::project(std::span<double> dv, std::span<double> lambda) const {
    // The bodies' momentum M dv, the impulses the projection starts from.
    for (std::size_t i = 0; i < m_mass.size(); ++i) {
        const Eigen::Map<const Vec6> v(dv.data() + 6 * i);
        m_p[i].head<3>() = m_mass[i] * v.head<3>();
        m_p[i].tail<3>().noalias() = m_inertia[i] * v.tail<3>();
    }
    const std::vector<Vec6>* passed = m_hasTargets ? &m_targetPassed : nullptr;
    if (m_softRows == 0) {
        for (auto it = m_joints.rbegin(); it != m_joints.rend(); ++it) up(*it, passed);
        down(dv, m_hasTargets ? &m_target : nullptr);
        return;
    }
    softOffsets(lambda);
    for (auto it = m_joints.rbegin(); it != m_joints.rend(); ++it) up<true>(*it, passed, &m_softY);
    down(dv, m_hasTargets ? &m_target : nullptr);
    softImpulses(dv, lambda);
}

void ArticulatedTree::solveImpulse(int a, const Vec6& fa, int b, const Vec6& fb, std::span<double> dv) const {
    // Only the joints on the paths from a and b to the root carry an impulse up; off them, no free part of one.
    m_onPath.assign(m_mass.size(), 0);
    for (const int start : {a, b})
        for (int body = start; body >= 0 && !m_onPath[static_cast<std::size_t>(body)];) {
            m_onPath[static_cast<std::size_t>(body)] = 1;
            m_p[static_cast<std::size_t>(body)].setZero();
            const int jj = m_jointOf[static_cast<std::size_t>(body)];
            body = jj < 0 ? -1 : m_joints[static_cast<std::size_t>(jj)].parent;
        }
    if (a >= 0) m_p[static_cast<std::size_t>(a)] += fa;
    if (b >= 0) m_p[static_cast<std::size_t>(b)] += fb;
    for (auto it = m_joints.rbegin(); it != m_joints.rend(); ++it) {
        if (m_onPath[static_cast<std::size_t>(it->child)]) up(*it, nullptr);
        else m_y[static_cast<std::size_t>(it->child)].setZero();
    }
    down(dv, nullptr);
}

void ArticulatedTree::jointImpulses(std::span<const double> f, std::span<const double> dv,
                                    std::span<double> lambda) const {
    // Leaves first: a child's joint impulse J_cᵀ λ_c = M_c Δv_c − f_c + Σ over its children k of T_kᵀ J_kᵀ λ_k.
    for (Vec6& acc : m_p) acc.setZero();
    for (auto it = m_joints.rbegin(); it != m_joints.rend(); ++it) {
        const Joint& j = *it;
        const auto c = static_cast<std::size_t>(j.child);
        const Eigen::Map<const Vec6> v(dv.data() + 6 * c), fc(f.data() + 6 * c);
        Vec6 g;
        g.head<3>() = m_mass[c] * v.head<3>();
        g.tail<3>() = m_inertia[c] * v.tail<3>();
        g += m_p[c] - fc;
        if (j.softCount == 0) {
            impulses(j, g, lambda);
        } else { // the soft rows' impulses are the caller's; the rest is the joint's
            Vec6 hard = g;
            for (int k = 0; k < j.softCount; ++k)
                hard.tail<3>() -= j.softAxis.col(k) * lambda[static_cast<std::size_t>(j.soft[k])];
            impulses(j, hard, lambda);
        }
        if (j.parent >= 0) m_p[static_cast<std::size_t>(j.parent)] += shiftBack(j.d, g);
    }
}

} // namespace afb::bullet
