// afb parse FILE...: checks that files parse; --json describes what each holds.
#include <filesystem>
#include <iostream>

#include "Commands.h"
#include "afb/decl/AfParser.h"
#include "afb/decl/Def.h"
#include "afb/decl/Md5Anim.h"
#include "afb/decl/Md5Mesh.h"
#include "afb/sim/Report.h"

namespace afb::cli {
namespace {

std::string lowerExtension(const std::filesystem::path& p) {
    std::string ext = p.extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

// Parses one file by its extension; returns the JSON description (with "ok") and fills `diags`.
nlohmann::json parseOne(const std::filesystem::path& path, text::Diagnostics& diags) {
    const std::string ext = lowerExtension(path);
    nlohmann::json out = {{"file", path.string()}};
    if (ext == ".af") {
        out["kind"] = "af";
        if (auto f = decl::loadAf(path, diags)) {
            nlohmann::json decls = nlohmann::json::array();
            for (const decl::AfDecl& d : f->decls)
                decls.push_back({{"name", d.name},
                                 {"kind", "articulatedFigure"},
                                 {"bodies", d.bodies.size()},
                                 {"constraints", d.constraints.size()}});
            out["decls"] = decls;
        }
    } else if (ext == ".def") {
        out["kind"] = "def";
        if (auto f = decl::loadDef(path, diags)) {
            nlohmann::json decls = nlohmann::json::array();
            for (const decl::EntityDef& e : f->entityDefs) decls.push_back({{"name", e.name}, {"kind", "entityDef"}});
            for (const decl::ModelDef& m : f->models) decls.push_back({{"name", m.name}, {"kind", "model"}});
            out["decls"] = decls;
        }
    } else if (ext == ".md5mesh") {
        out["kind"] = "md5mesh";
        if (auto m = decl::loadMd5Mesh(path, diags)) {
            out["joints"] = m->joints.size();
            out["meshes"] = m->meshes.size();
            out["verts"] = decl::totalVertCount(*m);
            out["tris"] = decl::totalTriCount(*m);
            out["weights"] = decl::totalWeightCount(*m);
        }
    } else if (ext == ".md5anim") {
        out["kind"] = "md5anim";
        if (auto a = decl::loadMd5Anim(path, diags)) {
            out["frames"] = a->frames.size();
            out["joints"] = a->hierarchy.size();
            out["frameRate"] = a->frameRate;
            out["components"] = a->numAnimatedComponents;
        }
    } else {
        out["kind"] = nullptr;
        diags.error({path.string(), 0, 0},
                    "unknown file type '" + ext + "' (expected .af, .def, .md5mesh or .md5anim)");
    }
    out["ok"] = !diags.hasErrors();
    return out;
}

} // namespace

void addParseCommand(CLI::App& app, int& exitCode) {
    auto* cmd = app.add_subcommand("parse", "Parse .af, .def, .md5mesh and .md5anim files (by extension); exit 0 "
                                            "iff every file parses\n"
                                            "Examples:\n  afb parse af/chain.af models/md5/props/chain/chain.md5mesh\n"
                                            "  afb parse --json def/*.def");
    struct Options {
        std::vector<std::filesystem::path> files;
        bool json = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("files", opt->files, "Files to parse")->required();
    cmd->add_flag("--json", opt->json,
                  "Print one JSON object per file per line: file, kind, ok, errors, warnings, and for .af/.def "
                  "decls[{name, kind, bodies, constraints}], for .md5mesh joints/meshes/verts/tris/weights, for "
                  ".md5anim frames/joints/frameRate/components");
    cmd->callback([opt, &exitCode] {
        for (const auto& file : opt->files) {
            text::Diagnostics diags;
            nlohmann::json j = parseOne(file, diags);
            printDiagnostics(diags);
            if (diags.hasErrors()) exitCode = 1;
            if (opt->json) {
                j.update(diagnosticsJson(diags));
                j["schema"] = sim::schemaJson(sim::kParseSchema);
                std::cout << j.dump() << "\n";
            }
        }
    });
}

} // namespace afb::cli
