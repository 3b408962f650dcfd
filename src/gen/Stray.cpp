// afb gen: vertices no body is fitted to. A prop or attachment weighted to a body bone (a helmet crest, a pack, an
// axe skinned to the hand) would otherwise stretch that bone's body over it; the skipSurfaces rule names such
// meshes, and the strayFactor rule finds them by distance, with statistics that a few far vertices cannot move.
#include <algorithm>
#include <cmath>
#include <regex>

#include "Fit.h"
#include "afb/gen/Generate.h"

namespace afb::gen {
namespace detail {
namespace {

double segmentDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    const Eigen::Vector3d ab = b - a;
    const double len2 = ab.squaredNorm();
    const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    return (a + t * ab - p).norm();
}

} // namespace

double median(std::vector<double> values) {
    const std::size_t mid = values.size() / 2;
    std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(mid), values.end());
    const double upper = values[mid];
    if (values.size() % 2 == 1) return upper;
    return (upper + *std::max_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(mid))) / 2;
}

double boneDistance(const Rig& rig, int joint, const Eigen::Vector3d& p) {
    const Eigen::Vector3d head = rig.joints[static_cast<std::size_t>(joint)].bind.position;
    double d = INFINITY;
    bool leaf = true;
    for (const RigJoint& c : rig.joints)
        if (c.parent == joint) {
            d = std::min(d, segmentDistance(p, head, c.bind.position));
            leaf = false;
        }
    return leaf ? segmentDistance(p, head, head) : d;
}

} // namespace detail

namespace {

using detail::median;

constexpr double kMadToSigma = 1.4826; // the median absolute deviation of a normal distribution, in σ
// A vertex this close to its bone's median distance, as a fraction of the model's height, is never stray: a bone
// whose skin hugs it (a median near zero) would otherwise lose its next ring of vertices.
constexpr double kMinStrayFraction = 0.1;

int topJoint(const RigVertex& v) {
    const auto top = std::max_element(v.influences.begin(), v.influences.end(),
                                      [](const RigInfluence& a, const RigInfluence& b) { return a.weight < b.weight; });
    return top == v.influences.end() ? -1 : top->joint;
}

bool surfaceSkipped(const RigSurface& s, const std::vector<std::regex>& patterns) {
    return std::any_of(patterns.begin(), patterns.end(), [&](const std::regex& re) {
        return std::regex_search(s.name, re) || (!s.material.empty() && std::regex_search(s.material, re));
    });
}

struct Sample {
    std::size_t surface = 0, vertex = 0;
    double distance = 0;
};

// The far vertices of one bone's samples, marked in `stray`, with a report when there are any.
void markFar(const std::vector<Sample>& samples, double factor, double height, std::vector<std::vector<bool>>& stray,
             StrayVertices& report) {
    std::vector<double> d;
    for (const Sample& s : samples) d.push_back(s.distance);
    const double m = median(d);
    std::vector<double> deviation;
    for (double x : d) deviation.push_back(std::abs(x - m));
    // The spread never counts as less than half the median: a bone whose vertices sit all at one radius (a tube
    // round it) has a deviation near zero, and the next ring out is no prop.
    const double spread = std::max(kMadToSigma * median(deviation), m / 2);
    const double limit = m + std::max(factor * spread, kMinStrayFraction * height);
    report.boneVertices = static_cast<int>(samples.size());
    report.medianM = m * kMetresPerDoomUnit;
    report.limitM = limit * kMetresPerDoomUnit;
    double nearest = INFINITY, farthest = 0;
    for (const Sample& s : samples)
        if (s.distance > limit) {
            stray[s.surface][s.vertex] = true;
            ++report.vertices;
            nearest = std::min(nearest, s.distance);
            farthest = std::max(farthest, s.distance);
        }
    if (report.vertices > 0) {
        report.nearestM = nearest * kMetresPerDoomUnit;
        report.farthestM = farthest * kMetresPerDoomUnit;
    }
}

} // namespace

std::vector<std::vector<bool>> strayVertices(const Rig& rig, const GenRules& rules,
                                             std::vector<StrayVertices>& report) {
    std::vector<std::vector<bool>> stray;
    std::vector<std::regex> skipRe;
    for (const std::string& p : rules.skipSurfaces) skipRe.emplace_back(p, std::regex::ECMAScript | std::regex::icase);
    const std::size_t n = rig.joints.size();
    std::vector<std::vector<Sample>> byJoint(n);
    for (std::size_t si = 0; si < rig.surfaces.size(); ++si) {
        const RigSurface& s = rig.surfaces[si];
        stray.emplace_back(s.vertices.size(), false);
        if (surfaceSkipped(s, skipRe)) {
            std::fill(stray.back().begin(), stray.back().end(), true);
            StrayVertices r;
            r.rule = "skipSurfaces";
            r.surface = s.name.empty() ? s.material : s.name;
            r.vertices = static_cast<int>(s.vertices.size());
            report.push_back(r);
            continue;
        }
        for (std::size_t vi = 0; vi < s.vertices.size(); ++vi) {
            const int j = topJoint(s.vertices[vi]);
            if (j >= 0 && static_cast<std::size_t>(j) < n) byJoint[static_cast<std::size_t>(j)].push_back({si, vi, 0});
        }
    }
    if (!(rules.strayFactor > 0)) return stray;
    const double height = modelHeight(rig);
    for (std::size_t j = 0; j < n; ++j) {
        std::vector<Sample>& samples = byJoint[j];
        if (samples.size() < detail::kMinMedianVertices) continue;
        // The bone: segments from its joint to each child joint, or its joint alone.
        for (Sample& sample : samples)
            sample.distance = detail::boneDistance(rig, static_cast<int>(j),
                                                   rig.surfaces[sample.surface].vertices[sample.vertex].position);
        StrayVertices r;
        r.rule = "strayFactor";
        r.joint = rig.joints[j].name;
        markFar(samples, rules.strayFactor, height, stray, r);
        if (r.vertices > 0) report.push_back(r);
    }
    return stray;
}

} // namespace afb::gen
