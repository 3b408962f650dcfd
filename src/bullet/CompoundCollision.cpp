// Contacts of a merged ragdoll body, child by child (CompoundCollision.h).
#include "CompoundCollision.h"

#include <vector>

#include <BulletCollision/CollisionDispatch/btActivatingCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btCollisionObjectWrapper.h>
#include <LinearMath/btAabbUtil2.h>

namespace afb::bullet::detail {
namespace {

// The other side's child index when it is itself a child of a compound (the wrapper of a nested pair), else -1.
int childIndexOf(const btCollisionObjectWrapper* w) {
    return w->getCollisionShape() != w->getCollisionObject()->getCollisionShape() ? w->m_index : -1;
}

class MergedBodyAlgorithm : public btActivatingCollisionAlgorithm {
  public:
    MergedBodyAlgorithm(const btCollisionAlgorithmConstructionInfo& ci, const btCollisionObjectWrapper* w0,
                        const btCollisionObjectWrapper* w1, bool swapped, const CompoundRules& rules)
        : btActivatingCollisionAlgorithm(ci, w0, w1), m_rules(rules), m_swapped(swapped) {
        const btCollisionObjectWrapper* compound = swapped ? w1 : w0;
        const btCollisionObjectWrapper* other = swapped ? w0 : w1;
        const auto* shape = static_cast<const btCompoundShape*>(compound->getCollisionShape());
        m_children.resize(static_cast<std::size_t>(shape->getNumChildShapes()));
        const int otherChild = childIndexOf(other);
        for (std::size_t i = 0; i < m_children.size(); ++i)
            m_children[i].allowed = rules.mayTouch(*compound->getCollisionObject(), static_cast<int>(i),
                                                   *other->getCollisionObject(), otherChild);
    }
    ~MergedBodyAlgorithm() override {
        for (Child& c : m_children) release(c);
    }
    MergedBodyAlgorithm(const MergedBodyAlgorithm&) = delete;
    MergedBodyAlgorithm& operator=(const MergedBodyAlgorithm&) = delete;

    void processCollision(const btCollisionObjectWrapper* w0, const btCollisionObjectWrapper* w1,
                          const btDispatcherInfo& info, btManifoldResult* out) override {
        const btCollisionObjectWrapper* compoundWrap = m_swapped ? w1 : w0;
        const btCollisionObjectWrapper* otherWrap = m_swapped ? w0 : w1;
        const btCollisionObject* compoundObject = compoundWrap->getCollisionObject();
        const btCollisionObject* otherObject = otherWrap->getCollisionObject();
        const auto* shape = static_cast<const btCompoundShape*>(compoundWrap->getCollisionShape());
        // The reach of this pair's contacts in this substep: a child is tested (and gets a manifold) once the other
        // object is within it, as two separate bodies are once their (threshold-widened) bounding boxes meet.
        const btScalar threshold = m_rules.breakingThreshold(*compoundObject, *otherObject, info.m_timeStep);
        const btVector3 widen(threshold, threshold, threshold);
        btVector3 otherMin, otherMax;
        otherWrap->getCollisionShape()->getAabb(otherWrap->getWorldTransform(), otherMin, otherMax);
        const bool otherConvex = otherWrap->getCollisionShape()->isConvex();

        for (std::size_t i = 0; i < m_children.size(); ++i) {
            Child& c = m_children[i];
            if (!c.allowed) continue;
            const int index = static_cast<int>(i);
            const btCollisionShape* childShape = shape->getChildShape(index);
            const btTransform childWorld = compoundWrap->getWorldTransform() * shape->getChildTransform(index);
            btVector3 childMin, childMax;
            childShape->getAabb(childWorld, childMin, childMax);
            if (!TestAabbAgainstAabb2(childMin - widen, childMax + widen, otherMin, otherMax)) {
                release(c);
                continue;
            }
            const btCollisionObjectWrapper childWrap(compoundWrap, childShape, compoundObject, childWorld, -1, index);
            if (c.algorithm == nullptr) {
                // Against a convex object the child's manifold is made here, with this substep's reach, so that
                // the first test already finds speculative points (the convex algorithms take a given manifold
                // and leave refreshing it to its owner). Planes, meshes and compounds make their own.
                if (otherConvex && m_dispatcher->needsCollision(compoundObject, otherObject)) {
                    c.manifold = m_dispatcher->getNewManifold(compoundObject, otherObject);
                    c.manifold->setContactBreakingThreshold(threshold);
                }
                c.algorithm =
                    m_dispatcher->findAlgorithm(&childWrap, otherWrap, c.manifold, BT_CONTACT_POINT_ALGORITHMS);
            }
            // The result reports the child as its side of the pair (part -1, index i), as Bullet's compound does.
            const bool compoundIs0 = out->getBody0Internal() == compoundObject;
            const btCollisionObjectWrapper* saved = compoundIs0 ? out->getBody0Wrap() : out->getBody1Wrap();
            if (compoundIs0) {
                out->setBody0Wrap(&childWrap);
                out->setShapeIdentifiersA(-1, index);
            } else {
                out->setBody1Wrap(&childWrap);
                out->setShapeIdentifiersB(-1, index);
            }
            c.algorithm->processCollision(&childWrap, otherWrap, info, out);
            if (compoundIs0) out->setBody0Wrap(saved);
            else out->setBody1Wrap(saved);
            if (c.manifold != nullptr) {
                out->setPersistentManifold(c.manifold);
                out->refreshContactPoints(); // what the convex algorithms do for a manifold they own
            }
        }
    }

    btScalar calculateTimeOfImpact(btCollisionObject*, btCollisionObject*, const btDispatcherInfo&,
                                   btManifoldResult*) override {
        return 1; // continuous collision of a rigid body sweeps its own sphere, not the algorithm
    }
    void getAllContactManifolds(btManifoldArray& manifolds) override {
        for (const Child& c : m_children) {
            if (c.manifold != nullptr) manifolds.push_back(c.manifold);
            else if (c.algorithm != nullptr) c.algorithm->getAllContactManifolds(manifolds);
        }
    }

  private:
    struct Child {
        bool allowed = true;
        btCollisionAlgorithm* algorithm = nullptr;
        btPersistentManifold* manifold = nullptr; ///< ours (against a convex object), else the algorithm's own
    };
    void release(Child& c) {
        if (c.algorithm != nullptr) {
            c.algorithm->~btCollisionAlgorithm();
            m_dispatcher->freeCollisionAlgorithm(c.algorithm);
            c.algorithm = nullptr;
        }
        if (c.manifold != nullptr) {
            m_dispatcher->releaseManifold(c.manifold);
            c.manifold = nullptr;
        }
    }

    const CompoundRules& m_rules;
    bool m_swapped;
    std::vector<Child> m_children;
};

} // namespace

class CompoundCollision::CreateFunc : public btCollisionAlgorithmCreateFunc {
  public:
    CreateFunc(const CompoundRules& rules, btCollisionConfiguration& config, bool compoundFirst)
        : m_rules(rules), m_config(config), m_compoundFirst(compoundFirst) {}

    btCollisionAlgorithm* CreateCollisionAlgorithm(btCollisionAlgorithmConstructionInfo& ci,
                                                   const btCollisionObjectWrapper* w0,
                                                   const btCollisionObjectWrapper* w1) override {
        const auto isOurs = [&](const btCollisionObjectWrapper* w) {
            return w->getCollisionShape()->isCompound() && m_rules.handles(*w->getCollisionObject());
        };
        // The merged body whose children this pair walks: the first one when both are compounds (its children meet
        // the other as a whole, which walks its own children in turn).
        int side = -1;
        if (m_compoundFirst && isOurs(w0)) side = 0;
        else if (isOurs(w1)) side = 1;
        if (side < 0) {
            btCollisionAlgorithmCreateFunc* bullet =
                m_config.getCollisionAlgorithmCreateFunc(w0->getCollisionShape()->getShapeType(),
                                                         w1->getCollisionShape()->getShapeType());
            return bullet->CreateCollisionAlgorithm(ci, w0, w1);
        }
        void* memory = ci.m_dispatcher1->allocateCollisionAlgorithm(sizeof(MergedBodyAlgorithm));
        return new (memory) MergedBodyAlgorithm(ci, w0, w1, side == 1, m_rules);
    }

  private:
    const CompoundRules& m_rules;
    btCollisionConfiguration& m_config;
    bool m_compoundFirst;
};

CompoundCollision::CompoundCollision(btCollisionDispatcher& dispatcher, btCollisionConfiguration& config,
                                     const CompoundRules& rules)
    : m_dispatcher(dispatcher), m_config(config), m_compoundFirst(std::make_unique<CreateFunc>(rules, config, true)),
      m_compoundSecond(std::make_unique<CreateFunc>(rules, config, false)) {
    for (int t = 0; t < MAX_BROADPHASE_COLLISION_TYPES; ++t) {
        dispatcher.registerCollisionCreateFunc(COMPOUND_SHAPE_PROXYTYPE, t, m_compoundFirst.get());
        if (t != COMPOUND_SHAPE_PROXYTYPE)
            dispatcher.registerCollisionCreateFunc(t, COMPOUND_SHAPE_PROXYTYPE, m_compoundSecond.get());
    }
}

CompoundCollision::~CompoundCollision() {
    for (int t = 0; t < MAX_BROADPHASE_COLLISION_TYPES; ++t) {
        m_dispatcher.registerCollisionCreateFunc(COMPOUND_SHAPE_PROXYTYPE, t,
                                                 m_config.getCollisionAlgorithmCreateFunc(COMPOUND_SHAPE_PROXYTYPE, t));
        m_dispatcher.registerCollisionCreateFunc(t, COMPOUND_SHAPE_PROXYTYPE,
                                                 m_config.getCollisionAlgorithmCreateFunc(t, COMPOUND_SHAPE_PROXYTYPE));
    }
}

} // namespace afb::bullet::detail
