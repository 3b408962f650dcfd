#include "afb/bullet/RagdollAsset.h"

#include <LinearMath/btGeometryUtil.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "afb/bullet/Convert.h"

namespace afb::bullet {
namespace {

// Outward face planes (n, d) with n·p + d = 0 on the face, n·p + d ≤ 0 inside.
btAlignedObjectArray<btVector3> facePlanes(const figure::BodyShape& shape) {
    btAlignedObjectArray<btVector3> planes;
    for (const std::vector<int>& face : shape.faces) {
        if (face.size() < 3) continue;
        Eigen::Vector3d n = Eigen::Vector3d::Zero();
        Eigen::Vector3d centre = Eigen::Vector3d::Zero();
        for (std::size_t k = 0; k < face.size(); ++k) {
            const Eigen::Vector3d& p = shape.vertices[static_cast<std::size_t>(face[k])];
            const Eigen::Vector3d& q = shape.vertices[static_cast<std::size_t>(face[(k + 1) % face.size()])];
            n += p.cross(q);
            centre += p;
        }
        if (n.norm() == 0.0) continue;
        n.normalize();
        centre /= static_cast<double>(face.size());
        btVector3 plane = toBt(n);
        plane[3] = static_cast<btScalar>(-n.dot(centre));
        planes.push_back(plane);
    }
    return planes;
}

} // namespace

std::shared_ptr<const RagdollAsset> RagdollAsset::create(figure::Figure figure) {
    std::shared_ptr<RagdollAsset> asset(new RagdollAsset(std::move(figure)));
    for (const figure::FigureBody& body : asset->m_figure.bodies) {
        const btAlignedObjectArray<btVector3> planes = facePlanes(body.shape);
        double inradius = std::numeric_limits<double>::infinity(); // COM (the body origin) to the nearest face
        for (int i = 0; i < planes.size(); ++i) inradius = std::min(inradius, -static_cast<double>(planes[i][3]));
        const double margin = std::max(0.0, std::min(kMaxMarginM, 0.2 * inradius));
        if (body.shape.boxHalfExtents) {
            auto box = std::make_unique<btBoxShape>(toBt(*body.shape.boxHalfExtents));
            box->setMargin(static_cast<btScalar>(margin));
            asset->m_shapes.push_back(std::move(box));
        } else {
            // Shrink every face plane by the margin, then take the vertices of the shrunk polytope.
            btAlignedObjectArray<btVector3> shrunk;
            for (int i = 0; i < planes.size(); ++i) {
                btVector3 p = planes[i];
                p[3] += static_cast<btScalar>(margin);
                shrunk.push_back(p);
            }
            btAlignedObjectArray<btVector3> vertices;
            btGeometryUtil::getVerticesFromPlaneEquations(shrunk, vertices);
            auto hull = std::make_unique<btConvexHullShape>();
            for (int i = 0; i < vertices.size(); ++i) hull->addPoint(vertices[i], false);
            hull->recalcLocalAabb();
            hull->setMargin(static_cast<btScalar>(margin));
            asset->m_shapes.push_back(std::move(hull));
        }
        asset->m_margins.push_back(margin);
        asset->m_innerRadii.push_back(std::isfinite(inradius) ? inradius : 0.0);
    }
    return asset;
}

} // namespace afb::bullet
