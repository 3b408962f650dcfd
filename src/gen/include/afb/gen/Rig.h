#pragma once
// A rigged, skinned model independent of its source format (afb gen): a joint hierarchy with its bind
// pose and surfaces whose vertices are weighted to joints. Loaded from an `.md5mesh` through our own reader or from
// any format assimp reads; written back as `.md5mesh` + a one-frame `af_pose.md5anim` with the decl writers.
// Everything here is in Doom units (1 unit = 0.0254 m by default), model space, Z up, X forward, standard column
// rotations (figure/Transform.h).
#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "afb/decl/Md5Anim.h"
#include "afb/decl/Md5Mesh.h"
#include "afb/figure/Transform.h"
#include "afb/text/Diagnostics.h"

namespace afb::gen {

/// Metres per Doom unit (one inch): the unit md5 and .af numbers are in.
inline constexpr double kMetresPerDoomUnit = 0.0254;

/// One joint of the bind pose.
struct RigJoint {
    std::string name;       ///< unique ignoring ASCII case, no quote or line break (md5 strings)
    int parent = -1;        ///< lower than this joint's index; -1 only for joint 0
    figure::Transform bind; ///< bind pose, model space, Doom units (a proper rotation, no scale)
};

/// One joint's share of a vertex.
struct RigInfluence {
    int joint = 0;     ///< index into Rig::joints
    double weight = 1; ///< > 0; a vertex's weights sum to 1
};

/// One skinned vertex at its bind position.
struct RigVertex {
    Eigen::Vector3d position = Eigen::Vector3d::Zero(); ///< model space, Doom units
    double s = 0, t = 0;                                ///< texture coordinates
    std::vector<RigInfluence> influences;               ///< at least one
};

/// One surface (one material).
struct RigSurface {
    std::string name;
    std::string material;
    std::vector<RigVertex> vertices;
    std::vector<std::array<int, 3>> triangles; ///< indices into vertices
};

/// How importRig turned a model's units and axes into Doom units, Z up: what `afb gen` reports.
struct RigUnits {
    /// Where the scale came from.
    enum class Source {
        Format,   ///< the format's default (md5 0.0254, glTF 1, FBX its unit scale factor, others 0.0254)
        Option,   ///< ImportOptions::metresPerUnit
        Height,   ///< ImportOptions::heightM
        Detected, ///< an md5mesh too small for Doom units, read as metres (ImportOptions)
    };
    double metresPerUnit = 0.0254; ///< metres per unit of the file, as used
    Source source = Source::Format;
    double fileHeight = 0; ///< the model's height in its file's units: the largest extent of its joints and vertices
    char up = 'z';         ///< the file's up axis as used: 'y' or 'z'
};

/// A whole rig. Invariants (checked by the loaders): at least one joint, joint 0 is the only root, parents precede
/// children, every index is in range, every vertex has an influence.
struct Rig {
    std::vector<RigJoint> joints;
    std::vector<RigSurface> surfaces;
    /// Set when the rig came from an md5mesh: that mesh, re-indexed if a root joint "origin" was inserted. It is
    /// written back as is (its weights keep their own offsets).
    std::optional<decl::Md5Mesh> md5;
    RigUnits units; ///< how the file's units and axes were read (set by importRig)
};

/// How a model's coordinates become Doom units, Z up.
struct ImportOptions {
    /// Metres per model unit; default by format: md5 0.0254, glTF 1, FBX 0.01 × its UnitScaleFactor, others 0.0254
    /// (game-scale models, as the Doom, Quake and DirectX exporters wrote them). An md5mesh under
    /// kMd5MetresBelowM tall at 0.0254 is read as metres instead (RigUnits::Source::Detected).
    std::optional<double> metresPerUnit;
    /// Scale the model so its bind pose is this tall (largest extent of joints and vertices), metres; wins over
    /// metresPerUnit.
    std::optional<double> heightM;
    /// The model's up axis: 'y' (assimp's convention, default for everything but md5: the model's Y becomes Doom's
    /// Z and its Z Doom's X, forward) or 'z' (md5's default: axes kept).
    std::optional<char> up;
};

/// An md5mesh whose height (RigUnits::fileHeight) at Doom's 0.0254 m per unit is under this many metres is read as
/// authored in metres, Blender's unit (its md5 exporters write Blender units as they are): no Doom figure is
/// that small, and a metre figure of that many units is a large one.
inline constexpr double kMd5MetresBelowM = 0.2;

/// The rig of an md5mesh: vertex positions skinned in the bind pose. A root joint "origin" at the identity is put
/// first when the mesh has no joint of that name (Doom's base body drives the first child of "origin").
Rig rigFromMd5(const decl::Md5Mesh& mesh);

/// The same in Doom units, Z up, from the mesh's own units and up axis as `options` give them or as detected
/// (kMd5MetresBelowM); the md5 written back is scaled and turned alike. An error naming `label` when the model is
/// over 100 m at that scale, or has no extent and `options.heightM` asks for one.
std::optional<Rig> rigFromMd5(const decl::Md5Mesh& mesh, const ImportOptions& options, const std::string& label,
                              text::Diagnostics& diagnostics);

/// Reads a rigged model: `.md5mesh` through decl::loadMd5Mesh, anything else through assimp, defensively (the scene
/// is validated and every index checked before use; assimp's exceptions are caught). A model without a bone gets
/// an error. nullopt on any error, with a message naming the file in `diagnostics`.
std::optional<Rig> importRig(const std::filesystem::path& path, const ImportOptions& options,
                             text::Diagnostics& diagnostics);

/// The post-processing steps (aiPostProcessSteps flags) importRig asks assimp for.
unsigned assimpPostProcessSteps();

/// Like importRig for a model in memory (`hint`: the file extension without the dot, e.g. "glb"); for the fuzzer.
std::optional<Rig> importRigFromMemory(const void* data, std::size_t size, const std::string& hint,
                                       const ImportOptions& options, text::Diagnostics& diagnostics);

/// The md5mesh of `rig`: `rig.md5` when set, else one mesh per surface, every vertex one weight per influence
/// with offsets from the bind pose (so skinning the written file in the bind pose gives the vertex back).
decl::Md5Mesh toMd5Mesh(const Rig& rig, const std::string& commandline);

/// The one-frame `af_pose` of `rig`'s bind pose: nothing animated, the baseframe parent-relative (docs/format.md §7.4).
decl::Md5Anim bindPoseAnim(const Rig& rig, const std::string& commandline);

/// The md5 quaternion components (x, y, z) of a standard rotation: the conjugate, w made non-negative (docs/format.md
/// §7.3).
Eigen::Vector3d md5Orientation(const Eigen::Matrix3d& rotation);

/// The model's size: the largest extent of its vertices' bounding box (of its joints' when it has no vertex),
/// Doom units.
double modelHeight(const Rig& rig);

/// Bind-pose positions of every vertex of an md5mesh (Σ bias·(p_j + R_j·offset)), surface by surface, Doom units.
std::vector<std::vector<Eigen::Vector3d>> skinnedBindVertices(const decl::Md5Mesh& mesh);

} // namespace afb::gen
