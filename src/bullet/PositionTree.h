#pragma once
// The tree step of the position pass (Method::positionTree): Newton steps that close every joint of a ragdoll at
// once over its joint tree (PositionPass.cpp).
#include <algorithm>
#include <cmath>
#include <span>
#include <vector>

#include "BlockTree.h"
#include "PositionBodies.h"

namespace afb::bullet::detail::position {

// Every joint at once: a Newton step on the ragdoll's joint tree with the bodies' masses (Baraff's block
// factorisation, as the direct velocity solve uses), so that closing one joint does not open its neighbours.
// Per joint: the anchor gap (3 rows), the locked axes (fixed: 3, hinge: 2) and the limit rows past their limit
// (as equalities: the step puts them back on the limit). Joints that close a loop, a second joint to the world in
// one tree, and sliders are left to the sweeps. Nodes: the movable bodies (6: position, rotation vector), then
// the joints; H = [[M, −Jᵀ], [−J, 0]], H [Δx; λ] = [0; C], so that J Δx = −C and M Δx = Jᵀ λ.
class JointTree {
  public:
    struct Joint {
        int constraint;
        int a, b; // body indices; −1: immovable
    };
    // A joint's rows this step: the two anchor copies, and angular rows J_A = [0, n], J_B = [0, −n], each with
    // its error C (the step makes C + n·(Δθ_A − Δθ_B) = 0).
    struct Rows {
        btVector3 anchorA, anchorB;
        int angular = 0;
        btVector3 axis[5];
        btScalar error[5];
    };
    // Lays the tree out once per pass from the joints' endpoints; false when there is nothing to solve.
    bool build(std::span<const Joint> joints, int bodies) {
        m_afterValid = false;
        m_bodies = bodies;
        std::vector<int>& root = m_root;
        root.resize(static_cast<std::size_t>(bodies));
        std::iota(root.begin(), root.end(), 0);
        std::vector<char>& grounded = m_grounded;
        grounded.assign(static_cast<std::size_t>(bodies), 0);
        const auto find = [&](int i) {
            while (root[static_cast<std::size_t>(i)] != i) i = root[static_cast<std::size_t>(i)];
            return i;
        };
        m_joints.clear();
        for (const Joint& j : joints) {
            if (j.a < 0 && j.b < 0) continue;
            if (j.a >= 0 && j.b >= 0) {
                const int ra = find(j.a), rb = find(j.b);
                if (ra == rb) continue; // closes a loop
                if (grounded[static_cast<std::size_t>(ra)] && grounded[static_cast<std::size_t>(rb)]) continue;
                root[static_cast<std::size_t>(ra)] = rb;
                grounded[static_cast<std::size_t>(rb)] |= grounded[static_cast<std::size_t>(ra)];
            } else {
                const int r = find(j.a >= 0 ? j.a : j.b);
                if (grounded[static_cast<std::size_t>(r)]) continue; // a second hold on the world
                grounded[static_cast<std::size_t>(r)] = 1;
            }
            m_joints.push_back(j);
        }
        if (m_joints.empty()) return false;
        // Parents: a grounded tree hangs from its world joint, any other from its first body.
        const int nodes = bodies + static_cast<int>(m_joints.size());
        m_parent.assign(static_cast<std::size_t>(nodes), -2);
        std::vector<std::vector<int>>& jointsAt = m_jointsAt;
        if (jointsAt.size() < static_cast<std::size_t>(bodies)) jointsAt.resize(static_cast<std::size_t>(bodies));
        for (auto& at : jointsAt) at.clear();
        for (std::size_t k = 0; k < m_joints.size(); ++k) {
            if (m_joints[k].a >= 0) jointsAt[static_cast<std::size_t>(m_joints[k].a)].push_back(static_cast<int>(k));
            if (m_joints[k].b >= 0) jointsAt[static_cast<std::size_t>(m_joints[k].b)].push_back(static_cast<int>(k));
        }
        std::vector<int>& stack = m_stack;
        stack.clear();
        auto hang = [&](int body) { // everything reachable from `body`, whose parent is already set
            stack.push_back(body);
            while (!stack.empty()) {
                const int x = stack.back();
                stack.pop_back();
                for (int k : jointsAt[static_cast<std::size_t>(x)]) {
                    const int node = bodies + k;
                    if (m_parent[static_cast<std::size_t>(node)] != -2) continue;
                    m_parent[static_cast<std::size_t>(node)] = x;
                    const Joint& j = m_joints[static_cast<std::size_t>(k)];
                    const int other = j.a == x ? j.b : j.a;
                    if (other < 0 || m_parent[static_cast<std::size_t>(other)] != -2) continue;
                    m_parent[static_cast<std::size_t>(other)] = node;
                    stack.push_back(other);
                }
            }
        };
        for (std::size_t k = 0; k < m_joints.size(); ++k) {
            const Joint& j = m_joints[k];
            if (j.a >= 0 && j.b >= 0) continue;
            const int body = j.a >= 0 ? j.a : j.b;
            m_parent[static_cast<std::size_t>(bodies) + k] = -1;
            m_parent[static_cast<std::size_t>(body)] = bodies + static_cast<int>(k);
            hang(body);
        }
        for (int x = 0; x < bodies; ++x)
            if (m_parent[static_cast<std::size_t>(x)] == -2) {
                m_parent[static_cast<std::size_t>(x)] = -1;
                hang(x);
            }
        return true;
    }

    // One Newton step of `sides` for the joints' rows (`rowsOf(joint)`). False (nothing moved) when every row is
    // within its tolerance already, or the factorisation fails.
    template <typename RowsOf>
    bool step(std::vector<Side>& sides, RowsOf rowsOf) {
        // assembleBodies and assembleJoints write every entry of every block.
        if (!measure(rowsOf) || !m_tree.reset(m_dims, m_parent, false)) return false;
        assembleBodies(sides);
        assembleJoints(sides);
        if (!m_tree.factor()) return false;
        m_tree.solve(m_rhs.data());
        if (!std::all_of(m_rhs.begin(), m_rhs.end(), [](double v) { return std::isfinite(v); })) return false;
        return moveByStep(sides, rowsOf);
    }

  private:
    // The joints' rows at the bodies' poses and the nodes' sizes; whether any row is past its tolerance.
    template <typename RowsOf>
    bool measure(RowsOf& rowsOf) {
        // After an accepted step the bodies are where it measured its error: its rows are this step's.
        const bool reuse = m_afterValid;
        m_afterValid = false;
        if (reuse) std::swap(m_rows, m_after);
        m_rows.resize(m_joints.size());
        m_after.resize(m_joints.size());
        m_dims.assign(m_parent.size(), 6);
        bool open = false;
        for (std::size_t k = 0; k < m_joints.size(); ++k) {
            if (!reuse) m_rows[k] = rowsOf(m_joints[k]);
            const Rows& r = m_rows[k];
            m_dims[static_cast<std::size_t>(m_bodies) + k] = 3 + r.angular;
            open = open || (r.anchorB - r.anchorA).length2() > kAnchorToleranceM * kAnchorToleranceM;
            for (int i = 0; i < r.angular; ++i) open = open || btFabs(r.error[i]) > kAngleToleranceRad;
        }
        return open;
    }

    // The bodies' blocks of H: mass and world inertia (an immovable body inside the tree: a very heavy one).
    void assembleBodies(const std::vector<Side>& sides) {
        for (int x = 0; x < m_bodies; ++x) {
            const Side& s = sides[static_cast<std::size_t>(x)];
            double* d = m_tree.diag(x);
            std::fill(d, d + 36, 0.0);
            if (s.body == nullptr) {
                for (int q = 0; q < 6; ++q) d[7 * q] = 1e12;
                continue;
            }
            const btVector3& il = s.invInertiaLocal;
            if (m_tree.leaf(x) && s.invMass > 0 && il.x() > 0 && il.y() > 0 && il.z() > 0) {
                // Its pivot is M: M⁻¹ as the side keeps it, transposed as factor() stores an inverse.
                for (int q = 0; q < 3; ++q) {
                    d[7 * q] = double(s.invMass);
                    for (int c = 0; c < 3; ++c) d[6 * (3 + q) + 3 + c] = double(s.invInertia[c][q]);
                }
                m_tree.setInverted(x);
                continue;
            }
            const auto inv = [](btScalar v) { return v > 0 ? 1 / v : btScalar(1e12); };
            const btMatrix3x3 inertia = s.r.scaled(btVector3(inv(il.x()), inv(il.y()), inv(il.z()))) * s.r.transpose();
            for (int q = 0; q < 3; ++q) {
                d[7 * q] = 1.0 / double(s.invMass);
                for (int c = 0; c < 3; ++c) d[6 * (3 + q) + 3 + c] = double(inertia[q][c]);
            }
        }
    }

    // The joints' blocks of H (−J against each of their bodies) and their errors on the right-hand side.
    void assembleJoints(const std::vector<Side>& sides) {
        m_rhs.assign(static_cast<std::size_t>(m_tree.size()), 0.0);
        double negJ[8 * 6]; // −J of one side, rows × 6, row-major
        for (std::size_t k = 0; k < m_joints.size(); ++k) {
            const Joint& j = m_joints[k];
            const Rows& r = m_rows[k];
            const int node = m_bodies + static_cast<int>(k);
            const int rows = 3 + r.angular;
            std::fill(m_tree.diag(node), m_tree.diag(node) + rows * rows, 0.0);
            double* rhs = m_rhs.data() + m_tree.offset(node);
            const btVector3 gap = r.anchorB - r.anchorA;
            for (int q = 0; q < 3; ++q) rhs[q] = double(gap[q]);
            for (int i = 0; i < r.angular; ++i) rhs[3 + i] = double(r.error[i]);
            // J_A = [−I, [r_A]×; 0, n], J_B = [I, −[r_B]×; 0, −n].
            for (int side = 0; side < 2; ++side) {
                const int x = side ? j.b : j.a;
                if (x < 0) continue;
                const Side& s = sides[static_cast<std::size_t>(x)];
                const btMatrix3x3 rx = skew((side ? r.anchorB : r.anchorA) - s.x);
                const double sign = side ? 1.0 : -1.0;
                std::fill(negJ, negJ + 6 * rows, 0.0);
                for (int q = 0; q < 3; ++q) {
                    negJ[6 * q + q] = -sign;
                    for (int c = 0; c < 3; ++c) negJ[6 * q + 3 + c] = sign * double(rx[q][c]);
                }
                for (int i = 0; i < r.angular; ++i)
                    for (int c = 0; c < 3; ++c) negJ[6 * (3 + i) + 3 + c] = sign * double(r.axis[i][c]);
                if (m_tree.parent(node) == x) {
                    std::copy(negJ, negJ + 6 * rows, m_tree.toParent(node)); // H_{joint,body}
                } else { // the body hangs from the joint: H_{body,joint} = (H_{joint,body})ᵀ
                    double* e = m_tree.toParent(x);
                    for (int q = 0; q < rows; ++q)
                        for (int c = 0; c < 6; ++c) e[rows * c + q] = negJ[6 * q + c];
                }
            }
        }
    }

    // The step is exact only to first order: where the mass-weighted solution turns light, thin bodies a long way
    // (a nearly straight rope of 10 cm links closes 1 mm gaps by turning links 0.3 rad one way and the next the
    // other), the second-order rest can exceed what it closed. So the error is measured after the move, and a step
    // that leaves more than it found is halved, then dropped.
    template <typename RowsOf>
    bool moveByStep(std::vector<Side>& sides, RowsOf& rowsOf) {
        const double before = error(m_rows);
        m_saved = sides;
        for (double scale = 1;; scale *= 0.5) {
            for (int x = 0; x < m_bodies; ++x) {
                const double* dx = m_rhs.data() + m_tree.offset(x);
                const btScalar f = static_cast<btScalar>(scale);
                move(sides[static_cast<std::size_t>(x)],
                     btVector3(btScalar(dx[0]), btScalar(dx[1]), btScalar(dx[2])) * f,
                     btVector3(btScalar(dx[3]), btScalar(dx[4]), btScalar(dx[5])) * f);
            }
            for (std::size_t k = 0; k < m_joints.size(); ++k) m_after[k] = rowsOf(m_joints[k]);
            if (error(m_after) < before) {
                m_afterValid = true;
                return true;
            }
            for (std::size_t x = 0; x < sides.size(); ++x) sides[x] = m_saved[x];
            if (scale <= 0.25) return false;
        }
    }

    // The largest error of `rows`: anchor gaps in metres, angles as the arc they make at 0.1 m.
    static double error(const std::vector<Rows>& rows) {
        double worst = 0;
        for (const Rows& r : rows) {
            worst = std::max(worst, double((r.anchorB - r.anchorA).length()));
            for (int i = 0; i < r.angular; ++i) worst = std::max(worst, 0.1 * std::abs(double(r.error[i])));
        }
        return worst;
    }

    int m_bodies = 0;
    std::vector<Joint> m_joints;
    std::vector<int> m_root, m_stack; // build()'s scratch
    std::vector<char> m_grounded;
    std::vector<std::vector<int>> m_jointsAt;
    std::vector<int> m_parent, m_dims;
    std::vector<Rows> m_rows, m_after;
    bool m_afterValid = false; // m_after holds the rows at the bodies' current poses
    std::vector<Side> m_saved;
    BlockTree m_tree;
    std::vector<double> m_rhs;
};

} // namespace afb::bullet::detail::position
