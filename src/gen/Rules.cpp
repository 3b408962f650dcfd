// afb gen's rules: the built-in humanoid template and the JSON file that overrides it.
#include <regex>
#include <set>

#include <nlohmann/json.hpp>

#include "afb/gen/Generate.h"
#include "afb/text/Files.h"

namespace afb::gen {
namespace {

JointTemplate universal(std::string role, std::string pattern, double coneDeg, double tiltDeg = 0,
                        std::string toward = {}, double friction = 0.4) {
    JointTemplate t;
    t.role = std::move(role);
    t.pattern = std::move(pattern);
    t.type = decl::ConstraintType::Universal;
    t.coneDeg = coneDeg;
    t.tiltDeg = tiltDeg;
    t.tiltToward = std::move(toward);
    t.friction = friction;
    return t;
}

JointTemplate hinge(std::string role, std::string pattern, double minDeg, double maxDeg, std::string bend) {
    JointTemplate t;
    t.role = std::move(role);
    t.pattern = std::move(pattern);
    t.type = decl::ConstraintType::Hinge;
    t.minDeg = minDeg;
    t.maxDeg = maxDeg;
    t.bend = std::move(bend);
    return t;
}

struct RulesError {
    std::string message;
};

void checkRegex(const std::string& pattern) {
    try {
        std::regex re(pattern, std::regex::ECMAScript | std::regex::icase);
    } catch (const std::regex_error& e) {
        throw RulesError{"bad regular expression \"" + pattern + "\": " + e.what()};
    }
}

double number(const nlohmann::json& v, const std::string& key) {
    if (!v.is_number()) throw RulesError{"\"" + key + "\" must be a number"};
    const double d = v.get<double>();
    if (!std::isfinite(d)) throw RulesError{"\"" + key + "\" must be finite"};
    return d;
}

std::string string(const nlohmann::json& v, const std::string& key) {
    if (!v.is_string()) throw RulesError{"\"" + key + "\" must be a string"};
    return v.get<std::string>();
}

std::vector<std::string> patterns(const nlohmann::json& v, const std::string& key) {
    if (!v.is_array()) throw RulesError{"\"" + key + "\" must be a list of regular expressions"};
    std::vector<std::string> out;
    for (const auto& e : v) {
        out.push_back(string(e, key));
        checkRegex(out.back());
    }
    return out;
}

JointTemplate jointTemplate(const nlohmann::json& j, JointTemplate t, const std::string& where) {
    if (!j.is_object()) throw RulesError{where + " must be an object"};
    for (const auto& [key, v] : j.items()) {
        const std::string k = where + "." + key;
        if (key == "role") t.role = string(v, k);
        else if (key == "pattern") {
            t.pattern = string(v, k);
            checkRegex(t.pattern);
        } else if (key == "type") {
            const std::string s = string(v, k);
            if (s == "universal") t.type = decl::ConstraintType::Universal;
            else if (s == "hinge") t.type = decl::ConstraintType::Hinge;
            else if (s == "ballAndSocket") t.type = decl::ConstraintType::BallAndSocket;
            else if (s == "fixed") t.type = decl::ConstraintType::Fixed;
            else throw RulesError{"\"" + k + "\" must be universal, hinge, ballAndSocket or fixed"};
        } else if (key == "coneDeg") {
            t.coneDeg = number(v, k);
            if (t.coneDeg < 0 || t.coneDeg > 360) throw RulesError{"\"" + k + "\" must be in [0, 360]"};
        } else if (key == "tiltDeg") t.tiltDeg = number(v, k);
        else if (key == "tiltToward") {
            t.tiltToward = string(v, k);
            if (!t.tiltToward.empty() && t.tiltToward != "down" && t.tiltToward != "up" && t.tiltToward != "forward" &&
                t.tiltToward != "back")
                throw RulesError{"\"" + k + "\" must be down, up, forward or back"};
        } else if (key == "minDeg") t.minDeg = number(v, k);
        else if (key == "maxDeg") t.maxDeg = number(v, k);
        else if (key == "bend") {
            t.bend = string(v, k);
            if (t.bend != "back" && t.bend != "forward") throw RulesError{"\"" + k + "\" must be back or forward"};
        } else if (key == "friction") {
            t.friction = number(v, k);
            if (t.friction < 0) throw RulesError{"\"" + k + "\" must be >= 0"};
        } else throw RulesError{"unknown key \"" + k + "\""};
    }
    if (t.type == decl::ConstraintType::Hinge && !(t.minDeg < t.maxDeg && t.maxDeg - t.minDeg <= 360))
        throw RulesError{where + ": a hinge needs minDeg < maxDeg, at most 360 apart"};
    return t;
}

} // namespace

GenRules defaultRules() {
    GenRules r;
    r.merge = {"fing|thumb|thm_|index|middle[^a-z]|ring|pinky|pinkie|digit|claw",       // fingers
               "toe|ball",                                                              // toes
               "tip|nub|_end$|\\.end$|end_site",                                        // end points
               "twist|roll|helper|_ik|ik_|^ik|pole|target",                             // twist, helper, IK bones
               "pad|rib|belly|breast|gun|weapon|sword|sheath|shield|lamp|prop|holster", // attachments
               "hand|wrist|palm|ankle|foot|feet",                                       // into forearm and shin
               "jaw|eye|lid|brow|tongue|teeth|hair|pony|^ear|[_.]ear"};                 // into the head
    r.keep = {"head|skull"};
    r.skip = {"gun|weapon|sword|sheath|shield|lamp|prop|holster"};
    r.shapes = {"box", "cylinder", "dodecahedron", "octahedron", "bone"};
    r.joints = {
        hinge("knee", "knee|shin|calf|loleg|lowleg|lower_?leg|leg_?lo|crus", -5, 130, "back"),
        hinge("elbow", "elbo|forearm|fore_arm|loarm|lowarm|lower_?arm|arm_?lo|ulna", -5, 140, "forward"),
        universal("spine", "spine|chest|torso|waist|back|abdomen|pelvis|hips|body|middle|shoulders", 60),
        universal("hip", "hip|thigh|upleg|upper_?leg|leg_?up|femur", 100, 25, "forward"),
        universal("shoulder", "shoulder|shldr|sholda|clavicle|clav|collar|uparm|upper_?arm|arm_?up|humerus|arm", 120,
                  45, "down", 0.5),
        universal("wrist", "wrist|hand|palm", 90),
        universal("ankle", "ankle|foot", 60),
        universal("neck", "neck", 60),
        universal("head", "head|skull", 60),
    };
    r.fallback = universal("", "", 60);
    return r;
}

std::optional<GenRules> parseRules(const std::string& json, const std::string& fileName,
                                   text::Diagnostics& diagnostics) {
    GenRules r = defaultRules();
    try {
        const nlohmann::json doc = nlohmann::json::parse(json);
        if (!doc.is_object()) throw RulesError{"the rules must be a JSON object"};
        for (const auto& [key, v] : doc.items()) {
            if (key == "weightThreshold") {
                r.weightThreshold = number(v, key);
                if (r.weightThreshold <= 0 || r.weightThreshold > 1)
                    throw RulesError{"\"weightThreshold\" must be in (0, 1]"};
            } else if (key == "merge") r.merge = patterns(v, key);
            else if (key == "keep") r.keep = patterns(v, key);
            else if (key == "skip") r.skip = patterns(v, key);
            else if (key == "skipSurfaces") r.skipSurfaces = patterns(v, key);
            else if (key == "strayFactor") {
                r.strayFactor = number(v, key);
                if (r.strayFactor < 0 || r.strayFactor > 1000) throw RulesError{"\"strayFactor\" must be in [0, 1000]"};
            } else if (key == "maxMergeGrowth") {
                r.maxMergeGrowth = number(v, key);
                if (r.maxMergeGrowth != 0 && !(r.maxMergeGrowth >= 1 && r.maxMergeGrowth <= 1000))
                    throw RulesError{"\"maxMergeGrowth\" must be 0 (off) or in [1, 1000]"};
            } else if (key == "maxPropGrowth") {
                r.maxPropGrowth = number(v, key);
                if (r.maxPropGrowth != 0 && !(r.maxPropGrowth >= 1 && r.maxPropGrowth <= 1000))
                    throw RulesError{"\"maxPropGrowth\" must be 0 (off) or in [1, 1000]"};
            } else if (key == "propRadius") {
                r.propRadius = number(v, key);
                if (!(r.propRadius >= 1 && r.propRadius <= 1000))
                    throw RulesError{"\"propRadius\" must be in [1, 1000]"};
            } else if (key == "minVertexFraction") {
                r.minVertexFraction = number(v, key);
                if (r.minVertexFraction < 0 || r.minVertexFraction >= 1)
                    throw RulesError{"\"minVertexFraction\" must be in [0, 1)"};
            } else if (key == "minBodyFraction") {
                r.minBodyFraction = number(v, key);
                if (r.minBodyFraction < 0 || r.minBodyFraction >= 1)
                    throw RulesError{"\"minBodyFraction\" must be in [0, 1)"};
            } else if (key == "minVolumeRatio") {
                r.minVolumeRatio = number(v, key);
                if (r.minVolumeRatio < 0 || r.minVolumeRatio >= 1)
                    throw RulesError{"\"minVolumeRatio\" must be in [0, 1)"};
            } else if (key == "minVertices") {
                if (!v.is_number_integer() || v.get<long long>() < 0 || v.get<long long>() > 1000000)
                    throw RulesError{"\"minVertices\" must be an integer in [0, 1000000]"};
                r.minVertices = v.get<int>();
            } else if (key == "shapes") {
                r.shapes.clear();
                if (!v.is_array() || v.empty()) throw RulesError{"\"shapes\" must be a non-empty list"};
                for (const auto& s : v) {
                    const std::string name = string(s, key);
                    static const std::set<std::string> known = {"box", "cylinder", "dodecahedron", "octahedron",
                                                                "bone"};
                    if (!known.count(name)) throw RulesError{"unknown shape \"" + name + "\" in \"shapes\""};
                    r.shapes.push_back(name);
                }
            } else if (key == "densityKgM3") {
                r.densityKgM3 = number(v, key);
                if (r.densityKgM3 <= 0 || r.densityKgM3 > 1e5) throw RulesError{"\"densityKgM3\" must be in (0, 1e5]"};
            } else if (key == "forward") {
                if (!v.is_array() || v.size() != 3) throw RulesError{"\"forward\" must be [x, y, z]"};
                Eigen::Vector3d f(number(v[0], key), number(v[1], key), number(v[2], key));
                if (f.norm() < 1e-9) throw RulesError{"\"forward\" must not be zero"};
                r.forward = f.normalized();
            } else if (key == "joints") {
                if (!v.is_array()) throw RulesError{"\"joints\" must be a list"};
                std::vector<JointTemplate> mine;
                for (std::size_t i = 0; i < v.size(); ++i) {
                    mine.push_back(jointTemplate(v[i], JointTemplate{}, "joints[" + std::to_string(i) + "]"));
                    if (mine.back().pattern.empty())
                        throw RulesError{"joints[" + std::to_string(i) + "] needs a pattern"};
                }
                r.joints.insert(r.joints.begin(), mine.begin(), mine.end());
            } else if (key == "fallback") r.fallback = jointTemplate(v, r.fallback, "fallback");
            else throw RulesError{"unknown key \"" + key + "\""};
        }
    } catch (const RulesError& e) {
        diagnostics.error({fileName, 0, 0}, e.message);
        return std::nullopt;
    } catch (const nlohmann::json::exception& e) {
        diagnostics.error({fileName, 0, 0}, std::string("not valid JSON: ") + e.what());
        return std::nullopt;
    }
    return r;
}

std::optional<GenRules> loadRules(const std::filesystem::path& path, text::Diagnostics& diagnostics) {
    const std::optional<std::string> text = text::readFile(path, diagnostics);
    if (!text) return std::nullopt;
    return parseRules(*text, path.string(), diagnostics);
}

} // namespace afb::gen
