// afb resolve --base DIR ENTITY: the chain from an entityDef to its model, mesh, af_pose and figure.
#include <iostream>

#include "Commands.h"
#include "afb/decl/Library.h"
#include "afb/sim/Report.h"

namespace afb::cli {

void addResolveCommand(CLI::App& app, int& exitCode) {
    auto* cmd = app.add_subcommand("resolve", "Follow an entityDef through inherit to its model decl, mesh, "
                                              "af_pose anim and articulated figure\n"
                                              "Examples:\n  afb resolve --base . humanoid\n"
                                              "  afb resolve --base . --json chain");
    struct Options {
        std::filesystem::path base = ".";
        std::string entity;
        bool json = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("--base", opt->base, "Content folder holding af/, def/ and models/ (like Doom's base/)")
        ->capture_default_str();
    cmd->add_option("entity", opt->entity, "entityDef name (case-insensitive)")->required();
    cmd->add_flag("--json", opt->json,
                  "Print JSON: entity, entityChain, model, modelChain, mesh, afPoseAnim, afPose, figureKey, figure, "
                  "figureFile (paths absolute)");
    cmd->callback([opt, &exitCode] {
        text::Diagnostics diags;
        std::optional<decl::ResolvedEntity> r;
        if (auto lib = decl::Library::open(opt->base, diags); lib && findEntities(*lib, {opt->entity}, diags))
            r = lib->resolveEntity(opt->entity, diags);
        printDiagnostics(diags);
        if (!r) {
            exitCode = 1;
            return;
        }
        if (opt->json) {
            const nlohmann::json j = {{"schema", sim::schemaJson(sim::kResolveSchema)},
                                      {"entity", r->entityName},
                                      {"entityChain", r->entityChain},
                                      {"model", r->modelName},
                                      {"modelChain", r->modelChain},
                                      {"mesh", r->meshPath.string()},
                                      {"afPoseAnim", r->afPoseAnim},
                                      {"afPose", r->afPosePath.string()},
                                      {"figureKey", r->figureKey},
                                      {"figure", r->figureName},
                                      {"figureFile", r->figureFile.string()}};
            std::cout << j.dump(2) << "\n";
            return;
        }
        auto chain = [](const std::vector<std::string>& names) {
            std::string s;
            for (const std::string& n : names) s += (s.empty() ? "" : " -> ") + n;
            return s;
        };
        std::cout << "entity   " << r->entityName << "  (" << r->entityLocation.str() << ")\n"
                  << "inherits " << chain(r->entityChain) << "\n"
                  << "model    " << r->modelName << "  (" << r->modelLocation.str() << ")\n"
                  << "         " << chain(r->modelChain) << "\n"
                  << "mesh     " << r->meshPath.string() << "\n"
                  << "af_pose  " << r->afPosePath.string() << "  (anim " << r->afPoseAnim << ")\n"
                  << "figure   " << r->figureName << "  (\"" << r->figureKey << "\", " << r->figureLocation.str()
                  << ")\n"
                  << "file     " << r->figureFile.string() << "\n";
    });
}

} // namespace afb::cli
