#pragma once
// Procedural rigs for afb_gen_content: a skeleton with identity bind orientations, meshes skinned to it built
// from tubes and boxes, and poses; turned into decl::Md5Mesh / decl::Md5Anim values for the md5 writers.
#include <array>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "afb/decl/Md5Anim.h"
#include "afb/decl/Md5Mesh.h"

namespace afb::gen {

struct Joint {
    std::string name;
    int parent = -1;
    Eigen::Vector3d pos = Eigen::Vector3d::Zero(); ///< model space, bind pose (all bind orientations are identity)
};

struct Skeleton {
    std::vector<Joint> joints;

    /// Appends a joint under `parent` ("" for a root) and returns its index.
    int add(const std::string& name, const std::string& parent, Eigen::Vector3d pos);
    /// Index of the joint named exactly `name`; throws std::runtime_error when there is none.
    int index(const std::string& name) const;
    /// Bind position of the joint named `name`, model space.
    Eigen::Vector3d pos(const std::string& name) const;
};

/// One weight, unrounded (rounded only when written).
struct Weight {
    int joint = 0;
    double bias = 1;
    Eigen::Vector3d offset = Eigen::Vector3d::Zero(); ///< joint-local = model-space offset (identity bind)
};

struct Vert {
    double s = 0, t = 0;
    int firstWeight = 0, count = 0;
};

/// A sub-mesh under construction.
struct Mesh {
    std::string name, shader;
    std::vector<Vert> verts;
    std::vector<std::array<int, 3>> tris;
    std::vector<Weight> weights;

    /// Adds a vertex at model-space `p` skinned to `influences` (joint, bias); returns its index.
    int vertex(const Skeleton& sk, Eigen::Vector3d p, double s, double t,
               const std::vector<std::pair<int, double>>& influences);
};

/// Half-axes (across u, across v) of a tube at t in [0, 1].
using TubeRadius = std::function<Eigen::Vector2d(double)>;

/// Radii varying linearly from (ru0, rv0) at t = 0 to (ru1, rv1) at t = 1.
TubeRadius linear(double ru0, double rv0, double ru1, double rv1);

/// Options of a tube: its skinning and tessellation.
struct TubeSpec {
    int joint = 0;       ///< the joint every vertex is weighted to
    int blendJoint = -1; ///< blended in near `a` (t < 0.25) when >= 0
    int rings = 2;       ///< rings of vertices from a to b
    int sides = 10;      ///< vertices per ring
    bool capA = false;   ///< close the tube at a with a fan
    bool capB = false;   ///< close the tube at b with a fan
};

/// A capsule-like tube from a to b appended to `m`.
void tube(Mesh& m, const Skeleton& sk, Eigen::Vector3d a, Eigen::Vector3d b, const TubeRadius& radius,
          const TubeSpec& spec);

/// A closed box of 8 vertices and 12 triangles, all weighted to one joint.
void boxMesh(Mesh& m, const Skeleton& sk, Eigen::Vector3d lo, Eigen::Vector3d hi, int joint);

/// One pose: parent-relative translation and rotation (standard convention) per joint.
struct Pose {
    std::vector<Eigen::Vector3d> t;
    std::vector<Eigen::Quaterniond> q;
};

/// The bind pose as parent-relative values.
Pose bindPose(const Skeleton& sk);

/// The md5mesh of `meshes` on `sk`, every number rounded to 4 decimals.
decl::Md5Mesh toMd5Mesh(const Skeleton& sk, const std::vector<Mesh>& meshes, const std::string& commandline);

/// An md5anim of full poses `frames`; `animated[j]` holds joint j's component flags (decl::Md5ComponentBit).
/// Translations and bounds are rounded to 4 decimals, quaternion components to 6.
decl::Md5Anim toMd5Anim(const Skeleton& sk, const std::vector<Mesh>& meshes, const std::vector<Pose>& frames,
                        const std::vector<int>& animated, int frameRate, const std::string& commandline);

/// The one-frame af_pose anim: the bind pose, nothing animated, 24 fps.
decl::Md5Anim afPoseAnim(const Skeleton& sk, const std::vector<Mesh>& meshes, const std::string& commandline);

} // namespace afb::gen
