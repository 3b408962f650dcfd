#pragma once
// Replays of drops as glTF 2.0 binaries (`afb drop --gltf FILE.glb`), written through assimp's exporter, so a drop
// opens in Blender or any glTF viewer. Tools only (library afbullet_gltf, not installed): the game library knows
// nothing of assimp.
//
// The file holds, under one root node named after the figure:
//   ground    a square at y = 0 under everything the bodies reached (1 m margin);
//   skeleton  the md5 joints as nodes (parents as in the md5mesh) and the node "mesh": every md5 sub-mesh, skinned
//             to every md5 joint (a skin of all the joints, inverse bind matrices from the md5mesh bind pose);
//   bodies    one node per body (centre of mass, principal axes) with its exact collision polytope as a mesh: a
//             separate tree, so a viewer can hide the hulls and keep the skinned mesh, or the reverse.
// and one animation, "drop": frame k of the recording at t = k · frameSeconds (frame 0: the spawn, before the first
// step), a translation and a rotation key per frame for every joint node (parent-relative; the md5 root joints relative
// to the root node, i.e. in the world) and every body node (world), linear interpolation. So a drop of N steps has N +
// 1 keys per channel and lasts N · frameSeconds.
//
// Units: metres. Axes: Doom and the drop are Z-up (X forward, Y left); glTF is Y-up with +Z forward and +X left. Every
// point p becomes P·p and every rotation R becomes P·R·Pᵀ with the proper rotation
//     P: (x, y, z)_Doom ↦ (y, z, x)_glTF,
// so Doom's up (+Z) is glTF's up (+Y), Doom's forward (+X) is glTF's forward (+Z) and Doom's left (+Y) is glTF's +X.
//
// Skinning: glTF blends at most four joint transforms about one bind-pose vertex (linear blend skinning); md5 gives
// every weight its own offset (docs/format.md §7.3). The bind vertex is the md5 vertex in the md5mesh bind pose, and
// each vertex keeps its four largest joint weights (weights on one joint summed), renormalised. That is exact for every
// vertex with at most four weights whose offsets are one bind-pose point seen from each joint (as exporters write
// them), and an approximation otherwise. The joint nodes themselves are exact (driveSkeleton).
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "afb/decl/Md5Mesh.h"
#include "afb/figure/Figure.h"
#include "afb/sim/Drop.h"

namespace afb::sim {

/// A drop's first instance, frame by frame, as runDrop's observer saw it.
struct DropRecording {
    double frameSeconds = 1.0 / 60.0; ///< time between frames: one step, s
    /// Frame k (0: the spawn, k: after step k): every body's frame (centre of mass, principal axes), world space,
    /// metres, Z up, in body order.
    std::vector<std::vector<figure::Transform>> frames;
};

/// An observer for runDrop that appends every frame to `recording` (which must outlive the run) and sets its
/// frameSeconds to 1 / `hz`.
DropObserver recordInto(DropRecording& recording, double hz);

/// What writeGltfReplay did.
struct GltfReplayResult {
    std::optional<std::string> error; ///< set when no file was written (bad input, or assimp's message)
    int frames = 0;                   ///< animation keys per channel
    int joints = 0;                   ///< skin joints: every md5 joint (0 when the mesh has no vertices)
    int bodies = 0;                   ///< body nodes
    /// Frames left out: the recording from the first frame with a non-finite or absurd pose (|x| > 1e6 m, an
    /// exploded drop) on, which a float glTF file cannot hold.
    int framesDropped = 0;
};

/// Writes `recording` of a drop of `figure` (whose skeleton was built from `mesh`) to `path` as a glTF 2.0 binary
/// (.glb), laid out as described above. Never throws and never crashes on bad input: an inconsistent input (a frame
/// without one transform per body, a mesh whose joints are not the figure's, an index out of range) or a failed
/// export gives an error and no file.
GltfReplayResult writeGltfReplay(const figure::Figure& figure, const decl::Md5Mesh& mesh,
                                 const DropRecording& recording, const std::filesystem::path& path);

} // namespace afb::sim
