// glTF replays of drops (see GltfReplay.h): the recording turned into an aiScene and written by assimp's glb2
// exporter. Assimp 5.2 trusts its input (a bad index, an unknown node name or a null array crashes it), so the scene
// is built from checked data only, every name is unique, and every array and count are set together.
#include "afb/sim/GltfReplay.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <set>
#include <string_view>
#include <system_error>

#include <assimp/Exporter.hpp>
#include <assimp/material.h>
#include <assimp/scene.h>

#include "afb/figure/Placement.h"
#include "afb/pose/SkeletonDriver.h"

namespace afb::sim {
namespace {

using figure::Transform;

// --- axes and numbers ---------------------------------------------------------------------------------------------

// P: (x, y, z)_Doom ↦ (y, z, x)_glTF, a cyclic permutation (det +1): Doom's up Z → glTF's up Y, forward X → +Z.
Eigen::Matrix3d doomToGltf() { return (Eigen::Matrix3d() << 0, 1, 0, 0, 0, 1, 1, 0, 0).finished(); }
Eigen::Vector3d toGltf(const Eigen::Vector3d& p) { return doomToGltf() * p; }
Transform toGltf(const Transform& t) {
    const Eigen::Matrix3d p = doomToGltf();
    return {p * t.rotation * p.transpose(), p * t.position};
}

// Poses beyond this are an exploded drop: float keys would lose them, or overflow.
constexpr double kMaxCoordinateM = 1e6;
// Assimp's exporter recurses once per node level; an md5 hierarchy deeper than this is refused, not exported.
constexpr int kMaxJointDepth = 1000;
// glTF JOINTS_0 holds unsigned shorts.
constexpr int kMaxJoints = 65535;

bool usable(const Transform& t) {
    return t.rotation.allFinite() && t.position.allFinite() && t.position.cwiseAbs().maxCoeff() <= kMaxCoordinateM;
}

aiVector3D aiVec(const Eigen::Vector3d& v) {
    return {static_cast<ai_real>(v.x()), static_cast<ai_real>(v.y()), static_cast<ai_real>(v.z())};
}

aiMatrix4x4 aiMat(const Transform& t) {
    aiMatrix4x4 m; // identity; column-vector convention with the translation in the fourth column, as ours
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) m[r][c] = static_cast<ai_real>(t.rotation(r, c));
        m[r][3] = static_cast<ai_real>(t.position(r));
    }
    return m;
}

// --- names --------------------------------------------------------------------------------------------------------

// The exporter finds nodes by name (bones and animation channels) and renames a node whose name an earlier object
// took (the GLB buffer "binary_glTF", a material): a lookup of the old name would then find nothing and crash. So
// every node name is claimed here, printable ASCII, short, and unique against everything created before the nodes.
class NameRegistry {
  public:
    explicit NameRegistry(std::initializer_list<std::string_view> reserved) {
        for (std::string_view r : reserved) m_used.emplace(r);
    }
    std::string claim(std::string_view wanted) {
        std::string base;
        for (char c : wanted.substr(0, 200)) base += (c >= 0x20 && c < 0x7f) ? c : '_';
        if (base.empty()) base = "node";
        std::string name = base;
        for (int i = 2; m_used.count(name); ++i) name = base + "_" + std::to_string(i);
        m_used.insert(name);
        return name;
    }

  private:
    std::set<std::string> m_used;
};

constexpr std::string_view kGlbBuffer = "binary_glTF"; // the exporter's GLB body buffer, created before the nodes
constexpr std::string_view kSkinMaterial = "afb_skin", kHullMaterial = "afb_hull", kGroundMaterial = "afb_ground";

// --- poses --------------------------------------------------------------------------------------------------------

// One frame in glTF axes: joint transforms relative to their parent node, body frames in the world.
struct GltfFrame {
    std::vector<Transform> jointLocal;
    std::vector<Transform> bodyWorld;
};

std::optional<GltfFrame> gltfFrame(const figure::Figure& figure, const std::vector<Transform>& bodies) {
    GltfFrame out;
    for (const Transform& b : bodies) {
        if (!usable(b)) return std::nullopt;
        out.bodyWorld.push_back(toGltf(b));
    }
    const pose::SkeletonPose pose = pose::driveSkeleton(figure, bodies);
    for (int j = 0; j < figure.skeleton.jointCount(); ++j) {
        const Transform& local = pose.local[static_cast<std::size_t>(j)];
        const Transform t = figure.skeleton.parent(j) < 0 ? pose.entity * local : local; // md5 roots: the world
        if (!usable(t)) return std::nullopt;
        out.jointLocal.push_back(toGltf(t));
    }
    return out;
}

// --- the skinned md5 mesh -----------------------------------------------------------------------------------------

// A checked sub-mesh ready for assimp: vertices merged where their float positions are equal (the exporter's
// JoinIdenticalVertices would merge them anyway, but pool their weights past 1), unreferenced ones dropped,
// triangles that collapse dropped, and at most four normalised joint weights per vertex.
struct SkinnedPart {
    std::string name;
    std::vector<aiVector3D> positions;
    std::vector<std::array<unsigned, 3>> triangles;
    std::vector<std::vector<std::pair<int, float>>> weights; // per vertex: (joint, weight), sum 1
};

std::optional<std::string> checkMesh(const decl::Md5Mesh& mesh, const figure::Skeleton& skeleton) {
    const int joints = static_cast<int>(mesh.joints.size());
    if (joints != skeleton.jointCount()) return "the mesh's joints are not the figure's skeleton";
    for (int j = 0; j < joints; ++j)
        if (mesh.joints[static_cast<std::size_t>(j)].parent != skeleton.parent(j))
            return "the mesh's joint hierarchy is not the figure's skeleton";
    if (joints > kMaxJoints) return "more than 65535 joints";
    std::vector<int> depth(static_cast<std::size_t>(joints), 0);
    for (int j = 0; j < joints; ++j) {
        const int p = skeleton.parent(j);
        if (p >= j) return "a joint's parent does not precede it";
        depth[static_cast<std::size_t>(j)] = p < 0 ? 0 : depth[static_cast<std::size_t>(p)] + 1;
        if (depth[static_cast<std::size_t>(j)] > kMaxJointDepth) return "the joint hierarchy is too deep to export";
    }
    for (const decl::Md5SubMesh& sub : mesh.meshes) {
        const long verts = static_cast<long>(sub.verts.size()), weights = static_cast<long>(sub.weights.size());
        for (const decl::Md5Vert& v : sub.verts)
            if (v.firstWeight < 0 || v.weightCount < 1 || v.firstWeight + static_cast<long>(v.weightCount) > weights)
                return "a vertex's weights are out of range";
        for (const decl::Md5Weight& w : sub.weights)
            if (w.joint < 0 || w.joint >= joints) return "a weight's joint is out of range";
        for (const decl::Md5Tri& t : sub.tris)
            for (int i : t.v)
                if (i < 0 || i >= verts) return "a triangle's vertex is out of range";
    }
    return std::nullopt;
}

// The four largest joint weights of md5 vertex `v` (biases on one joint summed, negatives as 0), renormalised in
// float so that they sum to 1 as closely as float allows.
std::vector<std::pair<int, float>> vertexWeights(const decl::Md5SubMesh& sub, const decl::Md5Vert& v) {
    std::map<int, double> perJoint;
    for (int k = 0; k < v.weightCount; ++k) {
        const decl::Md5Weight& w = sub.weights[static_cast<std::size_t>(v.firstWeight + k)];
        perJoint[w.joint] += std::isfinite(w.bias) ? std::max(0.0, w.bias) : 0.0;
    }
    std::vector<std::pair<int, double>> sorted(perJoint.begin(), perJoint.end());
    std::stable_sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a.second > b.second; });
    if (sorted.size() > 4) sorted.resize(4);
    double sum = 0;
    for (const auto& s : sorted) sum += s.second;
    if (!(sum > 0)) return {{sorted.front().first, 1.0f}}; // no positive bias: rigid on the first joint
    std::vector<std::pair<int, float>> out;
    float rest = 1.0f;
    for (std::size_t i = 1; i < sorted.size(); ++i) {
        const float w = static_cast<float>(sorted[i].second / sum);
        if (w <= 0) continue;
        out.emplace_back(sorted[i].first, w);
        rest -= w;
    }
    out.insert(out.begin(), {sorted.front().first, rest}); // the largest takes the float remainder
    return out;
}

// nullopt when a bind vertex is not finite or absurdly far (checked before it becomes a float or a map key).
std::optional<std::vector<SkinnedPart>> skinnedParts(const decl::Md5Mesh& mesh,
                                                     const std::vector<Transform>& bindMetres, double metresPerUnit) {
    const std::vector<std::vector<Eigen::Vector3d>> bind = pose::skin(mesh, bindMetres, metresPerUnit);
    std::vector<SkinnedPart> parts;
    for (std::size_t s = 0; s < mesh.meshes.size(); ++s) {
        const decl::Md5SubMesh& sub = mesh.meshes[s];
        for (const Eigen::Vector3d& p : bind[s])
            if (!p.allFinite() || p.cwiseAbs().maxCoeff() > kMaxCoordinateM) return std::nullopt;
        SkinnedPart part;
        part.name = sub.name.empty() ? "mesh" + std::to_string(s) : sub.name;
        std::vector<long> newIndex(sub.verts.size(), -1);
        std::map<std::array<float, 3>, unsigned> byPosition;
        auto vertex = [&](int v) -> unsigned {
            long& n = newIndex[static_cast<std::size_t>(v)];
            if (n >= 0) return static_cast<unsigned>(n);
            const aiVector3D p = aiVec(toGltf(bind[s][static_cast<std::size_t>(v)]));
            const auto [it, added] = byPosition.emplace(std::array<float, 3>{p.x, p.y, p.z}, part.positions.size());
            if (added) {
                part.positions.push_back(p);
                part.weights.push_back(vertexWeights(sub, sub.verts[static_cast<std::size_t>(v)]));
            }
            n = it->second;
            return it->second;
        };
        for (const decl::Md5Tri& t : sub.tris) {
            const std::array<unsigned, 3> tri{vertex(t.v[0]), vertex(t.v[1]), vertex(t.v[2])};
            if (tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2]) part.triangles.push_back(tri);
        }
        if (!part.triangles.empty()) parts.push_back(std::move(part));
    }
    return parts;
}

// --- assimp objects -----------------------------------------------------------------------------------------------

aiMaterial* makeMaterial(std::string_view name, const aiColor4D& colour, bool twoSided) {
    auto* m = new aiMaterial();
    const aiString aiName{std::string(name)};
    m->AddProperty(&aiName, AI_MATKEY_NAME);
    const aiColor4D opaque(colour.r, colour.g, colour.b, 1.0f);
    m->AddProperty(&opaque, 1, AI_MATKEY_BASE_COLOR);
    if (colour.a < 1.0f) m->AddProperty(&colour.a, 1, AI_MATKEY_OPACITY); // the exporter: alphaMode BLEND
    const float metallic = 0.0f, roughness = 0.8f;
    m->AddProperty(&metallic, 1, AI_MATKEY_METALLIC_FACTOR);
    m->AddProperty(&roughness, 1, AI_MATKEY_ROUGHNESS_FACTOR);
    const int sides = twoSided ? 1 : 0;
    m->AddProperty(&sides, 1, AI_MATKEY_TWOSIDED);
    return m;
}

// A triangle mesh; counts and arrays set together, so the aiMesh destructor can always free it.
aiMesh* makeMesh(const std::string& name, const std::vector<aiVector3D>& positions,
                 const std::vector<std::array<unsigned, 3>>& triangles, unsigned material) {
    auto* m = new aiMesh();
    m->mName = name;
    m->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
    m->mMaterialIndex = material;
    m->mVertices = new aiVector3D[positions.size()];
    m->mNumVertices = static_cast<unsigned>(positions.size());
    std::copy(positions.begin(), positions.end(), m->mVertices);
    m->mFaces = new aiFace[triangles.size()];
    m->mNumFaces = static_cast<unsigned>(triangles.size());
    for (std::size_t f = 0; f < triangles.size(); ++f) {
        m->mFaces[f].mIndices = new unsigned[3];
        m->mFaces[f].mNumIndices = 3;
        std::copy(triangles[f].begin(), triangles[f].end(), m->mFaces[f].mIndices);
    }
    return m;
}

// Bones for every joint (all of them, weighted or not, so the skin is the whole skeleton).
void addBones(aiMesh& m, const SkinnedPart& part, const std::vector<std::string>& jointNames,
              const std::vector<Transform>& bindGltf) {
    std::vector<std::vector<aiVertexWeight>> perJoint(jointNames.size());
    for (std::size_t v = 0; v < part.weights.size(); ++v)
        for (const auto& [joint, w] : part.weights[v])
            perJoint[static_cast<std::size_t>(joint)].emplace_back(static_cast<unsigned>(v), w);
    m.mBones = new aiBone*[jointNames.size()]();
    m.mNumBones = static_cast<unsigned>(jointNames.size());
    for (std::size_t j = 0; j < jointNames.size(); ++j) {
        auto* bone = new aiBone();
        m.mBones[j] = bone;
        bone->mName = jointNames[j];
        bone->mOffsetMatrix = aiMat(bindGltf[j].inverse()); // the inverse bind matrix
        if (!perJoint[j].empty()) {
            bone->mWeights = new aiVertexWeight[perJoint[j].size()];
            bone->mNumWeights = static_cast<unsigned>(perJoint[j].size());
            std::copy(perJoint[j].begin(), perJoint[j].end(), bone->mWeights);
        }
    }
}

// The polytope of a body in its body frame, glTF axes; faces as fans (they are convex, outward counter-clockwise).
aiMesh* hullMesh(const std::string& name, const figure::BodyShape& shape, unsigned material) {
    std::vector<aiVector3D> positions;
    for (const Eigen::Vector3d& v : shape.vertices) {
        if (!v.allFinite() || v.cwiseAbs().maxCoeff() > kMaxCoordinateM) return nullptr;
        positions.push_back(aiVec(toGltf(v)));
    }
    std::vector<std::array<unsigned, 3>> triangles;
    for (const std::vector<int>& face : shape.faces) {
        const bool inRange =
            std::all_of(face.begin(), face.end(), [&](int i) { return i >= 0 && i < int(positions.size()); });
        if (!inRange) return nullptr;
        for (std::size_t i = 1; i + 1 < face.size(); ++i)
            triangles.push_back({unsigned(face[0]), unsigned(face[i]), unsigned(face[i + 1])});
    }
    if (triangles.empty()) return nullptr;
    return makeMesh(name, positions, triangles, material);
}

// A node tree described first, then made into aiNodes at once (each aiNode owns its children).
struct NodeSpec {
    std::string name;
    Transform local;
    std::vector<unsigned> meshes;
    std::vector<std::size_t> children;
};

aiNode* makeNode(const std::vector<NodeSpec>& specs, std::size_t index, aiNode* parent) {
    const NodeSpec& s = specs[index];
    auto* n = new aiNode(s.name);
    n->mParent = parent;
    n->mTransformation = aiMat(s.local);
    if (!s.meshes.empty()) {
        n->mMeshes = new unsigned[s.meshes.size()];
        n->mNumMeshes = static_cast<unsigned>(s.meshes.size());
        std::copy(s.meshes.begin(), s.meshes.end(), n->mMeshes);
    }
    if (!s.children.empty()) {
        n->mChildren = new aiNode*[s.children.size()]();
        n->mNumChildren = static_cast<unsigned>(s.children.size());
        for (std::size_t c = 0; c < s.children.size(); ++c) n->mChildren[c] = makeNode(specs, s.children[c], n);
    }
    return n;
}

// A channel of the "drop" animation: one translation and one rotation key per frame, quaternion signs continuous
// (the shorter way between keys).
aiNodeAnim* makeChannel(const std::string& node, const std::vector<Transform>& keys) {
    auto* c = new aiNodeAnim();
    c->mNodeName = node;
    c->mPositionKeys = new aiVectorKey[keys.size()];
    c->mNumPositionKeys = static_cast<unsigned>(keys.size());
    c->mRotationKeys = new aiQuatKey[keys.size()];
    c->mNumRotationKeys = static_cast<unsigned>(keys.size());
    Eigen::Quaterniond previous = Eigen::Quaterniond::Identity();
    for (std::size_t k = 0; k < keys.size(); ++k) {
        Eigen::Quaterniond q(keys[k].rotation);
        q.normalize();
        if (k > 0 && q.dot(previous) < 0) q.coeffs() = -q.coeffs();
        previous = q;
        const double time = static_cast<double>(k); // in ticks: one tick per frame
        c->mPositionKeys[k] = aiVectorKey(time, aiVec(keys[k].position));
        c->mRotationKeys[k] = aiQuatKey(time, aiQuaternion(static_cast<ai_real>(q.w()), static_cast<ai_real>(q.x()),
                                                           static_cast<ai_real>(q.y()), static_cast<ai_real>(q.z())));
    }
    return c;
}

template <class T>
void setArray(T**& array, unsigned& count, std::vector<T*>& items) {
    array = new T*[items.size()];
    count = static_cast<unsigned>(items.size());
    std::copy(items.begin(), items.end(), array);
    items.clear(); // owned by the scene now
}

template <class T>
struct Owned { // frees items not yet handed to the scene (on an early return)
    std::vector<T*> items;
    ~Owned() {
        for (T* t : items) delete t;
    }
};

} // namespace

DropObserver recordInto(DropRecording& recording, double hz) {
    recording.frameSeconds = 1.0 / hz;
    recording.frames.clear();
    return [&recording](int, std::span<const Transform> bodies) {
        recording.frames.emplace_back(bodies.begin(), bodies.end());
    };
}

namespace {

GltfReplayResult writeReplay(const figure::Figure& figure, const decl::Md5Mesh& mesh, const DropRecording& recording,
                             const std::filesystem::path& path) {
    GltfReplayResult result;
    auto fail = [&](std::string message) {
        result.error = std::move(message);
        return result;
    };
    if (!(recording.frameSeconds > 0) || !std::isfinite(recording.frameSeconds))
        return fail("the recording's frame time is not a positive number");
    if (recording.frames.empty()) return fail("the recording has no frames");
    for (const auto& frame : recording.frames)
        if (frame.size() != figure.bodies.size()) return fail("a recorded frame does not have one pose per body");
    if (const auto problem = checkMesh(mesh, figure.skeleton)) return fail(*problem);

    // Every frame in glTF axes, up to the first one a float file cannot hold.
    std::vector<GltfFrame> frames;
    for (const auto& bodies : recording.frames) {
        auto f = gltfFrame(figure, bodies);
        if (!f) break;
        frames.push_back(std::move(*f));
    }
    result.framesDropped = static_cast<int>(recording.frames.size() - frames.size());
    if (frames.empty()) return fail("the drop's first frame is not finite");

    const int jointCount = figure.skeleton.jointCount();
    const double mpu = figure.units.metresPerUnit;
    std::vector<Transform> bindGltf;
    const std::vector<Transform> bindMetres = figure::toMetres(figure.skeleton.bindPose(), mpu);
    for (const Transform& b : bindMetres) {
        if (!usable(b)) return fail("the mesh's bind pose is not finite");
        bindGltf.push_back(toGltf(b));
    }
    const auto skinned = skinnedParts(mesh, bindMetres, mpu);
    if (!skinned) return fail("the mesh's bind vertices are not finite");
    const std::vector<SkinnedPart>& parts = *skinned;

    // Names first: the figure root and the groups, then joints and bodies.
    NameRegistry names{kGlbBuffer, kSkinMaterial, kHullMaterial, kGroundMaterial};
    std::vector<NodeSpec> nodes;
    auto addNode = [&](std::string_view name, std::optional<std::size_t> parent, const Transform& local) {
        nodes.push_back({names.claim(name), local, {}, {}});
        if (parent) nodes[*parent].children.push_back(nodes.size() - 1);
        return nodes.size() - 1;
    };
    const std::size_t root = addNode(figure.name.empty() ? "drop" : figure.name, std::nullopt, {});
    const std::size_t ground = addNode("ground", root, {});
    const std::size_t skeleton = addNode("skeleton", root, {});
    const std::size_t bodiesGroup = addNode("bodies", root, {});
    std::vector<std::size_t> jointNode;
    std::vector<std::string> jointNames;
    for (int j = 0; j < jointCount; ++j) {
        const int parent = figure.skeleton.parent(j);
        const std::size_t parentNode = parent < 0 ? skeleton : jointNode[static_cast<std::size_t>(parent)];
        jointNode.push_back(addNode(figure.skeleton.name(j), parentNode, frames[0].jointLocal[std::size_t(j)]));
        jointNames.push_back(nodes.back().name);
    }
    const std::size_t meshNode = parts.empty() ? 0 : addNode("mesh", skeleton, {});
    std::vector<std::size_t> bodyNode;
    for (std::size_t b = 0; b < figure.bodies.size(); ++b)
        bodyNode.push_back(addNode("body_" + figure.bodies[b].name, bodiesGroup, frames[0].bodyWorld[b]));

    // Materials and meshes: the skinned parts, one hull per body, the ground.
    Owned<aiMaterial> materials;
    materials.items = {makeMaterial(kSkinMaterial, aiColor4D(0.80f, 0.72f, 0.62f, 1.0f), true),
                       makeMaterial(kHullMaterial, aiColor4D(1.00f, 0.45f, 0.10f, 0.45f), false),
                       makeMaterial(kGroundMaterial, aiColor4D(0.36f, 0.39f, 0.42f, 1.0f), true)};
    Owned<aiMesh> meshes;
    for (const SkinnedPart& part : parts) {
        meshes.items.push_back(makeMesh(part.name, part.positions, part.triangles, 0));
        addBones(*meshes.items.back(), part, jointNames, bindGltf);
        nodes[meshNode].meshes.push_back(static_cast<unsigned>(meshes.items.size() - 1));
    }
    for (std::size_t b = 0; b < figure.bodies.size(); ++b)
        if (aiMesh* hull = hullMesh("hull_" + nodes[bodyNode[b]].name, figure.bodies[b].shape, 1)) {
            meshes.items.push_back(hull);
            nodes[bodyNode[b]].meshes.push_back(static_cast<unsigned>(meshes.items.size() - 1));
        }
    {
        // Under everything the bodies reached, with a metre to spare (glTF axes: the ground is y = 0).
        Eigen::Vector3d lo = frames[0].bodyWorld.empty() ? Eigen::Vector3d::Zero() : frames[0].bodyWorld[0].position;
        Eigen::Vector3d hi = lo;
        for (const GltfFrame& f : frames)
            for (const Transform& b : f.bodyWorld) {
                lo = lo.cwiseMin(b.position);
                hi = hi.cwiseMax(b.position);
            }
        const double x0 = lo.x() - 1, x1 = hi.x() + 1, z0 = lo.z() - 1, z1 = hi.z() + 1;
        const std::vector<aiVector3D> corners{aiVec({x0, 0, z0}), aiVec({x0, 0, z1}), aiVec({x1, 0, z1}),
                                              aiVec({x1, 0, z0})};
        meshes.items.push_back(makeMesh("ground", corners, {{0, 1, 2}, {0, 2, 3}}, 2)); // counter-clockwise from +Y
        nodes[ground].meshes.push_back(static_cast<unsigned>(meshes.items.size() - 1));
    }

    // The animation: every joint and every body, one key per frame.
    auto* animation = new aiAnimation();
    Owned<aiAnimation> animations;
    animations.items.push_back(animation);
    animation->mName = "drop";
    animation->mTicksPerSecond = 1.0 / recording.frameSeconds;
    animation->mDuration = static_cast<double>(frames.size() - 1);
    std::vector<aiNodeAnim*> channels;
    std::vector<Transform> keys(frames.size());
    for (int j = 0; j < jointCount; ++j) {
        for (std::size_t k = 0; k < frames.size(); ++k) keys[k] = frames[k].jointLocal[static_cast<std::size_t>(j)];
        channels.push_back(makeChannel(jointNames[static_cast<std::size_t>(j)], keys));
    }
    for (std::size_t b = 0; b < figure.bodies.size(); ++b) {
        for (std::size_t k = 0; k < frames.size(); ++k) keys[k] = frames[k].bodyWorld[b];
        channels.push_back(makeChannel(nodes[bodyNode[b]].name, keys));
    }
    setArray(animation->mChannels, animation->mNumChannels, channels);

    auto scene = std::make_unique<aiScene>();
    scene->mRootNode = makeNode(nodes, root, nullptr);
    setArray(scene->mMaterials, scene->mNumMaterials, materials.items);
    setArray(scene->mMeshes, scene->mNumMeshes, meshes.items);
    setArray(scene->mAnimations, scene->mNumAnimations, animations.items);

    Assimp::Exporter exporter;
    const aiReturn rc = exporter.Export(scene.get(), "glb2", path.string());
    std::error_code ec;
    if (rc != aiReturn_SUCCESS || !std::filesystem::is_regular_file(path, ec) ||
        std::filesystem::file_size(path, ec) < 12) {
        std::filesystem::remove(path, ec);
        const char* why = exporter.GetErrorString();
        return fail(std::string("assimp could not write ") + path.string() + ": " + (why && *why ? why : "failed"));
    }
    result.frames = static_cast<int>(frames.size());
    result.joints = parts.empty() ? 0 : jointCount;
    result.bodies = static_cast<int>(figure.bodies.size());
    return result;
}

} // namespace

GltfReplayResult writeGltfReplay(const figure::Figure& figure, const decl::Md5Mesh& mesh,
                                 const DropRecording& recording, const std::filesystem::path& path) {
    try {
        return writeReplay(figure, mesh, recording, path);
    } catch (const std::exception& e) { // out of memory, or a filesystem error
        GltfReplayResult failed;
        failed.error = std::string("cannot write the replay: ") + e.what();
        return failed;
    }
}

} // namespace afb::sim
