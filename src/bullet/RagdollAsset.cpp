#include "afb/bullet/RagdollAsset.h"

#include <algorithm>
#include <cmath>

#include <LinearMath/btGeometryUtil.h>

#include "PairPruning.h"
#include "afb/detail/Convert.h"
#include "afb/figure/Collision.h"
#include "afb/figure/MassProperties.h"
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

// Groups of bodies joined by `fixed` constraints between two bodies (union–find), by their smallest body.
std::vector<int> fixedGroups(const figure::Figure& f) {
    std::vector<int> root(f.bodies.size());
    for (std::size_t i = 0; i < root.size(); ++i) root[i] = static_cast<int>(i);
    const auto find = [&](int b) {
        while (root[static_cast<std::size_t>(b)] != b) b = root[static_cast<std::size_t>(b)];
        return b;
    };
    for (const figure::FigureConstraint& c : f.constraints) {
        if (c.type != figure::JointType::Fixed || c.body2 < 0) continue;
        const int a = find(c.body1), b = find(c.body2);
        root[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);
    }
    for (std::size_t i = 0; i < root.size(); ++i) root[i] = find(static_cast<int>(i));
    return root;
}

} // namespace

void RagdollAsset::buildLayout(RigidLayout& layout, bool mergeFixed) {
    const figure::Figure& f = m_figure;
    const std::size_t n = f.bodies.size();
    std::vector<int> group(n);
    if (mergeFixed) group = fixedGroups(f);
    else
        for (std::size_t i = 0; i < n; ++i) group[i] = static_cast<int>(i);
    // Groups ordered by their first body (a group's root is its smallest body).
    std::vector<std::vector<int>> groups;
    std::vector<int> index(n, -1);
    for (std::size_t i = 0; i < n; ++i) {
        const std::size_t root = static_cast<std::size_t>(group[i]);
        if (index[root] < 0) {
            index[root] = static_cast<int>(groups.size());
            groups.emplace_back();
        }
        groups[static_cast<std::size_t>(index[root])].push_back(static_cast<int>(i));
    }
    std::vector<figure::Transform> poses;
    for (const figure::FigureBody& b : f.bodies) poses.push_back(b.loadPose);
    fillLayout(layout, groups, poses, m_compounds);
}

RigidLayout RagdollAsset::layoutAt(const figure::LodLevel& level, std::span<const figure::Transform> poses,
                                   std::vector<std::unique_ptr<btCollisionShape>>& compounds) const {
    RigidLayout layout;
    fillLayout(layout, level.groups, poses, compounds);
    return layout;
}

void RagdollAsset::fillLayout(RigidLayout& layout, const std::vector<std::vector<int>>& groups,
                              std::span<const figure::Transform> poses,
                              std::vector<std::unique_ptr<btCollisionShape>>& compounds) const {
    const figure::Figure& f = m_figure;
    const std::size_t n = f.bodies.size();
    layout.rigidOf.assign(n, -1);
    layout.bodyInRigid.assign(n, figure::Transform{});
    layout.bodyInRigidBt.assign(n, btTransform::getIdentity());
    for (const std::vector<int>& group : groups) {
        for (const int b : group) layout.rigidOf[static_cast<std::size_t>(b)] = static_cast<int>(layout.rigids.size());
        layout.rigids.push_back({});
        layout.rigids.back().bodies = group;
    }
    for (RigidLayout::Rigid& r : layout.rigids) {
        std::vector<figure::RigidPart> parts;
        r.representative = r.bodies.front();
        r.innerRadius = m_innerRadii[static_cast<std::size_t>(r.bodies.front())];
        for (const int b : r.bodies) {
            const figure::FigureBody& body = f.bodies[static_cast<std::size_t>(b)];
            parts.push_back({body.massKg, body.inertiaKgM2, poses[static_cast<std::size_t>(b)]});
            if (body.massKg > f.bodies[static_cast<std::size_t>(r.representative)].massKg) r.representative = b;
            r.innerRadius = std::min(r.innerRadius, m_innerRadii[static_cast<std::size_t>(b)]);
        }
        const figure::RigidPart whole = figure::combineRigidParts(parts);
        r.massKg = whole.massKg;
        r.inertiaKgM2 = whole.inertiaKgM2;
        r.loadPose = whole.pose;
        btVector3 centre;
        btScalar radius = 0;
        if (r.bodies.size() == 1) {
            r.shape = m_shapes[static_cast<std::size_t>(r.bodies.front())].get();
            r.shape->getBoundingSphere(centre, radius);
            r.boundingRadius = radius;
            continue;
        }
        // A compound of the bodies' own shapes, each at its body frame in the rigid's frame. Two to a few
        // children: no bounding-volume tree.
        auto compound = std::make_unique<btCompoundShape>(false, static_cast<int>(r.bodies.size()));
        for (const int b : r.bodies) {
            const figure::Transform inRigid = whole.pose.inverse() * poses[static_cast<std::size_t>(b)];
            layout.bodyInRigid[static_cast<std::size_t>(b)] = inRigid;
            layout.bodyInRigidBt[static_cast<std::size_t>(b)] = toBt(inRigid);
            compound->addChildShape(toBt(inRigid), m_shapes[static_cast<std::size_t>(b)].get());
        }
        r.shape = compound.get();
        r.shape->getBoundingSphere(centre, radius);
        r.boundingRadius = radius;
        compounds.push_back(std::move(compound));
    }
    for (const auto& pair : m_contactPairs) {
        int a = layout.rigidOf[static_cast<std::size_t>(pair.first)];
        int b = layout.rigidOf[static_cast<std::size_t>(pair.second)];
        if (a == b) continue;
        if (a > b) std::swap(a, b);
        layout.contactPairs.emplace_back(a, b);
        if (!std::binary_search(m_overlappingPairs.begin(), m_overlappingPairs.end(), pair))
            layout.contactPairsApart.emplace_back(a, b);
    }
    for (auto* pairs : {&layout.contactPairs, &layout.contactPairsApart}) {
        std::sort(pairs->begin(), pairs->end());
        pairs->erase(std::unique(pairs->begin(), pairs->end()), pairs->end());
    }
    // What each ragdoll hands Bullet as it spawns (Ragdoll::filterPairs): their complements, and every pair of rigids
    // that a joint between two of their bodies disables (what Bullet's constraint references would add: a merged
    // rigid keeps its joints' pairs off even when another of its bodies may touch the other rigid).
    const int rigids = static_cast<int>(layout.rigids.size());
    std::vector<std::pair<int, int>> jointed;
    for (const figure::FigureConstraint& c : f.constraints) {
        if (!c.disablesCollision || c.body2 < 0) continue;
        const int a = layout.rigidOf[static_cast<std::size_t>(c.body1)];
        const int b = layout.rigidOf[static_cast<std::size_t>(c.body2)];
        if (a != b) jointed.emplace_back(std::min(a, b), std::max(a, b));
    }
    std::sort(jointed.begin(), jointed.end());
    for (const auto& [pairs, ignored] : {std::pair{&layout.contactPairs, &layout.ignoredPairs},
                                         std::pair{&layout.contactPairsApart, &layout.ignoredPairsApart}}) {
        ignored->clear();
        for (int i = 0; i < rigids; ++i)
            for (int j = i + 1; j < rigids; ++j) {
                const std::pair pair(i, j);
                if (!std::binary_search(pairs->begin(), pairs->end(), pair) ||
                    std::binary_search(jointed.begin(), jointed.end(), pair))
                    ignored->emplace_back(pair);
            }
    }
    for (const figure::FigureConstraint& c : f.constraints)
        layout.internal.push_back(c.body2 >= 0 && layout.rigidOf[static_cast<std::size_t>(c.body1)] ==
                                                      layout.rigidOf[static_cast<std::size_t>(c.body2)]);
}

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
            // Every triple of planes through a vertex yields it once, so a vertex where more than three faces meet
            // (an octahedron's, a bone's waist, a cone's apex) comes out several times. Duplicates cost every support
            // query and crowd distinct corners out of a four-point contact manifold (a bone lying on the ground was
            // held at one point, four times over, and rocked its far end 2.4 cm into the ground): keep one of each.
            const btScalar same = btScalar(1e-6) * btMax(btScalar(1e-3), static_cast<btScalar>(inradius));
            auto hull = std::make_unique<btConvexHullShape>();
            for (int i = 0; i < vertices.size(); ++i) {
                bool seen = false;
                for (int k = 0; k < hull->getNumPoints() && !seen; ++k)
                    seen = (hull->getUnscaledPoints()[k] - vertices[i]).length2() <= same * same;
                if (!seen) hull->addPoint(vertices[i], false);
            }
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
    for (const auto& [i, j] : asset->m_contactPairs)
        if (figure::separation(asset->m_figure.bodies[static_cast<std::size_t>(i)],
                               asset->m_figure.bodies[static_cast<std::size_t>(j)]) < -figure::kTouchToleranceM)
            asset->m_overlappingPairs.emplace_back(i, j);
    asset->buildLayout(asset->m_separate, false);
    asset->buildLayout(asset->m_merged, true);
    return asset;
}

} // namespace afb::bullet
