// gen::importRig: md5 through our own reader, every other format through assimp. assimp 5.2.5 crashes on some
// malformed files and trusts its own indices, so nothing of its scene is used before it is checked here: pointers,
// counts, vertex and bone indices, node names, finite numbers, and the node tree (depth-limited, cycle-free).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <functional>
#include <map>
#include <set>
#include <stdexcept>
#include <string>

#include <Eigen/SVD>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "afb/detail/Lexer.h"
#include "afb/gen/Rig.h"

// Debian's assimp is built with its internal asserts on (ASSIMP_BUILD_DEBUG), and its handler aborts the process:
// malformed files reach them (the fuzzer found `out_idx != nullptr` in FBXConverter.cpp:1523). The library calls
// this function through its PLT, so defining it here replaces that handler in every program that links the
// generator: a failed assert throws, assimp's importer catches it as a failed import (its own try around each
// format reader), and whatever escapes reaches the try in importRig/importRigFromMemory. The declaration in
// <assimp/ai_assert.h> exists only in debug builds of assimp, so it is repeated here with the same signature.
namespace Assimp {
[[gnu::visibility("default")]] void aiAssertViolation(const char* failedExpression, const char* file, int line);
void aiAssertViolation(const char* failedExpression, const char* file, int line) {
    throw std::runtime_error(std::string("assimp's internal check failed: ") +
                             (failedExpression ? failedExpression : "?") + " (" + (file ? file : "?") + ":" +
                             std::to_string(line) + ")");
}
} // namespace Assimp

namespace afb::gen {
namespace {

constexpr int kMaxNodeDepth = 1024;
constexpr std::size_t kMaxNodes = 1u << 20;

struct ImportError {
    std::string message;
};

Eigen::Matrix4d toEigen(const aiMatrix4x4& m) {
    Eigen::Matrix4d e;
    e << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3, m.d4;
    if (!e.allFinite()) throw ImportError{"a transform holds a non-finite number"};
    return e;
}

// A rigid transform from an affine one: the nearest rotation (polar decomposition, a mirror folded into a proper
// rotation) and the translation. md5 joints carry no scale; the vertices keep theirs.
figure::Transform rigidPart(const Eigen::Matrix4d& m) {
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(m.topLeftCorner<3, 3>(), Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d u = svd.matrixU();
    const Eigen::Matrix3d v = svd.matrixV();
    if ((u * v.transpose()).determinant() < 0) u.col(2) = -u.col(2);
    figure::Transform t{u * v.transpose(), m.topRightCorner<3, 1>()};
    if (!t.rotation.allFinite() || svd.singularValues()(0) <= 0) throw ImportError{"a joint transform is degenerate"};
    return t;
}

// A joint name md5 text can hold (no quote, line break or NUL), unique ignoring case.
std::string md5Name(std::string name, std::set<std::string>& taken) {
    for (char& c : name)
        if (c == '"' || c == '\n' || c == '\r' || c == '\0' || static_cast<unsigned char>(c) < 0x20) c = '_';
    if (name.empty()) name = "joint";
    std::string unique = name;
    for (int k = 2; taken.count(text::lowerAscii(unique)); ++k) unique = name + "_" + std::to_string(k);
    taken.insert(text::lowerAscii(unique));
    return unique;
}

struct NodeInfo {
    const aiNode* node = nullptr;
    int parent = -1;
    Eigen::Matrix4d global = Eigen::Matrix4d::Identity();
};

// The node tree flattened depth-first (parents first), with global transforms. Throws on a cycle, a null child or
// a tree too deep or too large.
std::vector<NodeInfo> flattenNodes(const aiScene& scene) {
    std::vector<NodeInfo> nodes;
    std::set<const aiNode*> seen;
    std::function<void(const aiNode*, int, int)> visit = [&](const aiNode* n, int parent, int depth) {
        if (!n) throw ImportError{"the node tree holds a null node"};
        if (depth > kMaxNodeDepth || nodes.size() >= kMaxNodes)
            throw ImportError{"the node tree is too deep or too large"};
        if (!seen.insert(n).second) throw ImportError{"the node tree holds a cycle"};
        const Eigen::Matrix4d local = toEigen(n->mTransformation);
        const Eigen::Matrix4d global = parent >= 0 ? nodes[static_cast<std::size_t>(parent)].global * local : local;
        const int self = static_cast<int>(nodes.size());
        nodes.push_back({n, parent, global});
        if (n->mNumChildren > 0 && !n->mChildren) throw ImportError{"a node's child list is missing"};
        for (unsigned i = 0; i < n->mNumChildren; ++i) visit(n->mChildren[i], self, depth + 1);
    };
    visit(scene.mRootNode, -1, 0);
    return nodes;
}

// Every mesh, bone and weight pointer and index, checked before anything is read.
void validateScene(const aiScene& scene) {
    if (!scene.mRootNode) throw ImportError{"the scene has no root node"};
    if (scene.mNumMeshes > 0 && !scene.mMeshes) throw ImportError{"the scene's mesh list is missing"};
    for (unsigned mi = 0; mi < scene.mNumMeshes; ++mi) {
        const aiMesh* m = scene.mMeshes[mi];
        if (!m) throw ImportError{"mesh " + std::to_string(mi) + " is missing"};
        if (m->mNumVertices > 0 && !m->mVertices) throw ImportError{"mesh " + std::to_string(mi) + " has no vertices"};
        for (unsigned v = 0; v < m->mNumVertices; ++v)
            if (!std::isfinite(m->mVertices[v].x) || !std::isfinite(m->mVertices[v].y) ||
                !std::isfinite(m->mVertices[v].z))
                throw ImportError{"mesh " + std::to_string(mi) + " has a non-finite vertex"};
        if (m->mNumFaces > 0 && !m->mFaces) throw ImportError{"mesh " + std::to_string(mi) + " has no face list"};
        for (unsigned f = 0; f < m->mNumFaces; ++f) {
            const aiFace& face = m->mFaces[f];
            if (face.mNumIndices > 0 && !face.mIndices)
                throw ImportError{"a face of mesh " + std::to_string(mi) + " has no indices"};
            for (unsigned k = 0; k < face.mNumIndices; ++k)
                if (face.mIndices[k] >= m->mNumVertices)
                    throw ImportError{"a face of mesh " + std::to_string(mi) + " indexes vertex " +
                                      std::to_string(face.mIndices[k]) + " of " + std::to_string(m->mNumVertices)};
        }
        if (m->mNumBones > 0 && !m->mBones) throw ImportError{"mesh " + std::to_string(mi) + " has no bone list"};
        for (unsigned b = 0; b < m->mNumBones; ++b) {
            const aiBone* bone = m->mBones[b];
            if (!bone) throw ImportError{"a bone of mesh " + std::to_string(mi) + " is missing"};
            if (bone->mNumWeights > 0 && !bone->mWeights)
                throw ImportError{"bone " + std::string(bone->mName.C_Str()) + " has no weight list"};
            for (unsigned w = 0; w < bone->mNumWeights; ++w)
                if (bone->mWeights[w].mVertexId >= m->mNumVertices || !std::isfinite(bone->mWeights[w].mWeight))
                    throw ImportError{"bone " + std::string(bone->mName.C_Str()) + " weights vertex " +
                                      std::to_string(bone->mWeights[w].mVertexId) + " of " +
                                      std::to_string(m->mNumVertices) + " (or a non-finite weight)"};
            (void)toEigen(bone->mOffsetMatrix);
        }
    }
}

std::optional<double> metaDouble(const aiScene& scene, const char* key) {
    if (!scene.mMetaData) return std::nullopt;
    for (unsigned i = 0; i < scene.mMetaData->mNumProperties; ++i) {
        if (!scene.mMetaData->mKeys || !scene.mMetaData->mValues) return std::nullopt;
        if (std::string(scene.mMetaData->mKeys[i].C_Str()) != key) continue;
        const aiMetadataEntry& e = scene.mMetaData->mValues[i];
        if (!e.mData) return std::nullopt;
        if (e.mType == AI_FLOAT) return static_cast<double>(*static_cast<const float*>(e.mData));
        if (e.mType == AI_DOUBLE) return *static_cast<const double*>(e.mData);
        if (e.mType == AI_INT32) return static_cast<double>(*static_cast<const int32_t*>(e.mData));
    }
    return std::nullopt;
}

// The scene's nodes flattened, by name, and the node of each mesh.
struct SceneIndex {
    std::vector<NodeInfo> nodes;
    std::map<std::string, int> nodeByName; // first node of a name, as assimp's own lookups
    std::vector<int> meshNode;             // per mesh, the first node that holds it (−1: none)

    Eigen::Matrix4d meshGlobal(unsigned mesh) const {
        return meshNode[mesh] >= 0 ? nodes[static_cast<std::size_t>(meshNode[mesh])].global
                                   : Eigen::Matrix4d::Identity();
    }
};

SceneIndex indexScene(const aiScene& scene) {
    SceneIndex index;
    index.nodes = flattenNodes(scene);
    for (std::size_t i = 0; i < index.nodes.size(); ++i)
        index.nodeByName.emplace(index.nodes[i].node->mName.C_Str(), static_cast<int>(i));
    index.meshNode.assign(scene.mNumMeshes, -1);
    for (std::size_t i = 0; i < index.nodes.size(); ++i) {
        const aiNode* n = index.nodes[i].node;
        if (n->mNumMeshes > 0 && !n->mMeshes) throw ImportError{"a node's mesh list is missing"};
        for (unsigned k = 0; k < n->mNumMeshes; ++k) {
            if (n->mMeshes[k] >= scene.mNumMeshes)
                throw ImportError{"a node names mesh " + std::to_string(n->mMeshes[k])};
            if (index.meshNode[n->mMeshes[k]] < 0) index.meshNode[n->mMeshes[k]] = static_cast<int>(i);
        }
    }
    return index;
}

// Bone nodes and their bind transforms: the mesh node's transform after the inverse of the bone's offset.
std::map<int, figure::Transform> boneBinds(const aiScene& scene, const SceneIndex& index) {
    std::map<int, figure::Transform> boneBind;
    for (unsigned mi = 0; mi < scene.mNumMeshes; ++mi) {
        const aiMesh* m = scene.mMeshes[mi];
        const Eigen::Matrix4d meshGlobal = index.meshGlobal(mi);
        for (unsigned b = 0; b < m->mNumBones; ++b) {
            const auto it = index.nodeByName.find(m->mBones[b]->mName.C_Str());
            if (it == index.nodeByName.end())
                throw ImportError{"bone \"" + std::string(m->mBones[b]->mName.C_Str()) + "\" names no node"};
            const Eigen::Matrix4d offset = toEigen(m->mBones[b]->mOffsetMatrix);
            if (std::abs(offset.topLeftCorner<3, 3>().determinant()) < 1e-12)
                throw ImportError{"bone \"" + std::string(m->mBones[b]->mName.C_Str()) + "\" has a singular offset"};
            boneBind.emplace(it->second, rigidPart(meshGlobal * offset.inverse()));
        }
    }
    if (boneBind.empty()) throw ImportError{"the model has no bones: nothing to build a ragdoll from"};
    return boneBind;
}

// The skeleton's nodes: every bone node and its ancestors below the deepest node common to all of them (`top`).
struct SkeletonNodes {
    int top = -1;
    std::set<int> nodes;
};

SkeletonNodes skeletonNodes(const SceneIndex& index, const std::map<int, figure::Transform>& boneBind) {
    std::vector<std::vector<int>> paths;
    for (const auto& [node, bind] : boneBind) {
        std::vector<int> path;
        for (int n = node; n >= 0; n = index.nodes[static_cast<std::size_t>(n)].parent) path.push_back(n);
        std::reverse(path.begin(), path.end());
        paths.push_back(std::move(path));
    }
    std::size_t common = 0;
    while (std::all_of(paths.begin(), paths.end(),
                       [&](const std::vector<int>& p) { return common < p.size() && p[common] == paths[0][common]; }))
        ++common;
    SkeletonNodes out;
    out.top = paths[0][common - 1];
    for (const auto& p : paths) out.nodes.insert(p.begin() + static_cast<std::ptrdiff_t>(common - 1), p.end());
    return out;
}

// The rig's joints, parents first: an "origin" root unless the skeleton's top node is one, then every skeleton
// node at its bind transform (a bone's, else the node's own). `jointOfNode` receives each node's joint.
void addJoints(Rig& rig, const SceneIndex& index, const std::map<int, figure::Transform>& boneBind,
               const SkeletonNodes& skeleton, bool topIsOrigin, std::map<int, int>& jointOfNode) {
    std::set<std::string> taken;
    if (!topIsOrigin) rig.joints.push_back({md5Name("origin", taken), -1, {}});
    for (std::size_t i = 0; i < index.nodes.size(); ++i) {
        const int n = static_cast<int>(i);
        if (!skeleton.nodes.count(n)) continue;
        const int parent = n == skeleton.top ? (topIsOrigin ? -1 : 0) : jointOfNode.at(index.nodes[i].parent);
        figure::Transform bind;
        if (const auto it = boneBind.find(n); it != boneBind.end()) bind = it->second;
        else bind = rigidPart(index.nodes[i].global);
        jointOfNode[n] = static_cast<int>(rig.joints.size());
        rig.joints.push_back({md5Name(index.nodes[i].node->mName.C_Str(), taken), parent, bind});
    }
}

// Mesh `mi` as a surface: its name and material (quotes and control characters replaced), vertices in model
// space with their bone weights normalised (a vertex no bone weighs follows `rigidJoint`), triangles as fans.
RigSurface surfaceOf(const aiScene& scene, unsigned mi, const SceneIndex& index, const std::map<int, int>& jointOfNode,
                     int rigidJoint) {
    const aiMesh* m = scene.mMeshes[mi];
    const Eigen::Matrix4d meshGlobal = index.meshGlobal(mi);
    RigSurface surface;
    surface.name = m->mName.C_Str();
    if (scene.mMaterials && m->mMaterialIndex < scene.mNumMaterials && scene.mMaterials[m->mMaterialIndex]) {
        aiString matName;
        if (scene.mMaterials[m->mMaterialIndex]->Get(AI_MATKEY_NAME, matName) == AI_SUCCESS)
            surface.material = matName.C_Str();
    }
    for (std::string* s : {&surface.name, &surface.material})
        for (char& c : *s)
            if (c == '"' || static_cast<unsigned char>(c) < 0x20) c = '_';
    surface.vertices.resize(m->mNumVertices);
    for (unsigned v = 0; v < m->mNumVertices; ++v) {
        const aiVector3D& p = m->mVertices[v];
        surface.vertices[v].position = (meshGlobal * Eigen::Vector4d(p.x, p.y, p.z, 1.0)).head<3>();
        if (m->mTextureCoords[0] && m->mNumUVComponents[0] >= 2) {
            surface.vertices[v].s = std::isfinite(m->mTextureCoords[0][v].x) ? m->mTextureCoords[0][v].x : 0.0;
            surface.vertices[v].t = std::isfinite(m->mTextureCoords[0][v].y) ? 1.0 - m->mTextureCoords[0][v].y : 0.0;
        }
    }
    for (unsigned b = 0; b < m->mNumBones; ++b) {
        const int joint = jointOfNode.at(index.nodeByName.at(m->mBones[b]->mName.C_Str()));
        for (unsigned w = 0; w < m->mBones[b]->mNumWeights; ++w) {
            const aiVertexWeight& vw = m->mBones[b]->mWeights[w];
            if (vw.mWeight > 1e-6f) surface.vertices[vw.mVertexId].influences.push_back({joint, vw.mWeight});
        }
    }
    for (RigVertex& v : surface.vertices) {
        double sum = 0;
        for (const RigInfluence& in : v.influences) sum += in.weight;
        if (sum <= 0) v.influences = {{rigidJoint, 1.0}};
        else
            for (RigInfluence& in : v.influences) in.weight /= sum;
    }
    for (unsigned f = 0; f < m->mNumFaces; ++f) {
        const aiFace& face = m->mFaces[f];
        for (unsigned k = 2; k < face.mNumIndices; ++k) // a fan over polygons (triangulated already)
            surface.triangles.push_back({static_cast<int>(face.mIndices[0]), static_cast<int>(face.mIndices[k - 1]),
                                         static_cast<int>(face.mIndices[k])});
    }
    return surface;
}

// Scale (metres → Doom units, or to the requested height) and axes, applied once to joints and vertices; the
// units the rig was read in. `metres` is the format's metres per unit (before the options).
void scaleRig(Rig& rig, double metres, const Eigen::Matrix3d& axes, bool topIsOrigin, const ImportOptions& options) {
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
    for (const RigJoint& j : rig.joints) {
        lo = lo.cwiseMin(j.bind.position);
        hi = hi.cwiseMax(j.bind.position);
    }
    for (const RigSurface& s : rig.surfaces)
        for (const RigVertex& v : s.vertices) {
            lo = lo.cwiseMin(v.position);
            hi = hi.cwiseMax(v.position);
        }
    const double extent = (hi - lo).maxCoeff();
    if (!(extent > 0) || !std::isfinite(extent)) throw ImportError{"the model has no extent"};
    if (options.heightM) metres = *options.heightM / extent;
    const double scale = metres / kMetresPerDoomUnit;
    if (!(scale > 0) || !std::isfinite(scale * extent) || scale * extent * kMetresPerDoomUnit > 100)
        throw ImportError{"the model is " + std::to_string(extent * metres) +
                          " m large at this scale (at most 100 m): give --unit-m or --height"};
    for (std::size_t i = 0; i < rig.joints.size(); ++i) {
        RigJoint& j = rig.joints[i];
        if (i == 0 && !topIsOrigin) continue;
        j.bind = {axes * j.bind.rotation, axes * (scale * j.bind.position)};
    }
    for (RigSurface& s : rig.surfaces)
        for (RigVertex& v : s.vertices) v.position = axes * (scale * v.position);
    rig.units.metresPerUnit = metres;
    rig.units.source = options.heightM         ? RigUnits::Source::Height
                       : options.metresPerUnit ? RigUnits::Source::Option
                                               : RigUnits::Source::Format;
    rig.units.fileHeight = extent;
    rig.units.up = options.up.value_or('y');
}

Rig rigFromScene(const aiScene& scene, const std::string& extension, const ImportOptions& options) {
    validateScene(scene);
    const SceneIndex index = indexScene(scene);
    const std::map<int, figure::Transform> boneBind = boneBinds(scene, index);
    const SkeletonNodes skeleton = skeletonNodes(index, boneBind);

    // Unit and axes: Doom units, Z up, X forward (assimp's Y up, Z forward → Doom's Z up, X forward).
    const std::string ext = text::lowerAscii(extension);
    double metres = ext == "gltf" || ext == "glb" ? 1.0
                    : ext == "fbx"                ? 0.01 * metaDouble(scene, "UnitScaleFactor").value_or(1.0)
                                                  : kMetresPerDoomUnit;
    if (options.metresPerUnit) metres = *options.metresPerUnit;
    Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
    if (options.up.value_or('y') == 'y') axes << 0, 0, 1, 1, 0, 0, 0, 1, 0;

    Rig rig;
    std::map<int, int> jointOfNode;
    const bool topIsOrigin =
        text::lowerAscii(index.nodes[static_cast<std::size_t>(skeleton.top)].node->mName.C_Str()) == "origin";
    addJoints(rig, index, boneBind, skeleton, topIsOrigin, jointOfNode);
    for (unsigned mi = 0; mi < scene.mNumMeshes; ++mi) {
        // Vertices no bone weighs follow the nearest skeleton joint above their mesh node (else the skeleton's top).
        int rigidJoint = jointOfNode.at(skeleton.top);
        for (int n = index.meshNode[mi]; n >= 0; n = index.nodes[static_cast<std::size_t>(n)].parent)
            if (jointOfNode.count(n)) {
                rigidJoint = jointOfNode.at(n);
                break;
            }
        rig.surfaces.push_back(surfaceOf(scene, mi, index, jointOfNode, rigidJoint));
    }
    scaleRig(rig, metres, axes, topIsOrigin, options);
    return rig;
}

std::optional<Rig> fromImporter(Assimp::Importer& importer, const aiScene* scene, const std::string& label,
                                const std::string& extension, const ImportOptions& options,
                                text::Diagnostics& diagnostics) {
    if (!scene) {
        diagnostics.error({label, 0, 0}, std::string("cannot import: ") + importer.GetErrorString());
        return std::nullopt;
    }
    try {
        return rigFromScene(*scene, extension, options);
    } catch (const ImportError& e) {
        diagnostics.error({label, 0, 0}, e.message);
    } catch (const std::exception& e) {
        diagnostics.error({label, 0, 0}, std::string("cannot import: ") + e.what());
    }
    return std::nullopt;
}

} // namespace

unsigned assimpPostProcessSteps() {
    return aiProcess_Triangulate | aiProcess_ValidateDataStructure | aiProcess_SortByPType;
}

std::optional<Rig> importRig(const std::filesystem::path& path, const ImportOptions& options,
                             text::Diagnostics& diagnostics) {
    std::string ext = text::lowerAscii(path.extension().string());
    if (!ext.empty()) ext.erase(0, 1);
    if (ext == "md5mesh") {
        auto mesh = decl::loadMd5Mesh(path, diagnostics);
        if (!mesh) return std::nullopt;
        return rigFromMd5(*mesh, options, path.string(), diagnostics);
    }
    const std::string label = path.string();
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) {
        diagnostics.error({label, 0, 0}, "cannot read the file");
        return std::nullopt;
    }
    try {
        Assimp::Importer importer; // by path, so a .gltf finds its buffers beside it
        const aiScene* scene = importer.ReadFile(label, assimpPostProcessSteps());
        return fromImporter(importer, scene, label, ext, options, diagnostics);
    } catch (const std::exception& e) {
        diagnostics.error({label, 0, 0}, std::string("cannot import: ") + e.what());
    } catch (...) {
        diagnostics.error({label, 0, 0}, "cannot import: assimp failed");
    }
    return std::nullopt;
}

std::optional<Rig> importRigFromMemory(const void* data, std::size_t size, const std::string& hint,
                                       const ImportOptions& options, text::Diagnostics& diagnostics) {
    const std::string label = "<model>." + hint;
    try {
        Assimp::Importer importer;
        const aiScene* scene = importer.ReadFileFromMemory(data, size, assimpPostProcessSteps(), hint.c_str());
        return fromImporter(importer, scene, label, hint, options, diagnostics);
    } catch (const std::exception& e) {
        diagnostics.error({label, 0, 0}, std::string("cannot import: ") + e.what());
    } catch (...) {
        diagnostics.error({label, 0, 0}, "cannot import: assimp failed");
    }
    return std::nullopt;
}

} // namespace afb::gen
