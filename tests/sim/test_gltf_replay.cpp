// glTF replays of drops (`afb drop --gltf`): a short drop of the bundled humanoid written through assimp's exporter,
// read back through assimp's importer, and compared with independent runs of the same drop: the skin's joints, one
// animation of steps + 1 keys, the joint and body positions at a sampled frame (from a second drop stopped at that
// step), and the skinned vertices. The Khronos validator checks the files in cli.drop_gltf.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <string>
#include <tuple>

#include <assimp/Importer.hpp>
#include <assimp/scene.h>
#include <unistd.h>

#include "EntityFixture.h"
#include "afb/figure/Placement.h"
#include "afb/pose/SkeletonDriver.h"
#include "afb/sim/Drop.h"
#include "afb/sim/GltfReplay.h"

namespace {

namespace fs = std::filesystem;
using afb::figure::Transform;

constexpr int kSteps = 30;
constexpr int kSampledFrame = 12;

// glTF is Y-up with +Z forward; Doom is Z-up with +X forward: glTF (x, y, z) = Doom (y, z, x).
aiVector3D gltfFromDoom(const Eigen::Vector3d& p) {
    return aiVector3D(static_cast<float>(p.y()), static_cast<float>(p.z()), static_cast<float>(p.x()));
}

double distance(const aiVector3D& a, const aiVector3D& b) { return static_cast<double>((a - b).Length()); }

afb::sim::DropOptions dropOptions(int steps) {
    afb::sim::DropOptions o;
    o.heightM = 0.5;
    o.steps = steps;
    o.sleeping = false;
    return o;
}

// A scratch file removed at the end of the test.
struct TempFile {
    fs::path path;
    explicit TempFile(const std::string& name)
        : path(fs::temp_directory_path() / ("afb_test_" + std::to_string(::getpid()) + "_" + name)) {}
    ~TempFile() {
        std::error_code ec;
        fs::remove(path, ec);
    }
};

const aiNodeAnim* channelOf(const aiAnimation& anim, const std::string& node) {
    for (unsigned c = 0; c < anim.mNumChannels; ++c)
        if (node == anim.mChannels[c]->mNodeName.C_Str()) return anim.mChannels[c];
    return nullptr;
}

// World matrices of every node at animation key `key` (nodes without a channel keep their own transform).
void worldAtKey(const aiNode& node, const aiMatrix4x4& parent, const aiAnimation& anim, unsigned key,
                std::map<std::string, aiMatrix4x4>& out) {
    aiMatrix4x4 local = node.mTransformation;
    if (const aiNodeAnim* c = channelOf(anim, node.mName.C_Str())) {
        REQUIRE(key < c->mNumPositionKeys);
        REQUIRE(key < c->mNumRotationKeys);
        local = aiMatrix4x4(aiVector3D(1, 1, 1), c->mRotationKeys[key].mValue, c->mPositionKeys[key].mValue);
    }
    const aiMatrix4x4 world = parent * local;
    out[node.mName.C_Str()] = world;
    for (unsigned i = 0; i < node.mNumChildren; ++i) worldAtKey(*node.mChildren[i], world, anim, key, out);
}

aiVector3D origin(const aiMatrix4x4& m) { return aiVector3D(m.a4, m.b4, m.c4); }

const aiNode& child(const aiNode& node, const std::string& name) {
    const aiNode* found = node.FindNode(name.c_str());
    INFO(name);
    REQUIRE(found);
    return *found;
}

} // namespace

TEST_CASE("gltf replay: a drop read back through assimp is the drop", "[sim][gltf]") {
    const afb::figure::LoadedFigure loaded = afb::test::loadEntity("humanoid");
    const afb::figure::Figure& figure = loaded.figure;
    const int joints = figure.skeleton.jointCount();

    afb::sim::DropRecording recording;
    const afb::sim::DropResult whole =
        afb::sim::runDrop(figure, dropOptions(kSteps), afb::sim::recordInto(recording, 60.0));
    REQUIRE(recording.frames.size() == kSteps + 1);
    CHECK(recording.frameSeconds == Approx(1.0 / 60.0));

    // The observer changes nothing: the same drop without it ends in the same pose.
    const afb::sim::DropResult unobserved = afb::sim::runDrop(figure, dropOptions(kSteps));
    REQUIRE(unobserved.finalPose.size() == whole.finalPose.size());
    for (std::size_t j = 0; j < whole.finalPose.size(); ++j)
        for (int a = 0; a < 3; ++a) CHECK(unobserved.finalPose[j].position[a] == whole.finalPose[j].position[a]);

    TempFile file("humanoid.glb");
    const afb::sim::GltfReplayResult written = afb::sim::writeGltfReplay(figure, loaded.mesh, recording, file.path);
    INFO(written.error.value_or(""));
    REQUIRE_FALSE(written.error);
    CHECK(written.frames == kSteps + 1);
    CHECK(written.framesDropped == 0);
    CHECK(written.joints == joints);
    CHECK(written.bodies == static_cast<int>(figure.bodies.size()));

    Assimp::Importer importer;
    const aiScene* scene = importer.ReadFile(file.path.string(), 0);
    INFO(importer.GetErrorString());
    REQUIRE(scene);
    REQUIRE(scene->mRootNode);

    SECTION("the skin is the whole md5 skeleton, and the joint nodes are its hierarchy") {
        const aiNode& meshNode = child(*scene->mRootNode, "mesh");
        REQUIRE(meshNode.mNumMeshes == loaded.mesh.meshes.size());
        for (unsigned m = 0; m < meshNode.mNumMeshes; ++m) {
            const aiMesh& mesh = *scene->mMeshes[meshNode.mMeshes[m]];
            REQUIRE(mesh.mNumBones == static_cast<unsigned>(joints));
            for (int j = 0; j < joints; ++j) CHECK(mesh.mBones[j]->mName.C_Str() == figure.skeleton.name(j));
        }
        for (int j = 1; j < joints; ++j) {
            const aiNode& node = child(*scene->mRootNode, figure.skeleton.name(j));
            REQUIRE(node.mParent);
            CHECK(node.mParent->mName.C_Str() == figure.skeleton.name(figure.skeleton.parent(j)));
        }
    }

    SECTION("the body hulls are a tree of their own: one node and one mesh per body") {
        const aiNode& bodies = child(*scene->mRootNode, "bodies");
        REQUIRE(bodies.mNumChildren == figure.bodies.size());
        for (unsigned b = 0; b < bodies.mNumChildren; ++b) {
            CHECK(bodies.mChildren[b]->mName.C_Str() == "body_" + figure.bodies[b].name);
            CHECK(bodies.mChildren[b]->mNumMeshes == 1);
        }
        const aiNode& ground = child(*scene->mRootNode, "ground");
        REQUIRE(ground.mNumMeshes == 1);
        const aiMesh& plane = *scene->mMeshes[ground.mMeshes[0]];
        for (unsigned v = 0; v < plane.mNumVertices; ++v) CHECK(plane.mVertices[v].y == 0.0f);
    }

    SECTION("one animation, steps + 1 keys per channel, steps / rate long") {
        REQUIRE(scene->mNumAnimations == 1);
        const aiAnimation& anim = *scene->mAnimations[0];
        CHECK(anim.mNumChannels == static_cast<unsigned>(joints) + figure.bodies.size());
        for (unsigned c = 0; c < anim.mNumChannels; ++c) {
            CHECK(anim.mChannels[c]->mNumPositionKeys == kSteps + 1);
            CHECK(anim.mChannels[c]->mNumRotationKeys == kSteps + 1);
        }
        REQUIRE(anim.mTicksPerSecond > 0);
        CHECK(anim.mDuration / anim.mTicksPerSecond == Approx(kSteps / 60.0).epsilon(1e-6));
    }

    SECTION("at a sampled frame the joints, the bodies and the skinned vertices are where the drop had them") {
        REQUIRE(scene->mNumAnimations == 1);
        const aiAnimation& anim = *scene->mAnimations[0];
        // An independent drop stopped at that step: its pose (driveSkeleton of its bodies) is the reference.
        const afb::sim::DropResult atFrame = afb::sim::runDrop(figure, dropOptions(kSampledFrame));
        std::map<std::string, aiMatrix4x4> world;
        worldAtKey(*scene->mRootNode, aiMatrix4x4(), anim, kSampledFrame, world);

        const Eigen::Quaterniond qe(atFrame.entity[3], atFrame.entity[4], atFrame.entity[5], atFrame.entity[6]);
        const Eigen::Vector3d pe(atFrame.entity[0], atFrame.entity[1], atFrame.entity[2]);
        std::vector<Transform> jointsWorld;
        double worstJoint = 0;
        for (int j = 0; j < joints; ++j) {
            const afb::sim::JointPose& jp = atFrame.finalPose[static_cast<std::size_t>(j)];
            const Eigen::Quaterniond qj(jp.quaternion[0], jp.quaternion[1], jp.quaternion[2], jp.quaternion[3]);
            const Eigen::Vector3d pj(jp.position[0], jp.position[1], jp.position[2]);
            jointsWorld.push_back({(qe * qj).toRotationMatrix(), qe * pj + pe});
            REQUIRE(world.count(jp.name));
            worstJoint =
                std::max(worstJoint, distance(origin(world[jp.name]), gltfFromDoom(jointsWorld.back().position)));
        }
        CHECK(worstJoint < 1e-4);

        double worstBody = 0;
        for (std::size_t b = 0; b < figure.bodies.size(); ++b) {
            const std::string name = "body_" + figure.bodies[b].name;
            REQUIRE(world.count(name));
            const aiMatrix4x4& m = world[name];
            const Transform& expected = atFrame.firstBodies[b];
            worstBody = std::max(worstBody, distance(origin(m), gltfFromDoom(expected.position)));
            // The body's local +X axis, a metre out: catches a rotation that the position alone would not.
            const aiVector3D tip = m * aiVector3D(0, 0, 1); // glTF +Z = Doom +X
            worstBody = std::max(worstBody, distance(tip, gltfFromDoom(expected.apply(Eigen::Vector3d::UnitX()))));
        }
        CHECK(worstBody < 1e-4);

        // glTF's skinning (Σ weight · joint world × inverse bind × bind vertex, at most four weights) must give the
        // md5 skin (pose::skin: Σ bias · joint world × the weight's own offset) of the drop at that frame. Exact for
        // vertices on one joint; for blended ones because the bundled mesh, like an exporter's, derives every
        // weight's offset from one bind-pose point. Vertices are matched by their bind positions.
        const double mpu = figure.units.metresPerUnit;
        const std::vector<Transform> bind = afb::figure::toMetres(figure.skeleton.bindPose(), mpu);
        const auto bindVerts = afb::pose::skin(loaded.mesh, bind, mpu);
        const Transform entity{qe.toRotationMatrix(), pe};
        std::vector<Transform> jointsModel;
        for (const Transform& w : jointsWorld) jointsModel.push_back(entity.inverse() * w);
        const auto posedVerts = afb::pose::skin(loaded.mesh, jointsModel, mpu);
        struct Expected {
            Eigen::Vector3d posedWorld; // Doom axes
            bool oneJoint;
        };
        std::map<std::tuple<float, float, float>, Expected> expected; // by bind position, glTF axes
        for (std::size_t s = 0; s < loaded.mesh.meshes.size(); ++s) {
            const afb::decl::Md5SubMesh& sub = loaded.mesh.meshes[s];
            for (std::size_t v = 0; v < sub.verts.size(); ++v) {
                const afb::decl::Md5Vert& mv = sub.verts[v];
                bool oneJoint = true;
                for (int k = 1; k < mv.weightCount; ++k)
                    oneJoint = oneJoint && sub.weights[std::size_t(mv.firstWeight + k)].joint ==
                                               sub.weights[std::size_t(mv.firstWeight)].joint;
                const aiVector3D b = gltfFromDoom(bindVerts[s][v]);
                expected[{b.x, b.y, b.z}] = {entity.apply(posedVerts[s][v]), oneJoint};
            }
        }
        const aiNode& meshNode = child(*scene->mRootNode, "mesh");
        int rigid = 0, blended = 0;
        double worstRigid = 0, worstBlended = 0;
        for (unsigned m = 0; m < meshNode.mNumMeshes; ++m) {
            const aiMesh& mesh = *scene->mMeshes[meshNode.mMeshes[m]];
            std::vector<aiVector3D> skinned(mesh.mNumVertices, aiVector3D(0, 0, 0));
            for (unsigned b = 0; b < mesh.mNumBones; ++b) {
                const aiBone& bone = *mesh.mBones[b];
                const aiMatrix4x4 jointMatrix = world[bone.mName.C_Str()] * bone.mOffsetMatrix;
                for (unsigned w = 0; w < bone.mNumWeights; ++w) {
                    REQUIRE(bone.mWeights[w].mVertexId < mesh.mNumVertices);
                    const aiVertexWeight& vw = bone.mWeights[w];
                    skinned[vw.mVertexId] += vw.mWeight * (jointMatrix * mesh.mVertices[vw.mVertexId]);
                }
            }
            for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
                const aiVector3D& b = mesh.mVertices[v];
                const auto it = expected.find({b.x, b.y, b.z});
                REQUIRE(it != expected.end());
                const double d = distance(skinned[v], gltfFromDoom(it->second.posedWorld));
                if (it->second.oneJoint) {
                    worstRigid = std::max(worstRigid, d);
                    ++rigid;
                } else {
                    worstBlended = std::max(worstBlended, d);
                    ++blended;
                }
            }
        }
        CHECK(rigid > 100);
        CHECK(blended > 100);
        CHECK(worstRigid < 1e-4);
        CHECK(worstBlended < 1e-4);
    }
}

TEST_CASE("gltf replay: bad input gives an error and no file, never a crash", "[sim][gltf]") {
    const afb::figure::LoadedFigure loaded = afb::test::loadEntity("chain");
    afb::sim::DropRecording recording;
    (void)afb::sim::runDrop(loaded.figure, dropOptions(5), afb::sim::recordInto(recording, 60.0));
    REQUIRE(recording.frames.size() == 6);
    TempFile file("chain.glb");

    SECTION("a frame without one pose per body") {
        recording.frames[3].pop_back();
        const auto r = afb::sim::writeGltfReplay(loaded.figure, loaded.mesh, recording, file.path);
        CHECK(r.error);
        CHECK_FALSE(fs::exists(file.path));
    }
    SECTION("a mesh that is not the figure's") {
        const afb::figure::LoadedFigure other = afb::test::loadEntity("humanoid");
        const auto r = afb::sim::writeGltfReplay(loaded.figure, other.mesh, recording, file.path);
        CHECK(r.error);
        CHECK_FALSE(fs::exists(file.path));
    }
    SECTION("a weight on a joint that does not exist") {
        afb::decl::Md5Mesh broken = loaded.mesh;
        REQUIRE_FALSE(broken.meshes.empty());
        REQUIRE_FALSE(broken.meshes[0].weights.empty());
        broken.meshes[0].weights[0].joint = 999;
        const auto r = afb::sim::writeGltfReplay(loaded.figure, broken, recording, file.path);
        CHECK(r.error);
    }
    SECTION("no frames, or no frame time") {
        afb::sim::DropRecording empty;
        CHECK(afb::sim::writeGltfReplay(loaded.figure, loaded.mesh, empty, file.path).error);
        recording.frameSeconds = std::numeric_limits<double>::quiet_NaN();
        CHECK(afb::sim::writeGltfReplay(loaded.figure, loaded.mesh, recording, file.path).error);
    }
    SECTION("a folder that does not exist: assimp's failure is reported") {
        const auto r = afb::sim::writeGltfReplay(loaded.figure, loaded.mesh, recording,
                                                 file.path.parent_path() / "afb_no_such_folder" / "x.glb");
        REQUIRE(r.error);
        CHECK_THAT(*r.error, Catch::Contains("assimp could not write"));
    }
    SECTION("an exploded pose ends the replay where the pose stopped being finite") {
        recording.frames[4][0].position.x() = std::numeric_limits<double>::infinity();
        const auto r = afb::sim::writeGltfReplay(loaded.figure, loaded.mesh, recording, file.path);
        REQUIRE_FALSE(r.error);
        CHECK(r.frames == 4);
        CHECK(r.framesDropped == 2);
        Assimp::Importer importer;
        const aiScene* scene = importer.ReadFile(file.path.string(), 0);
        REQUIRE(scene);
        REQUIRE(scene->mNumAnimations == 1);
        CHECK(scene->mAnimations[0]->mChannels[0]->mNumPositionKeys == 4);
    }
}
