// afb track: a powered ragdoll following an animation (looped) with its motors; how closely it follows, how it takes
// a hit and what it costs.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <regex>

#include "Commands.h"
#include "MethodOptions.h"
#include "Suggest.h"
#include "Usage.h"
#include "afb/figure/Load.h"
#include "afb/sim/GltfReplay.h"
#include "afb/sim/RawRagdoll.h"
#include "afb/sim/Report.h"
#include "afb/sim/Track.h"

namespace afb::cli {
namespace {

/// The options of `afb track`.
struct TrackCli {
    std::filesystem::path base = ".";
    std::string entity;
    std::filesystem::path anim;
    std::string root = "keyframed";
    std::string hit; ///< BODY:NS@SECONDS as given
    sim::TrackOptions track;
    std::shared_ptr<MethodOptions> method = std::make_shared<MethodOptions>();
    std::string json, csv;
    std::filesystem::path gltf;
    bool strict = false, verbose = false;
};

/// --hit as parsed, the body still a name.
struct HitSpec {
    std::string body;
    double impulseNs = 0, atSeconds = 0;
};

void addTrackOptions(CLI::App* cmd, TrackCli& opt) {
    cmd->add_option("entity", opt.entity, "entityDef to track the animation with")->required();
    cmd->add_option("--base", opt.base, "Content folder (af/, def/, models/)")->capture_default_str();
    cmd->add_option("--anim", opt.anim,
                    "The md5anim to follow, looped (a path; a relative one not found here is looked up under --base)")
        ->required();
    cmd->add_option("--root", opt.root,
                    "keyframed: body 0 (the pelvis) follows the animation exactly, the rest is powered, hanging in "
                    "the air; free: the legs (the subtrees hanging below body 0) follow it exactly and the rest, "
                    "body 0 included, is powered, on a ground")
        ->check(CLI::IsMember({"keyframed", "free"}))
        ->capture_default_str();
    cmd->add_option("--strength", opt.track.strength,
                    "Scale of every motor gain (stiffness and damping): 1 the default gains (15 Hz, damping "
                    "ratio 4), 0 limp")
        ->check(nonNegative())
        ->capture_default_str();
    cmd->add_option("--hit", opt.hit,
                    "BODY:NS@SECONDS: an impulse of NS newton-seconds along world +X (the figure's forward) at the "
                    "centre of mass of BODY at that time, the motors limp at once and back to strength over 0.5 s; "
                    "after the 0.5 s warm-up");
    cmd->add_option("--seconds", opt.track.seconds, "Simulated time, s")->check(positive())->capture_default_str();
    cmd->add_option("--hz", opt.track.hz, "Fixed frame rate")->check(positive())->capture_default_str();
    addMethodOptions(cmd, opt.method);
    cmd->add_flag("--strict", opt.strict, "Refuse values the builder would repair (docs/format.md: hostile numbers)");
    cmd->add_flag("--verbose", opt.verbose, "Print every knob of the method (JSON and CSV reports always have them)");
    cmd->add_option("--json", opt.json,
                    "Write the result as JSON to this file ('-': stdout, which then holds only the JSON)");
    cmd->add_option("--csv", opt.csv,
                    "Write the result as CSV to this file ('-': stdout, which then holds only the CSV)");
    cmd->add_option("--gltf", opt.gltf,
                    "Record the run as a glTF 2.0 binary (FILE.glb) as afb drop --gltf does: the skinned mesh, the "
                    "body hulls, the ground and one animation at the step rate");
}

/// --hit's text, or a usage error.
HitSpec parseHit(const std::string& text) {
    static const std::regex form(R"(^(.+):([^:@]+)@([^:@]+)$)");
    std::smatch m;
    if (!std::regex_match(text, m, form)) usageError("--hit: '" + text + "' is not BODY:NS@SECONDS");
    HitSpec hit;
    hit.body = m[1].str();
    try {
        const std::string ns = m[2].str(), seconds = m[3].str();
        std::size_t used = 0;
        hit.impulseNs = std::stod(ns, &used);
        if (used != ns.size()) throw std::invalid_argument("trailing text");
        hit.atSeconds = std::stod(seconds, &used);
        if (used != seconds.size()) throw std::invalid_argument("trailing text");
    } catch (const std::exception&) {
        usageError("--hit: '" + text + "': NS and SECONDS must be numbers");
    }
    if (!std::isfinite(hit.impulseNs) || !std::isfinite(hit.atSeconds))
        usageError("--hit: '" + text + "': NS and SECONDS must be finite");
    return hit;
}

void checkTrackOptions(TrackCli& opt, const bullet::Method& method) {
    checkStepCount("--seconds", opt.track.seconds, opt.track.hz);
    if (opt.json == "-" && opt.csv == "-") usageError("--json - and --csv - both ask for stdout; give one a file");
    if (sim::isRaw(method) || method.backend != bullet::Backend::Rigid)
        usageError("afb track needs the rigid backend (motors and keyframed bodies; not the raw method or the "
                   "multibody backend)");
    if (!opt.hit.empty()) {
        const HitSpec hit = parseHit(opt.hit);
        if (!(hit.atSeconds > opt.track.warmupSeconds && hit.atSeconds < opt.track.seconds))
            usageError("--hit: the time must lie after the 0.5 s warm-up and before --seconds");
    }
    if (opt.gltf.empty()) return;
    std::string ext = opt.gltf.extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (ext != ".glb") usageError("--gltf must name a .glb file");
}

/// The body named `name` (case ignored, as the engine compares names), or an error naming the nearest.
std::optional<int> findBody(const figure::Figure& figure, const std::string& name, std::string& error) {
    std::vector<std::string> names;
    const auto lower = [](std::string s) {
        for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
        return s;
    };
    for (std::size_t b = 0; b < figure.bodies.size(); ++b) {
        if (lower(figure.bodies[b].name) == lower(name)) return static_cast<int>(b);
        names.push_back(figure.bodies[b].name);
    }
    error = unknownName("body", name, names) + " in --hit (figure '" + figure.name + "')";
    return std::nullopt;
}

std::filesystem::path animPath(const TrackCli& opt) {
    if (opt.anim.is_absolute() || std::filesystem::exists(opt.anim)) return opt.anim;
    if (const auto under = opt.base / opt.anim; std::filesystem::exists(under)) return under;
    return opt.anim; // not found: the loader says so
}

std::FILE* trackTextStream(const TrackCli& opt) { return opt.json == "-" || opt.csv == "-" ? stderr : stdout; }

void printTrackHeader(const TrackCli& opt, const std::filesystem::path& anim, double gravity) {
    std::FILE* text = trackTextStream(opt);
    const bullet::Method& m = opt.track.method;
    const std::string methodLine =
        opt.verbose ? bullet::describe(m) : methodSpec(m) + " (every knob: --verbose, or afb methods " + m.name + ")";
    std::fprintf(text, "afb track: Bullet %s (%s), %g Hz, gravity %.3f m/s²\n  method %s\n  animation %s, looped\n",
                 sim::bulletVersion().c_str(), sim::bulletPrecision(), opt.track.hz, gravity, methodLine.c_str(),
                 anim.string().c_str());
    std::fflush(text);
}

void printTrackTable(const TrackCli& opt, const sim::TrackResult& r) {
    std::FILE* out = trackTextStream(opt);
    std::fprintf(out, "  root %s (%s); keyframed:", toString(r.root),
                 r.root == sim::TrackRoot::Free ? "on a ground" : "in the air");
    for (const std::string& b : r.keyframed) std::fprintf(out, " %s", b.c_str());
    std::fprintf(out, "\n  motors %.3g Hz, damping ratio %.3g (strength %g); loop %.3f s\n", r.gains.frequencyHz,
                 r.gains.dampingRatio, r.strength, r.loopSeconds);
    std::fprintf(out, "\n%-32s %6s %7s %9s %9s %9s %9s %10s %8s %9s\n", "entity", "bodies", "steps", "rms m", "max m",
                 "rms deg", "max deg", "recovery s", "exploded", "us/body");
    const std::string recovery = r.recoveryS ? std::to_string(*r.recoveryS).substr(0, 6) : r.hitAtS ? "never" : "-";
    std::fprintf(out, "%-32s %6d %7d %9.4f %9.4f %9.2f %9.2f %10s %8s %9.2f\n", opt.entity.c_str(), r.bodies, r.steps,
                 r.trackingRmsM, r.trackingMaxM, r.trackingRmsDeg, r.trackingMaxDeg, recovery.c_str(),
                 r.exploded ? "YES" : "no", r.cpuUsPerAwakeBodyStep);
    std::fprintf(out,
                 "  (rms, max: every md5 joint's world distance and angle from the animation after %g s, worst at "
                 "%s;\n   recovery s: from the hit until the errors are back within their pre-hit bounds; us/body: "
                 "CPU µs per awake body-step; every field: --help)\n",
                 opt.track.warmupSeconds, r.worstJoint.empty() ? "-" : r.worstJoint.c_str());
    if (r.animLimitExcessDeg > 0.5)
        std::fprintf(out,
                     "  the animation itself passes the figure's limits by up to %.1f deg (at %s): no motor follows "
                     "it there\n",
                     r.animLimitExcessDeg, r.animLimitJoint.c_str());
    if (r.animLockedExcessDeg > 0.5)
        std::fprintf(out,
                     "  the animation itself turns a joint about an axis it locks by up to %.1f deg (at %s): no "
                     "motor follows it there\n",
                     r.animLockedExcessDeg, r.animLockedJoint.c_str());
    if (r.hitAtS)
        std::fprintf(out, "  hit: %s at %.3f s; before it the errors stayed within %.4f m and %.2f deg\n",
                     r.hitBody.c_str(), *r.hitAtS, r.preHitMaxM, r.preHitMaxDeg);
    std::fflush(out);
}

void writeTrackReports(const TrackCli& opt, const sim::TrackResult& r, const figure::Figure& figure) {
    const nlohmann::json all = {{"schema", sim::schemaJson(sim::kTrackSchema)},
                                {"bullet", sim::bulletVersion()},
                                {"precision", sim::bulletPrecision()},
                                {"gravity_mps2", figure.units.gravityMps2},
                                {"entity", opt.entity},
                                {"anim", opt.anim.string()},
                                {"scenario", sim::trackOptionsJson(opt.track, figure)},
                                {"runs", nlohmann::json::array({sim::trackResultJson(r)})}};
    if (!opt.json.empty()) writeReport(opt.json, all.dump(2) + "\n");
    if (!opt.csv.empty()) writeReport(opt.csv, sim::trackCsvHeader() + "\n" + sim::trackCsvRow(r) + "\n");
}

bool writeTrackReplay(const TrackCli& opt, const figure::LoadedFigure& loaded, const sim::DropRecording& recording) {
    const sim::GltfReplayResult written = sim::writeGltfReplay(loaded.figure, loaded.mesh, recording, opt.gltf);
    if (written.error) {
        std::cerr << "afb track: --gltf: " << *written.error << "\n";
        return false;
    }
    std::fprintf(trackTextStream(opt), "afb track: replay of %s (%d frames at %g Hz, %d joints, %d bodies) -> %s\n",
                 opt.entity.c_str(), written.frames, opt.track.hz, written.joints, written.bodies, opt.gltf.c_str());
    return true;
}

int runTrackCommand(TrackCli& opt) {
    text::Diagnostics diags;
    auto lib = decl::Library::open(opt.base, diags);
    std::optional<figure::LoadedFigure> loaded;
    if (lib && findEntities(*lib, {opt.entity}, diags))
        loaded = figure::loadEntityFigure(*lib, opt.entity, figure::UnitSystem{}, diags, opt.strict);
    const std::filesystem::path path = animPath(opt);
    const auto anim = loaded ? decl::loadMd5Anim(path, diags) : std::nullopt;
    std::string hitError;
    if (loaded && anim && !opt.hit.empty()) {
        const HitSpec spec = parseHit(opt.hit);
        if (const auto body = findBody(loaded->figure, spec.body, hitError))
            opt.track.hit = sim::TrackHit{*body, spec.impulseNs, spec.atSeconds};
    }
    printDiagnostics(diags);
    if (!hitError.empty()) std::cerr << "afb track: " << hitError << "\n";
    if (!loaded || !anim || !hitError.empty()) return kExitFailure;
    printTrackHeader(opt, path, loaded->figure.units.gravityMps2);
    sim::DropRecording recording;
    sim::DropObserver observer;
    if (!opt.gltf.empty()) observer = sim::recordInto(recording, opt.track.hz);
    const auto result = sim::runTrack(loaded->figure, *anim, opt.track, diags, observer);
    if (!result) {
        printDiagnostics(diags);
        std::cerr << "afb track: " << path.string() << ": the animation does not fit the figure of '" << opt.entity
                  << "'\n";
        return kExitFailure;
    }
    printTrackTable(opt, *result);
    int exitCode = result->exploded ? kExitFailure : 0;
    if (!opt.gltf.empty() && !writeTrackReplay(opt, *loaded, recording)) exitCode = kExitFailure;
    writeTrackReports(opt, *result, loaded->figure);
    return exitCode;
}

} // namespace

void addTrackCommand(CLI::App& app, int& exitCode) {
    auto* cmd = app.add_subcommand(
        "track", "Drive a figure with its joint motors along an animation (looped) and report how closely it follows\n"
                 "Examples:\n"
                 "  afb track --base . humanoid --anim models/md5/humanoid/walk.md5anim\n"
                 "  afb track --base . humanoid --anim models/md5/humanoid/walk.md5anim --root free --json -\n"
                 "  afb track --base . humanoid --anim models/md5/humanoid/walk.md5anim --hit torso:40@2 --seconds 5");
    cmd->footer(sim::trackFieldsHelp());
    auto opt = std::make_shared<TrackCli>();
    addTrackOptions(cmd, *opt);
    cmd->callback([opt, &exitCode] {
        const bullet::Method method = resolveMethod(*opt->method);
        checkTrackOptions(*opt, method);
        opt->track.method = method;
        opt->track.root = opt->root == "free" ? sim::TrackRoot::Free : sim::TrackRoot::Keyframed;
        exitCode = runTrackCommand(*opt);
    });
}

} // namespace afb::cli
