// afb gen MODEL --out DIR: a ragdoll figure from a rigged mesh, written as a content folder.
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <iostream>

#include <sys/wait.h>
#include <unistd.h>

#include "Commands.h"
#include "Usage.h"
#include "afb/gen/Generate.h"
#include "afb/sim/Report.h"

namespace afb::cli {
namespace {

const char* shapeName(decl::ShapeKind k) {
    switch (k) {
    case decl::ShapeKind::Box: return "box";
    case decl::ShapeKind::Octahedron: return "octahedron";
    case decl::ShapeKind::Dodecahedron: return "dodecahedron";
    case decl::ShapeKind::Cylinder: return "cylinder";
    case decl::ShapeKind::Cone: return "cone";
    case decl::ShapeKind::Bone: return "bone";
    }
    return "?";
}

struct GenCliOptions {
    std::filesystem::path model, out, rules;
    std::string name;
    std::optional<double> massKg, unitM, heightM;
    std::string up;
    bool json = false;
};

const char* unitSourceName(gen::RigUnits::Source s) {
    switch (s) {
    case gen::RigUnits::Source::Format: return "format";
    case gen::RigUnits::Source::Option: return "unit-m";
    case gen::RigUnits::Source::Height: return "height";
    case gen::RigUnits::Source::Detected: return "detected";
    }
    return "?";
}

// The scale afb gen chose by itself, said once on stderr (as compilers' notes).
void noteDetectedUnits(const gen::Rig& rig, const std::filesystem::path& model) {
    if (rig.units.source != gen::RigUnits::Source::Detected) return;
    std::fprintf(stderr,
                 "%s: note: the model is %.3g m tall at Doom's 0.0254 m per unit (%.3g in its own units): read as %g m "
                 "per unit, %.3g m tall; --unit-m or --height sets the scale\n",
                 model.string().c_str(), rig.units.fileHeight * 0.0254, rig.units.fileHeight, rig.units.metresPerUnit,
                 rig.units.fileHeight * rig.units.metresPerUnit);
}

nlohmann::json unitsJson(const gen::RigUnits& u) {
    return {{"metresPerUnit", u.metresPerUnit},
            {"source", unitSourceName(u.source)},
            {"up", std::string(1, u.up)},
            {"heightM", u.fileHeight * u.metresPerUnit}};
}

nlohmann::json strayJson(const std::vector<gen::StrayVertices>& stray) {
    nlohmann::json out = nlohmann::json::array();
    for (const auto& s : stray)
        out.push_back({{"rule", s.rule},
                       {"joint", s.joint},
                       {"surface", s.surface},
                       {"body", s.body},
                       {"vertices", s.vertices},
                       {"nearestM", s.nearestM},
                       {"farthestM", s.farthestM},
                       {"medianM", s.medianM},
                       {"limitM", s.limitM},
                       {"growth", s.growth},
                       {"together", s.together}});
    return out;
}

int runGen(const GenCliOptions& opt) {
    text::Diagnostics diags;
    gen::GenOptions options;
    options.name = opt.name.empty() ? gen::figureNameFor(opt.model) : opt.name;
    options.massKg = opt.massKg;
    options.source = opt.model.string();
    options.outDir = opt.out.string();
    if (!opt.rules.empty()) {
        auto rules = gen::loadRules(opt.rules, diags);
        if (!rules) {
            printDiagnostics(diags);
            return 1;
        }
        options.rules = std::move(*rules);
    }
    gen::ImportOptions import;
    import.metresPerUnit = opt.unitM;
    import.heightM = opt.heightM;
    if (!opt.up.empty()) import.up = opt.up[0];
    std::optional<gen::Generated> generated;
    const auto rig = gen::importRig(opt.model, import, diags);
    if (rig) {
        noteDetectedUnits(*rig, opt.model);
        generated = gen::generateFigure(*rig, options, diags);
    }
    if (generated && !gen::writeContent(*generated, opt.out, diags)) generated.reset();
    printDiagnostics(diags);
    if (!generated) {
        return 1;
    }
    const gen::ContentPaths paths = gen::contentPaths(generated->name);
    if (opt.json) {
        nlohmann::json bodies = nlohmann::json::array(), joints = nlohmann::json::array();
        for (const auto& b : generated->bodies)
            bodies.push_back({{"name", b.name},
                              {"joint", b.joint},
                              {"shape", shapeName(b.shape)},
                              {"massKg", b.massKg},
                              {"vertices", b.vertices},
                              {"joints", b.joints.size()}});
        for (const auto& j : generated->joints)
            joints.push_back({{"name", j.name},
                              {"role", j.role},
                              {"body1", generated->bodies[static_cast<std::size_t>(j.body1)].name},
                              {"body2", generated->bodies[static_cast<std::size_t>(j.body2)].name}});
        std::cout << nlohmann::json{{"schema", sim::schemaJson(sim::kGenSchema)},
                                    {"name", generated->name},
                                    {"totalMassKg", generated->totalMassKg},
                                    {"files", {paths.af, paths.def, paths.mesh, paths.afPose}},
                                    {"units", unitsJson(rig->units)},
                                    {"bodies", bodies},
                                    {"constraints", joints},
                                    {"stray", strayJson(generated->stray)}}
                         .dump(2)
                  << "\n";
        return 0;
    }
    std::printf("figure %s: %zu bodies, %zu constraints, %zu md5 joints, total mass %.1f kg\n", generated->name.c_str(),
                generated->bodies.size(), generated->joints.size(), generated->mesh.joints.size(),
                generated->totalMassKg);
    for (const auto& b : generated->bodies)
        std::printf("  body %-16s %-12s %6.2f kg  %5d vertices  %zu joints\n", b.name.c_str(), shapeName(b.shape),
                    b.massKg, b.vertices, b.joints.size());
    for (const auto& j : generated->joints)
        std::printf("  joint %-15s %-9s %s - %s\n", j.name.c_str(), j.role.empty() ? "(default)" : j.role.c_str(),
                    generated->bodies[static_cast<std::size_t>(j.body1)].name.c_str(),
                    generated->bodies[static_cast<std::size_t>(j.body2)].name.c_str());
    std::printf("wrote %s/{%s, %s, %s, %s}\n", opt.out.string().c_str(), paths.af.c_str(), paths.def.c_str(),
                paths.mesh.c_str(), paths.afPose.c_str());
    return 0;
}

// assimp 5.2.5 crashes on some malformed files (inside its parsers, before anything can be checked): a model that
// is not an md5mesh is imported in a child process, so such a crash is an error message, not a crash of afb.
int runIsolated(const GenCliOptions& opt) {
    std::cout.flush();
    std::fflush(nullptr);
    const pid_t pid = ::fork();
    if (pid < 0) return runGen(opt);
    if (pid == 0) {
        const int code = runGen(opt);
        std::cout.flush();
        std::cerr.flush();
        std::fflush(nullptr);
        ::_exit(code);
    }
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0)
        if (errno != EINTR) return 1;
    if (WIFEXITED(status)) return WEXITSTATUS(status);
    std::cerr << opt.model.string() << ": error: the importer crashed on this file (signal "
              << (WIFSIGNALED(status) ? WTERMSIG(status) : 0) << "): the file is malformed or not supported\n";
    return 1;
}

} // namespace

void addGenCommand(CLI::App& app, int& exitCode) {
    auto* cmd = app.add_subcommand(
        "gen", "Generate a ragdoll figure from a rigged mesh (.md5mesh, or any format assimp reads: FBX, glTF/GLB, "
               "Collada, X, B3D, ...): writes DIR/af/N.af, DIR/def/N.def and DIR/models/md5/N/ (mesh and af_pose)\n"
               "Examples:\n  afb gen models/md5/humanoid/humanoid.md5mesh --out generated\n"
               "  afb gen character.fbx --out generated --name hero --height 1.8");
    auto opt = std::make_shared<GenCliOptions>();
    cmd->add_option("model", opt->model, "The rigged mesh")->required();
    cmd->add_option("--out", opt->out, "Content folder to write into (created when missing)")->required();
    cmd->add_option("--name", opt->name,
                    "Figure name (the .af decl, the entityDef, file names); default: the "
                    "model's file name");
    cmd->add_option("--mass", opt->massKg, "Total mass, kg (default: 500 kg/m^3 times the bodies' volume)")
        ->check(within(0.01, 1e5));
    cmd->add_option("--rules", opt->rules,
                    "JSON rules overriding the built-in humanoid template (docs/cli.md: afb gen)");
    cmd->add_option("--unit-m", opt->unitM,
                    "Metres per model unit (default by format: md5 0.0254, or 1 for an md5mesh under 0.2 m tall at "
                    "0.0254, with a note; glTF 1, FBX 0.01 x UnitScaleFactor, others 0.0254)")
        ->check(within(1e-9, 1e9));
    cmd->add_option("--height", opt->heightM, "Scale the model to this height (its largest extent), metres")
        ->check(within(0.01, 100.0));
    cmd->add_option("--up", opt->up, "The model's up axis (default: y for assimp formats, z for md5)")
        ->check(CLI::IsMember({"y", "z"}));
    cmd->add_flag("--json", opt->json, "Print the generated bodies and joints as JSON on stdout");
    cmd->callback([opt, &exitCode] {
        std::string ext = opt->model.extension().string();
        for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
        exitCode = ext == ".md5mesh" ? runGen(*opt) : runIsolated(*opt);
    });
}

} // namespace afb::cli
