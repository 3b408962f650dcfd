// RagdollWorld's owner table: which ragdoll owns a Bullet collision object (RagdollWorld.h).
#include <algorithm>
#include <bit>
#include <cstdint>

#include "afb/bullet/RagdollWorld.h"

namespace afb::bullet {

namespace {
// A removed entry's key: the slot stays taken for the probes that passed it (no object lives at this address).
const char kRemovedKey = 0;
const btCollisionObject* removed() { return reinterpret_cast<const btCollisionObject*>(&kRemovedKey); }
} // namespace

std::size_t RagdollWorld::OwnerTable::slotOf(const btCollisionObject* body) const {
    // Fibonacci hashing of the address (its low bits are the allocator's alignment).
    const auto key = static_cast<std::uint64_t>(reinterpret_cast<std::uintptr_t>(body) >> 4);
    return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ULL) >> m_shift);
}

const RagdollWorld::BodyOwner* RagdollWorld::OwnerTable::find(const btCollisionObject* body) const {
    if (m_count == 0 || body == nullptr) return nullptr;
    const std::size_t mask = m_slots.size() - 1;
    for (std::size_t i = slotOf(body);; i = (i + 1) & mask) {
        const BodyOwner& s = m_slots[i];
        if (s.body == body) return &s;
        if (s.body == nullptr) return nullptr;
    }
}

void RagdollWorld::OwnerTable::insert(const BodyOwner& owner) {
    if (2 * (m_count + m_removed + 1) > m_slots.size()) rehash();
    const std::size_t mask = m_slots.size() - 1;
    BodyOwner* reuse = nullptr; // the first removed entry on the way, taken if the body is not further on
    for (std::size_t i = slotOf(owner.body);; i = (i + 1) & mask) {
        BodyOwner& s = m_slots[i];
        if (s.body == owner.body) return;
        if (s.body == removed() && reuse == nullptr) reuse = &s;
        if (s.body == nullptr) {
            if (reuse != nullptr) --m_removed;
            *(reuse != nullptr ? reuse : &s) = owner;
            ++m_count;
            return;
        }
    }
}

void RagdollWorld::OwnerTable::rehash() {
    // At most a third taken by live entries afterwards (the removed ones are dropped).
    const std::size_t size = std::max<std::size_t>(16, std::bit_ceil(3 * (m_count + 1)));
    std::vector<BodyOwner> old(size, BodyOwner{nullptr, -1, 0});
    old.swap(m_slots);
    m_shift = 64 - std::countr_zero(m_slots.size());
    m_count = m_removed = 0;
    for (const BodyOwner& o : old)
        if (o.ragdoll >= 0) insert(o);
}

void RagdollWorld::OwnerTable::removeRagdoll(int index, bool renumber, std::vector<const btCollisionObject*>& bodies) {
    for (const BodyOwner& o : m_slots)
        if (o.ragdoll == index) bodies.push_back(o.body);
    // One pass over the slots, without branches on their contents (empty and removed slots hold ragdoll −1, which
    // is neither `index` nor above it): the ragdoll's entries become removed keys, later ragdolls' indices go down.
    std::size_t gone = 0;
    for (BodyOwner& o : m_slots) {
        const bool mine = o.ragdoll == index;
        const int down = renumber && o.ragdoll > index ? 1 : 0;
        o.body = mine ? removed() : o.body;
        o.ragdoll = mine ? -1 : o.ragdoll - down;
        gone += mine ? 1 : 0;
    }
    m_count -= gone;
    m_removed += gone;
}

} // namespace afb::bullet
