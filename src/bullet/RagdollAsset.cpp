#include "afb/bullet/RagdollAsset.h"

#include <algorithm>
#include <cmath>

#include <LinearMath/btGeometryUtil.h>

#include "PairPruning.h"
#include "afb/bullet/Convert.h"
#include "afb/figure/Collision.h"
#include "afb/figure/Polytope.h"

namespace afb::bullet {
namespace {

// The figure's face planes as Bullet plane equations (n, d): n·p + d = 0 on the face, n·p + d ≤ 0 inside.
btAlignedObjectArray<btVector3> btPlanes(const std::vector<figure::FacePlane>& faces) {
    btAlignedObjectArray<btVector3> planes;
    for (const figure::FacePlane& face : faces) {
        btVector3 plane = toBt(face.normal);
        plane[3] = static_cast<btScalar>(-face.offset);
        planes.push_back(plane);
    }
    return planes;
}

} // namespace

std::shared_ptr<const RagdollAsset> RagdollAsset::create(figure::Figure figure) {
    std::shared_ptr<RagdollAsset> asset(new RagdollAsset(std::move(figure)));
    for (const figure::FigureBody& body : asset->m_figure.bodies) {
        const std::vector<figure::FacePlane> faces = figure::facePlanes(body.shape.vertices, body.shape.faces);
        const btAlignedObjectArray<btVector3> planes = btPlanes(faces);
        // COM (the body origin) to the nearest face, rounded to btScalar as the hull's planes are.
        const double inradius = static_cast<btScalar>(figure::inRadius(faces));
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
    asset->m_prunedPairs = detail::unreachablePairs(asset->m_figure);
    for (const auto& pair : figure::selfCollisionPairs(asset->m_figure))
        if (!std::binary_search(asset->m_prunedPairs.begin(), asset->m_prunedPairs.end(), pair))
            asset->m_contactPairs.push_back(pair);
    return asset;
}

} // namespace afb::bullet
