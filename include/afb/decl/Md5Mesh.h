#pragma once
// Value types and parser for `.md5mesh` files (docs/format.md §7.3): what the file says, nothing more. Joint
// transforms stay in the file's Doom conventions (model-space bind pose, quaternion w left implicit); the
// figure layer converts them (docs/format.md §0, §8 item 21).
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "afb/decl/Af.h"
#include "afb/text/Diagnostics.h"

namespace afb::decl {

/// One line of the `joints { }` block: a joint of the bind pose.
struct Md5Joint {
    std::string name; ///< as written; looked up case-insensitively, first match wins (see findJoint)
    int parent = -1;  ///< index of the parent joint, always lower than this joint's index; -1 for a root
    Vec3 position;    ///< bind position in model space (absolute, not parent-relative), Doom units
    Vec3 orientation; ///< bind orientation in model space: qx, qy, qz as written (w = +sqrt(|1-x²-y²-z²|),
                      ///< docs/format.md §7.3)
    /// Equal when every field is.
    bool operator==(const Md5Joint&) const = default;
};

/// One `vert` line: texture coordinates and the vertex's range in its mesh's weight list.
struct Md5Vert {
    double s = 0;        ///< texture coordinate s (horizontal) as written
    double t = 0;        ///< texture coordinate t (vertical) as written
    int firstWeight = 0; ///< index of the vertex's first weight in Md5SubMesh::weights
    int weightCount = 1; ///< number of consecutive weights, at least 1 (firstWeight + weightCount <= weights.size())
    /// Equal when every field is.
    bool operator==(const Md5Vert&) const = default;
};

/// One `tri` line: a triangle of the mesh.
struct Md5Tri {
    int v[3] = {0, 0, 0}; ///< indices into Md5SubMesh::verts, in the file's winding order
    /// Equal when every field is.
    bool operator==(const Md5Tri&) const = default;
};

/// One `weight` line: a joint's contribution to the vertices that use it.
struct Md5Weight {
    int joint = 0;   ///< index into Md5Mesh::joints
    double bias = 0; ///< blend factor as written (the engine does not renormalise biases)
    Vec3 offset;     ///< position in the joint's bind frame (joint-local), Doom units
    /// Equal when every field is.
    bool operator==(const Md5Weight&) const = default;
};

/// One `mesh { }` block: a surface with one material.
struct Md5SubMesh {
    std::string name;               ///< the optional `name` string; empty when absent
    std::string shader;             ///< material name as written
    std::vector<Md5Vert> verts;     ///< `vert` lines, in index order
    std::vector<Md5Tri> tris;       ///< `tri` lines, in index order
    std::vector<Md5Weight> weights; ///< `weight` lines, in index order
    /// Equal when every field is.
    bool operator==(const Md5SubMesh&) const = default;
};

/// A whole `.md5mesh` file: the bind-pose skeleton and its skinned surfaces.
struct Md5Mesh {
    int version = 10;               ///< `MD5Version`, always 10 once parsed
    std::string commandline;        ///< `commandline` string as written (exporter notes)
    std::vector<Md5Joint> joints;   ///< `joints` block, in file order; parents precede children
    std::vector<Md5SubMesh> meshes; ///< `mesh` blocks, in file order
    /// Where each line of the `joints` block is written (its joint name), one per joint once parsed; empty for a
    /// mesh built in code. Not part of equality.
    std::vector<text::SourceLocation> jointLocations;
    /// Equal when every field but jointLocations is.
    bool operator==(const Md5Mesh& other) const {
        return version == other.version && commandline == other.commandline && joints == other.joints &&
               meshes == other.meshes;
    }
};

/// Index of the first joint named `name`, compared ignoring ASCII case as the engine's GetJointHandle does
/// (docs/format.md §7.3, §8 item 22: a duplicate name is shadowed by the earlier joint); nullopt when absent.
std::optional<int> findJoint(const Md5Mesh& mesh, std::string_view name);

/// Number of vertices over all sub-meshes.
std::size_t totalVertCount(const Md5Mesh& mesh);
/// Number of triangles over all sub-meshes.
std::size_t totalTriCount(const Md5Mesh& mesh);
/// Number of weights over all sub-meshes.
std::size_t totalWeightCount(const Md5Mesh& mesh);

/// Parses `.md5mesh` text. Every count, index and reference is checked (docs/format.md §7.3); on any error:
/// nullopt, with a `file:line:col` error in `diagnostics` — nothing is half-loaded. `fileName` is used in
/// locations only.
std::optional<Md5Mesh> parseMd5Mesh(std::string_view text, const std::string& fileName, text::Diagnostics& diagnostics);

/// Reads and parses one `.md5mesh` file.
std::optional<Md5Mesh> loadMd5Mesh(const std::filesystem::path& path, text::Diagnostics& diagnostics);

/// Canonical `.md5mesh` text of `mesh`, laid out as the id exporters write it (one entry a line, blocks
/// indented with a tab); counts are the vector sizes. Every number is in its shortest fixed-point form that
/// reads back as exactly the same double (so a value rounded to d decimals prints with at most d decimals).
/// `parseMd5Mesh(writeMd5Mesh(m)) == m` for every `m` that parseMd5Mesh can produce. Throws
/// std::invalid_argument when a string holds a quote, a line break or a NUL byte (md5 strings have no
/// escapes).
std::string writeMd5Mesh(const Md5Mesh& mesh);

} // namespace afb::decl
