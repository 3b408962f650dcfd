// The inertia a joint motor carries (CarriedInertia.h).
#include "CarriedInertia.h"

#include <cmath>

#include "afb/bullet/Convert.h"

namespace afb::bullet::detail {
namespace {

// |x|² 1 − x xᵀ: a unit point mass's inertia about the origin.
Eigen::Matrix3d pointInertia(const Eigen::Vector3d& x) {
    return x.squaredNorm() * Eigen::Matrix3d::Identity() - x * x.transpose();
}

// The inverse of a side's inertia (symmetric) added to w, when it is positive definite (its leading minors are
// positive): its cofactors over its determinant.
bool addInverse(const Eigen::Matrix3d& a, Eigen::Matrix3d& w) {
    const double c00 = a(1, 1) * a(2, 2) - a(1, 2) * a(1, 2), c01 = a(0, 2) * a(1, 2) - a(0, 1) * a(2, 2),
                 c02 = a(0, 1) * a(1, 2) - a(0, 2) * a(1, 1), c11 = a(0, 0) * a(2, 2) - a(0, 2) * a(0, 2),
                 c12 = a(0, 1) * a(0, 2) - a(0, 0) * a(1, 2), c22 = a(0, 0) * a(1, 1) - a(0, 1) * a(0, 1);
    const double det = a(0, 0) * c00 + a(0, 1) * c01 + a(0, 2) * c02;
    if (!(a(0, 0) > 0) || !(c22 > 0) || !(det > 0) || !std::isfinite(det)) return false;
    const double s = 1 / det;
    w(0, 0) += c00 * s;
    w(1, 1) += c11 * s;
    w(2, 2) += c22 * s;
    w(0, 1) += c01 * s;
    w(1, 0) += c01 * s;
    w(0, 2) += c02 * s;
    w(2, 0) += c02 * s;
    w(1, 2) += c12 * s;
    w(2, 1) += c12 * s;
    return true;
}

} // namespace

CarriedInertia::Sum& CarriedInertia::Sum::operator+=(const Sum& o) {
    mass += o.mass;
    first += o.first;
    second += o.second;
    held += o.held;
    return *this;
}

CarriedInertia::Sum CarriedInertia::Sum::operator-(const Sum& o) const {
    Sum s = *this;
    s.mass -= o.mass;
    s.first -= o.first;
    s.second -= o.second;
    s.held -= o.held;
    return s;
}

// Σ I_b + m_b P(y_b − x) with P(v) = |v|² 1 − v vᵀ: P(y − x) = P(y) + P(x) − 2 ((y·x) 1 − (y xᵀ + x yᵀ)/2),
// summed with the masses.
Eigen::Matrix3d CarriedInertia::Sum::about(const Eigen::Vector3d& x) const {
    const Eigen::Matrix3d cross =
        first.dot(x) * Eigen::Matrix3d::Identity() - 0.5 * (first * x.transpose() + x * first.transpose());
    return second - 2 * cross + mass * pointInertia(x);
}

void CarriedInertia::reset(int rigids, std::span<const Joint> joints) {
    const auto n = static_cast<std::size_t>(rigids > 0 ? rigids : 0);
    m_parent.assign(n, -1);
    m_root.assign(n, 0);
    m_worldJoints.assign(n, 0);
    m_child.assign(joints.size(), -1);
    m_subtree.assign(n, Sum{});
    m_order.clear();
    std::vector<std::vector<std::pair<int, int>>> next(n); // per rigid: (neighbour, joint)
    const auto inRange = [rigids](int r) { return r >= 0 && r < rigids; };
    for (std::size_t j = 0; j < joints.size(); ++j) {
        const Joint& jt = joints[j];
        if (!inRange(jt.a)) continue;
        if (jt.b < 0) ++m_worldJoints[static_cast<std::size_t>(jt.a)];
        else if (inRange(jt.b) && jt.b != jt.a) {
            next[static_cast<std::size_t>(jt.a)].emplace_back(jt.b, static_cast<int>(j));
            next[static_cast<std::size_t>(jt.b)].emplace_back(jt.a, static_cast<int>(j));
        }
    }
    // Breadth first from every rigid not reached yet (rigid 0 first): a joint that closes a loop is no tree edge.
    std::vector<char> seen(n, 0);
    for (std::size_t root = 0; root < n; ++root) {
        if (seen[root]) continue;
        seen[root] = 1;
        const std::size_t first = m_order.size();
        m_order.push_back(static_cast<int>(root));
        for (std::size_t k = first; k < m_order.size(); ++k) {
            const int r = m_order[k];
            m_root[static_cast<std::size_t>(r)] = static_cast<int>(root);
            for (const auto& [other, joint] : next[static_cast<std::size_t>(r)]) {
                if (seen[static_cast<std::size_t>(other)]) continue;
                seen[static_cast<std::size_t>(other)] = 1;
                m_parent[static_cast<std::size_t>(other)] = r;
                m_order.push_back(other);
            }
        }
    }
    // Each joint's far side: the child of the tree edge between its rigids (a second joint between the same two
    // rigids shares it); a joint to the world has the whole tree beyond it.
    for (std::size_t j = 0; j < joints.size(); ++j) {
        const Joint& jt = joints[j];
        if (!inRange(jt.a) || (jt.b >= 0 && !inRange(jt.b))) continue;
        if (jt.b < 0) continue; // the world: handled in inverseInertia
        if (m_parent[static_cast<std::size_t>(jt.b)] == jt.a) m_child[j] = jt.b;
        else if (m_parent[static_cast<std::size_t>(jt.a)] == jt.b) m_child[j] = jt.a;
    }
    m_joints.assign(joints.begin(), joints.end());
}

void CarriedInertia::update(std::span<btRigidBody* const> bodies) {
    if (bodies.size() != m_subtree.size() || bodies.empty()) return;
    m_reference = toEigen(bodies[0]->getCenterOfMassPosition());
    for (std::size_t r = 0; r < bodies.size(); ++r) {
        const btRigidBody& b = *bodies[r];
        Sum& s = m_subtree[r];
        s = Sum{};
        const bool held = !(b.getInvMass() > 0) || m_worldJoints[r] > 0;
        if (held) {
            s.held = 1;
            if (!(b.getInvMass() > 0)) continue; // a keyframed or static body: nothing of it moves
        }
        const double mass = 1 / double(b.getInvMass());
        const btVector3& inv = b.getInvInertiaDiagLocal();
        Eigen::Vector3d principal;
        for (int k = 0; k < 3; ++k) principal[k] = inv[k] > 0 ? 1 / double(inv[k]) : 0.0;
        const btMatrix3x3& basis = b.getCenterOfMassTransform().getBasis();
        Eigen::Matrix3d rotation;
        for (int i = 0; i < 3; ++i)
            for (int k = 0; k < 3; ++k) rotation(i, k) = double(basis[i][k]);
        const Eigen::Vector3d x = toEigen(b.getCenterOfMassPosition()) - m_reference;
        s.mass = mass;
        s.first = mass * x;
        s.second = rotation * principal.asDiagonal() * rotation.transpose() + mass * pointInertia(x);
    }
    // Children before parents: the breadth-first order backwards.
    for (auto it = m_order.rbegin(); it != m_order.rend(); ++it) {
        const auto r = static_cast<std::size_t>(*it);
        if (m_parent[r] >= 0) m_subtree[static_cast<std::size_t>(m_parent[r])] += m_subtree[r];
    }
}

bool CarriedInertia::inverseInertia(int j, const btVector3& pivot, btMatrix3x3& w) const {
    if (j < 0 || static_cast<std::size_t>(j) >= m_child.size()) return false;
    const Joint& jt = m_joints[static_cast<std::size_t>(j)];
    Sum far, near;
    if (m_child[static_cast<std::size_t>(j)] >= 0) {
        const auto child = static_cast<std::size_t>(m_child[static_cast<std::size_t>(j)]);
        far = m_subtree[child];
        near = m_subtree[static_cast<std::size_t>(m_root[child])] - far; // the rest of its part of the figure
    } else if (jt.b < 0 && jt.a >= 0 && static_cast<std::size_t>(jt.a) < m_parent.size()) {
        // Held by the world: the figure's part that turns about it is all of it (the world side is held).
        far = m_subtree[static_cast<std::size_t>(m_root[static_cast<std::size_t>(jt.a)])];
        near.held = 1;
    } else return false;
    const Eigen::Vector3d x = toEigen(pivot) - m_reference;
    Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
    bool any = false;
    for (const Sum* side : {&far, &near})
        if (side->held == 0 && side->mass > 0) any = addInverse(side->about(x), sum) || any;
    if (!any)
        for (const Sum* side : {&far, &near})
            if (side->mass > 0) any = addInverse(side->about(x), sum) || any;
    if (!any) return false;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) w[r][c] = btScalar(sum(r, c));
    return true;
}

} // namespace afb::bullet::detail
