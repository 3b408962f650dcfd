#pragma once
// Value types and parser for `.md5anim` files (docs/format.md §7.4): what the file says, nothing more.
//
// In particular the root translation is kept as written. The engine's anim loader subtracts the baseframe
// root translation from the animated root components and then zeroes the baseframe root translation
// (docs/format.md §7.4, §8 item 19); that meaning belongs to the layer that builds poses from an anim, not to this
// value type.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "afb/decl/Af.h"
#include "afb/decl/Md5Mesh.h"
#include "afb/text/Diagnostics.h"

namespace afb::decl {

/// Bits of Md5HierarchyEntry::flags: which components of a joint a frame overrides (ANIM_TX … ANIM_QZ).
/// Set components are read from the frame in this order, starting at the joint's startIndex.
enum Md5ComponentBit : int {
    kMd5Tx = 1 << 0,        ///< translation x
    kMd5Ty = 1 << 1,        ///< translation y
    kMd5Tz = 1 << 2,        ///< translation z
    kMd5Qx = 1 << 3,        ///< quaternion x
    kMd5Qy = 1 << 4,        ///< quaternion y
    kMd5Qz = 1 << 5,        ///< quaternion z
    kMd5AllComponents = 63, ///< every component; flags never hold other bits
};

/// One line of the `hierarchy { }` block.
struct Md5HierarchyEntry {
    /// Joint name as written; must equal the mesh's joint name case-sensitively (docs/format.md §7.4).
    std::string name;
    int parent = -1;    ///< parent index, lower than this joint's index; -1 only for joint 0
    int flags = 0;      ///< Md5ComponentBit set: components animated by the frames (0..63)
    int startIndex = 0; ///< index in each frame of the joint's first animated component
    /// Equal when every field is.
    bool operator==(const Md5HierarchyEntry&) const = default;
};

/// One line of the `bounds { }` block: the model's bounding box in one frame.
struct Md5Bounds {
    Vec3 min; ///< minimum corner, model space, Doom units
    Vec3 max; ///< maximum corner, model space, Doom units
    /// Equal when every field is.
    bool operator==(const Md5Bounds&) const = default;
};

/// One line of the `baseframe { }` block: a joint's values for the components its flags do not animate.
struct Md5BaseJoint {
    Vec3 position;    ///< translation relative to the parent joint (root: model-relative), Doom units, as written
    Vec3 orientation; ///< parent-relative orientation qx, qy, qz as written (w = +sqrt(|1-x²-y²-z²|); docs/format.md
                      ///< §7.3)
    /// Equal when every field is.
    bool operator==(const Md5BaseJoint&) const = default;
};

/// A whole `.md5anim` file.
struct Md5Anim {
    int version = 10;                         ///< `MD5Version`, always 10 once parsed
    std::string commandline;                  ///< `commandline` string as written (exporter notes)
    int frameRate = 24;                       ///< frames per second, >= 0 (0: a still pose)
    int numAnimatedComponents = 0;            ///< floats per frame, 0..6 × joints
    std::vector<Md5HierarchyEntry> hierarchy; ///< one entry per joint, in joint order
    std::vector<Md5Bounds> bounds;            ///< one box per frame
    std::vector<Md5BaseJoint> baseframe;      ///< one entry per joint; root translation NOT zeroed (see above)
    std::vector<std::vector<double>> frames;  ///< `frame k` values, each numAnimatedComponents long, k = index
    /// Where each line of the `hierarchy` block is written (its joint name), one per joint once parsed; empty for
    /// an anim built in code. Not part of equality.
    std::vector<text::SourceLocation> hierarchyLocations;
    /// Equal when every field but hierarchyLocations is.
    bool operator==(const Md5Anim& other) const {
        return version == other.version && commandline == other.commandline && frameRate == other.frameRate &&
               numAnimatedComponents == other.numAnimatedComponents && hierarchy == other.hierarchy &&
               bounds == other.bounds && baseframe == other.baseframe && frames == other.frames;
    }
};

/// Number of bits set in Md5HierarchyEntry::flags: how many components the joint reads from each frame.
int animatedComponentCount(int flags);

/// The first way `anim`'s hierarchy differs from `mesh`'s joints (joint count, names compared
/// case-sensitively, parent indices), as the engine's CheckModelHierarchy checks them (docs/format.md §7.4);
/// nullopt when they match.
std::optional<std::string> hierarchyMismatch(const Md5Anim& anim, const Md5Mesh& mesh);

/// hierarchyMismatch as a diagnostic: an error at the anim's line of the first joint that differs, naming the
/// mesh's line of that joint (for a joint count that differs: at the first joint one file has and the other
/// lacks, else without a position); `context` prefixes the message. nullopt when they match.
std::optional<text::Diagnostic> hierarchyMismatchDiagnostic(const Md5Anim& anim, const Md5Mesh& mesh,
                                                            const std::string& context);

/// Parses `.md5anim` text. Every count, index and reference is checked (docs/format.md §7.4); on any error:
/// nullopt, with a `file:line:col` error in `diagnostics` — nothing is half-loaded. `fileName` is used in
/// locations only.
std::optional<Md5Anim> parseMd5Anim(std::string_view text, const std::string& fileName, text::Diagnostics& diagnostics);

/// Reads and parses one `.md5anim` file.
std::optional<Md5Anim> loadMd5Anim(const std::filesystem::path& path, text::Diagnostics& diagnostics);

/// Canonical `.md5anim` text of `anim`, in the layout and number form of writeMd5Mesh; each frame has one
/// line per animated joint (a line starts at every startIndex). numFrames and numJoints are the vector sizes.
/// `parseMd5Anim(writeMd5Anim(a)) == a` for every `a` that parseMd5Anim can produce. Throws
/// std::invalid_argument when a string cannot be written (see writeMd5Mesh), when baseframe and hierarchy or
/// bounds and frames differ in length, or when a frame does not hold numAnimatedComponents values.
std::string writeMd5Anim(const Md5Anim& anim);

} // namespace afb::decl
