// afb draw: a headless picture of a figure, in its load pose or in the pose of a drop at a given time.
#include <cmath>
#include <cstdio>
#include <iostream>

#include "Commands.h"
#include "MethodOptions.h"
#include "Picture.h"
#include "Usage.h"
#include "afb/figure/Load.h"
#include "afb/pose/SkeletonDriver.h"
#include "afb/sim/Drop.h"

namespace afb::cli {
namespace {

std::vector<View> parseViews(const std::vector<std::string>& names) {
    std::vector<View> views;
    for (const std::string& n : names)
        views.push_back(n == "front" ? View::Front : n == "side" ? View::Side : View::Top);
    return views;
}

PictureLayers parseLayers(const std::vector<std::string>& names) {
    PictureLayers show{false, false, false, false, false, false};
    for (const std::string& n : names) {
        if (n == "bodies") show.bodies = true;
        if (n == "joints") show.joints = true;
        if (n == "limits") show.limits = true;
        if (n == "mass") show.mass = true;
        if (n == "skeleton") show.skeleton = true;
        if (n == "names") show.names = true;
    }
    return show;
}

std::string describeDrop(const sim::DropOptions& drop) {
    char buf[160];
    const int steps = drop.steps.value_or(0);
    std::snprintf(buf, sizeof buf, "drop from %g m, t = %.3f s (%d steps at %g Hz)", drop.heightM, steps / drop.hz,
                  steps, drop.hz);
    return buf;
}

struct DrawCli {
    std::filesystem::path base = ".";
    std::string entity;
    std::filesystem::path out;
    std::vector<std::string> views{"front", "side", "top"};
    std::vector<std::string> show{"bodies", "joints", "limits", "mass", "skeleton"};
    std::optional<double> atSeconds;
    sim::DropOptions drop;
    std::shared_ptr<MethodOptions> method = std::make_shared<MethodOptions>();
    bool doomGravity = false, noSleep = false;
};

void addDrawOptions(CLI::App* cmd, DrawCli& opt) {
    cmd->add_option("entity", opt.entity, "entityDef to draw")->required();
    cmd->add_option("--base", opt.base, "Content folder (af/, def/, models/)")->capture_default_str();
    cmd->add_option("--out", opt.out, "The picture: FILE.png or FILE.svg")->required();
    cmd->add_option("--view", opt.views, "Views, left to right")
        ->delimiter(',')
        ->check(CLI::IsMember({"front", "side", "top"}))
        ->capture_default_str();
    cmd->add_option("--show", opt.show, "Layers to draw")
        ->delimiter(',')
        ->check(CLI::IsMember({"bodies", "joints", "limits", "mass", "skeleton", "names"}))
        ->capture_default_str();
    cmd->add_option("--at", opt.atSeconds, "Draw the pose of a drop at this time, s (default: the load pose)")
        ->check(nonNegative());
    cmd->add_option("--height", opt.drop.heightM, "Drop: height of the lowest point at spawn, m")
        ->check(nonNegative())
        ->capture_default_str();
    cmd->add_option("--hz", opt.drop.hz, "Drop: fixed step rate")->check(positive())->capture_default_str();
    addMethodOptions(cmd, opt.method);
    cmd->add_flag("--no-sleep", opt.noSleep, "Drop: never put the figure to rest");
    cmd->add_flag("--doom-gravity", opt.doomGravity, "Drop: Doom's gravity, 1066 units/s², instead of 9.81 m/s²");
}

// The bodies of the first instance of a drop at --at, relative to its spawn (the load pose at step 0, falling
// toward the ground below it afterwards), with the ground when in view.
void dropPose(const DrawCli& opt, const figure::LoadedFigure& loaded, const bullet::Method& method,
              PictureRequest& request) {
    sim::DropOptions drop = opt.drop;
    drop.method = method;
    drop.count = 1;
    drop.worlds = 1;
    drop.steps = static_cast<int>(std::lround(*opt.atSeconds * drop.hz));
    drop.sleeping = !opt.noSleep;
    drop.startAtRest = loaded.startAtRest;
    const sim::DropResult result = sim::runDrop(loaded.figure, drop);
    const figure::Transform toSpawn = result.firstSpawn.inverse();
    for (const figure::Transform& b : result.firstBodies) request.bodies.push_back(toSpawn * b);
    if ((toSpawn.rotation * Eigen::Vector3d::UnitZ()).z() > 1 - 1e-9)
        request.groundZ = toSpawn.position.z(); // the world's z = 0 plane
    request.subtitle = describeDrop(drop);
    if (result.exploded) std::cerr << "afb draw: warning: the figure exploded during the drop\n";
}

int drawCommand(const DrawCli& opt) {
    const std::string extension = opt.out.extension().string();
    if (extension != ".png" && extension != ".svg")
        usageError("--out " + opt.out.string() + ": the picture must be a .png or .svg file");
    // The method is checked before anything runs, though only a drop (--at) uses it.
    const bullet::Method method = resolveMethod(*opt.method);
    if (opt.atSeconds) checkStepCount("--at", *opt.atSeconds, opt.drop.hz);
    figure::UnitSystem units;
    if (opt.doomGravity) units.gravityMps2 = units.doomGravityMps2();
    text::Diagnostics diags;
    auto lib = decl::Library::open(opt.base, diags);
    std::optional<figure::LoadedFigure> loaded;
    if (lib && findEntities(*lib, {opt.entity}, diags))
        loaded = figure::loadEntityFigure(*lib, opt.entity, units, diags);
    printDiagnostics(diags);
    if (!loaded) return kExitFailure;
    const figure::Figure& figure = loaded->figure;
    PictureRequest request;
    request.title = opt.entity;
    request.views = parseViews(opt.views);
    request.show = parseLayers(opt.show);
    if (opt.atSeconds) {
        dropPose(opt, *loaded, method, request);
    } else {
        for (const figure::FigureBody& b : figure.bodies) request.bodies.push_back(b.loadPose);
        request.subtitle = "load pose";
    }
    request.joints = pose::driveSkeleton(figure, request.bodies).world();
    if (const auto error = drawPicture(figure, request, opt.out)) {
        std::cerr << "afb draw: " << *error << "\n";
        return kExitFailure;
    }
    std::printf("afb draw: %s (%s) -> %s\n", opt.entity.c_str(), request.subtitle.c_str(), opt.out.c_str());
    return 0;
}

} // namespace

void addDrawCommand(CLI::App& app, int& exitCode) {
    auto* cmd = app.add_subcommand("draw", "A picture of a figure (PNG or SVG): bodies, md5 skeleton, constraint "
                                           "anchors, limits and masses, in its load pose or during a drop\n"
                                           "Examples:\n  afb draw --base . humanoid --out humanoid.png\n"
                                           "  afb draw --base . humanoid --out names.svg --view side --show "
                                           "bodies,skeleton,names");
    cmd->footer("Views are orthographic, at one scale, side by side: front (from +X, the way Doom models face), side "
                "(from -Y) and top (from +Z). With --at, the figure is drawn in the pose of `afb drop` at that time "
                "(the first instance, relative to its spawn: --at 0 is the load pose) and the ground is shown when "
                "it is in view.");
    auto opt = std::make_shared<DrawCli>();
    addDrawOptions(cmd, *opt);
    cmd->callback([opt, &exitCode] { exitCode = drawCommand(*opt); });
}

} // namespace afb::cli
