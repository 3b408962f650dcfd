#pragma once
// Contacts of a merged ragdoll body (Method::mergeFixed: one btRigidBody with a btCompoundShape of its figure bodies'
// shapes) made as its bodies made them unmerged. Bullet's compound algorithm differs in two ways that matter here:
// it tests a child only where the child's bounding box overlaps the other object's, without the contact breaking
// threshold that speculative contacts widen (so a merged body's contacts start once they overlap), and it lets every
// child touch whatever the compound may touch (a hand that never collides with its own figure does, once merged
// with a forearm that does). This algorithm widens each child's test by the pair's speculative reach, gives each
// child against a convex object a manifold of its own with that reach from the first step, and lets a child touch a
// body of its own ragdoll only where the figure's self-collision pairs allow it (docs/performance.md).
#include <memory>

#include <btBulletCollisionCommon.h>

namespace afb::bullet::detail {

/// What the algorithm asks its world about the objects of a pair.
class CompoundRules {
  public:
    virtual ~CompoundRules() = default;
    /// Whether `compound` is a merged ragdoll body of this world (else Bullet's own compound algorithm runs).
    virtual bool handles(const btCollisionObject& compound) const = 0;
    /// Whether child `child` of the merged body `compound` may touch `other` (its child `otherChild`, or any part of
    /// it for -1): the figure's self-collision pairs within one ragdoll, anything else always.
    virtual bool mayTouch(const btCollisionObject& compound, int child, const btCollisionObject& other,
                          int otherChild) const = 0;
    /// The contact breaking threshold the world gives the pair's manifolds for a substep of `dt` seconds
    /// (speculative contacts: how far the two can close in it), metres.
    virtual btScalar breakingThreshold(const btCollisionObject& a, const btCollisionObject& b, btScalar dt) const = 0;
};

/// Installs the merged-body algorithm for every pair with a compound in `dispatcher` while it lives (pairs whose
/// compound `rules` does not handle get Bullet's algorithm from `config`), and restores `config`'s on destruction.
/// Destroy it after the ragdolls whose pairs use it.
class CompoundCollision {
  public:
    CompoundCollision(btCollisionDispatcher& dispatcher, btCollisionConfiguration& config, const CompoundRules& rules);
    ~CompoundCollision();
    CompoundCollision(const CompoundCollision&) = delete;
    CompoundCollision& operator=(const CompoundCollision&) = delete;

    class CreateFunc;

  private:
    btCollisionDispatcher& m_dispatcher;
    btCollisionConfiguration& m_config;
    std::unique_ptr<CreateFunc> m_compoundFirst, m_compoundSecond;
};

} // namespace afb::bullet::detail
