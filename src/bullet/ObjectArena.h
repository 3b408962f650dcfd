// One ragdoll's Bullet objects (bodies, constraints, joint feedback) in a few blocks instead of one heap allocation
// each: spawning the humanoid made about 60 of them (Bullet's aligned allocator per object), a third of the spawn's
// allocator work. Internal to the bullet layer (Ragdoll).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <utility>
#include <vector>

namespace afb::bullet::detail {

/// Objects constructed in place in blocks this arena owns, destroyed in the reverse order of their construction
/// by clear() or the destructor. Blocks are never moved, so an object's address holds until it is destroyed.
class ObjectArena {
  public:
    /// `firstBlock`: bytes of the first block, `objects`: how many objects to expect (what the previous instance
    /// of the same figure used, say); later blocks are as large as the request or the first block, whichever is
    /// larger.
    explicit ObjectArena(std::size_t firstBlock = 0, std::size_t objects = 0)
        : m_next(std::max<std::size_t>(firstBlock, kMinBlock)) {
        m_objects.reserve(objects);
    }
    ~ObjectArena() { clear(); }
    ObjectArena(const ObjectArena&) = delete;
    ObjectArena& operator=(const ObjectArena&) = delete;

    /// A new T(args...) owned by the arena.
    template <typename T, typename... Args>
    T* make(Args&&... args) {
        void* at = allocate(sizeof(T), std::max<std::size_t>(alignof(T), kAlign));
        roomForOne(); // before the construction, so that pushing cannot throw after it
        T* object = ::new (at) T(std::forward<Args>(args)...);
        m_objects.push_back({object, [](void* p) { static_cast<T*>(p)->~T(); }});
        return object;
    }

    /// Takes over an object made elsewhere (deleted, not destroyed in place, by clear()).
    template <typename T>
    T* adopt(std::unique_ptr<T> object) {
        roomForOne();
        T* raw = object.release();
        m_objects.push_back({raw, [](void* p) { delete static_cast<T*>(p); }});
        return raw;
    }

    /// Destroys every object (last made first); the first block is kept for the next objects.
    void clear() {
        for (auto it = m_objects.rbegin(); it != m_objects.rend(); ++it) it->destroy(it->object);
        m_objects.clear();
        if (m_blocks.size() > 1) m_blocks.erase(m_blocks.begin() + 1, m_blocks.end());
        m_used = m_usedBefore = 0;
    }

    /// Bytes taken by the objects made so far (with alignment padding), over every block, and their count.
    std::size_t bytesUsed() const { return m_usedBefore + m_used; }
    std::size_t objectCount() const { return m_objects.size(); }

  private:
    static constexpr std::size_t kAlign = 16; // Bullet's aligned classes (btRigidBody, constraints) need 16
    static constexpr std::size_t kMinBlock = 1024;
    struct Free {
        void operator()(std::byte* p) const { ::operator delete[](p, std::align_val_t(kAlign)); }
    };
    struct Block {
        std::unique_ptr<std::byte[], Free> bytes;
        std::size_t size;
    };
    struct Object {
        void* object;
        void (*destroy)(void*);
    };

    void roomForOne() {
        if (m_objects.size() == m_objects.capacity())
            m_objects.reserve(std::max<std::size_t>(16, 2 * m_objects.size()));
    }

    // The offset in `block` of the first `align`-aligned address at or after offset `from`.
    static std::size_t alignedOffset(const Block& block, std::size_t from, std::size_t align) {
        const auto base = reinterpret_cast<std::uintptr_t>(block.bytes.get());
        return static_cast<std::size_t>((base + from + align - 1) / align * align - base);
    }

    void* allocate(std::size_t size, std::size_t align) {
        if (!m_blocks.empty()) {
            const std::size_t at = alignedOffset(m_blocks.back(), m_used, align);
            if (at + size <= m_blocks.back().size) {
                m_used = at + size;
                return m_blocks.back().bytes.get() + at;
            }
        }
        const std::size_t bytes = std::max(m_next, size + align); // room for the object wherever the block starts
        Block b{std::unique_ptr<std::byte[], Free>(
                    static_cast<std::byte*>(::operator new[](bytes, std::align_val_t(kAlign)))),
                bytes};
        m_usedBefore = bytesUsed();
        m_blocks.push_back(std::move(b));
        const std::size_t at = alignedOffset(m_blocks.back(), 0, align);
        m_used = at + size;
        return m_blocks.back().bytes.get() + at;
    }

    std::vector<Block> m_blocks;
    std::vector<Object> m_objects;
    std::size_t m_next;           // size of a new block
    std::size_t m_used = 0;       // bytes used in the last block
    std::size_t m_usedBefore = 0; // bytes used in the blocks before it
};

} // namespace afb::bullet::detail
