#include "afb/figure/Collision.h"

#include <algorithm>
#include <limits>

#include "afb/figure/Polytope.h"

namespace afb::figure {

std::vector<std::pair<int, int>> selfCollisionPairs(const Figure& figure) {
    std::vector<std::pair<int, int>> pairs;
    if (!figure.selfCollision) return pairs;
    const int n = static_cast<int>(figure.bodies.size());
    std::vector<bool> joined(static_cast<std::size_t>(n * n), false);
    for (const FigureConstraint& c : figure.constraints) {
        if (!c.disablesCollision || c.body2 < 0) continue;
        joined[static_cast<std::size_t>(c.body1 * n + c.body2)] = true;
        joined[static_cast<std::size_t>(c.body2 * n + c.body1)] = true;
    }
    for (int i = 0; i < n; ++i) {
        const FigureBody& a = figure.bodies[static_cast<std::size_t>(i)];
        if (!a.selfCollision) continue;
        for (int j = i + 1; j < n; ++j) {
            const FigureBody& b = figure.bodies[static_cast<std::size_t>(j)];
            if (!b.selfCollision || joined[static_cast<std::size_t>(i * n + j)]) continue;
            if ((a.clipMask & b.contents) == 0 || (b.clipMask & a.contents) == 0) continue;
            pairs.emplace_back(i, j);
        }
    }
    return pairs;
}

bool attachedToWorld(const Figure& figure, int body) {
    return std::any_of(figure.constraints.begin(), figure.constraints.end(), [&](const FigureConstraint& c) {
        return c.disablesCollision && c.body2 < 0 && c.body1 == body;
    });
}

namespace {

std::vector<Eigen::Vector3d> worldVertices(const FigureBody& b) {
    std::vector<Eigen::Vector3d> out;
    out.reserve(b.shape.vertices.size());
    for (const Eigen::Vector3d& p : b.shape.vertices) out.push_back(b.loadPose.apply(p));
    return out;
}

void addAxes(const FigureBody& b, const std::vector<Eigen::Vector3d>& world, std::vector<Eigen::Vector3d>& normals,
             std::vector<Eigen::Vector3d>& edges) {
    for (const std::vector<int>& face : b.shape.faces) {
        if (face.size() < 2) continue;
        for (std::size_t k = 0; k < face.size(); ++k) {
            // One edge per direction: parallel edges (a box has 12 edges in 3 directions, each edge is shared by two
            // faces) give the same separating axes, and the axis count is the product of both bodies' edge counts.
            const Eigen::Vector3d e =
                world[static_cast<std::size_t>(face[(k + 1) % face.size()])] - world[static_cast<std::size_t>(face[k])];
            const bool seen = std::any_of(edges.begin(), edges.end(), [&](const Eigen::Vector3d& f) {
                return e.cross(f).norm() <= 1e-12 * e.norm() * f.norm();
            });
            if (!seen) edges.push_back(e);
        }
        if (const std::optional<Eigen::Vector3d> n = faceNormal(world, face)) normals.push_back(*n);
    }
}

} // namespace

double separation(const FigureBody& a, const FigureBody& b) {
    const std::vector<Eigen::Vector3d> va = worldVertices(a), vb = worldVertices(b);
    std::vector<Eigen::Vector3d> axes, edgesA, edgesB;
    addAxes(a, va, axes, edgesA);
    addAxes(b, vb, axes, edgesB);
    for (const Eigen::Vector3d& ea : edgesA)
        for (const Eigen::Vector3d& eb : edgesB) {
            const Eigen::Vector3d n = ea.cross(eb);
            if (n.norm() > 1e-9 * ea.norm() * eb.norm()) axes.push_back(n.normalized());
        }
    double best = -std::numeric_limits<double>::infinity();
    for (const Eigen::Vector3d& n : axes) {
        double minA = std::numeric_limits<double>::infinity(), maxA = -minA, minB = minA, maxB = -minA;
        for (const Eigen::Vector3d& p : va) {
            minA = std::min(minA, n.dot(p));
            maxA = std::max(maxA, n.dot(p));
        }
        for (const Eigen::Vector3d& p : vb) {
            minB = std::min(minB, n.dot(p));
            maxB = std::max(maxB, n.dot(p));
        }
        best = std::max(best, std::max(minB - maxA, minA - maxB));
    }
    return best;
}

} // namespace afb::figure
