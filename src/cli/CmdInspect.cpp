// afb inspect: the built figure — bodies, constraints, totals and findings.
#include <cstdio>
#include <iostream>

#include "Commands.h"
#include "Usage.h"
#include "afb/detail/DoomMath.h"
#include "afb/figure/Load.h"
#include "afb/sim/Report.h"

namespace afb::cli {
namespace {

const char* modName(figure::JointMod m) {
    return m == figure::JointMod::Position ? "position" : m == figure::JointMod::Both ? "both" : "orientation";
}
nlohmann::json vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }
double deg(double rad) { return rad / figure::kRadPerDeg; }

nlohmann::json limitJson(const figure::FigureConstraint& c) {
    if (const auto* cone = std::get_if<figure::ConeLimit>(&c.limit))
        return {{"kind", "cone"}, {"halfAngleDeg", deg(cone->halfAngleRad)}};
    if (const auto* p = std::get_if<figure::PyramidLimit>(&c.limit))
        return {{"kind", "pyramid"},
                {"halfAngle1Deg", deg(p->halfAngle1Rad)},
                {"halfAngle2Deg", deg(p->halfAngle2Rad)}};
    if (const auto* h = std::get_if<figure::HingeRange>(&c.limit))
        return {{"kind", "hinge"}, {"lowerDeg", deg(h->lowerRad)}, {"upperDeg", deg(h->upperRad)}};
    return nullptr;
}

std::string limitText(const figure::FigureConstraint& c) {
    char buf[128];
    if (const auto* cone = std::get_if<figure::ConeLimit>(&c.limit))
        std::snprintf(buf, sizeof buf, "cone half-angle %.1f deg", deg(cone->halfAngleRad));
    else if (const auto* p = std::get_if<figure::PyramidLimit>(&c.limit))
        std::snprintf(buf, sizeof buf, "pyramid %.1f x %.1f deg", deg(p->halfAngle1Rad), deg(p->halfAngle2Rad));
    else if (const auto* h = std::get_if<figure::HingeRange>(&c.limit))
        std::snprintf(buf, sizeof buf, "hinge [%.1f, %.1f] deg", deg(h->lowerRad), deg(h->upperRad));
    else return "-";
    return buf;
}

nlohmann::json figureJson(const figure::Figure& f) {
    nlohmann::json bodies = nlohmann::json::array(), constraints = nlohmann::json::array();
    for (const figure::FigureBody& b : f.bodies)
        bodies.push_back({{"name", b.name},
                          {"joint", b.joint >= 0 ? f.skeleton.name(b.joint) : ""},
                          {"mod", modName(b.mod)},
                          {"shape", figure::toString(b.shape.kind)},
                          {"vertices", b.shape.vertices.size()},
                          {"volumeM3", b.volumeM3},
                          {"massKg", b.massKg},
                          {"centerOfMassM", vec(b.loadPose.position)},
                          {"principalMomentsKgM2", vec(b.inertiaKgM2)},
                          {"contactFriction", b.contactFriction},
                          {"linearDamping", b.linearDamping},
                          {"angularDamping", b.angularDamping},
                          {"selfCollision", b.selfCollision},
                          {"containedJoints", b.containedJoints.size()}});
    for (const figure::FigureConstraint& c : f.constraints) {
        const Eigen::Vector3d anchor =
            f.bodies[static_cast<std::size_t>(c.body1)].loadPose.apply(c.frameInBody1.position);
        constraints.push_back({{"name", c.name},
                               {"type", figure::toString(c.type)},
                               {"body1", f.bodies[static_cast<std::size_t>(c.body1)].name},
                               {"body2", c.body2 >= 0 ? f.bodies[static_cast<std::size_t>(c.body2)].name : "world"},
                               {"anchorM", vec(anchor)},
                               {"friction", c.friction},
                               {"limit", limitJson(c)}});
    }
    return {{"name", f.name},
            {"metresPerUnit", f.units.metresPerUnit},
            {"bodies", bodies},
            {"constraints", constraints},
            {"totalMassKg", f.totalMassKg},
            {"joints", f.skeleton.jointCount()},
            {"selfCollision", f.selfCollision}};
}

void printFigure(const figure::Figure& f) {
    std::printf("figure %s: %zu bodies, %zu constraints, %d md5 joints, total mass %.3f kg (1 unit = %g m)\n\n",
                f.name.c_str(), f.bodies.size(), f.constraints.size(), f.skeleton.jointCount(), f.totalMassKg,
                f.units.metresPerUnit);
    std::printf("%-14s %-14s %-11s %-12s %5s %11s %9s  %-26s %s\n", "body", "joint", "mod", "shape", "verts",
                "volume m3", "mass kg", "centre of mass (model, m)", "principal moments kg m2");
    for (const figure::FigureBody& b : f.bodies) {
        const Eigen::Vector3d& c = b.loadPose.position;
        std::printf("%-14s %-14s %-11s %-12s %5zu %11.3e %9.3f  (%7.3f %7.3f %7.3f)  %.3e %.3e %.3e\n", b.name.c_str(),
                    b.joint >= 0 ? f.skeleton.name(b.joint).c_str() : "-", modName(b.mod),
                    figure::toString(b.shape.kind), b.shape.vertices.size(), b.volumeM3, b.massKg, c.x(), c.y(), c.z(),
                    b.inertiaKgM2.x(), b.inertiaKgM2.y(), b.inertiaKgM2.z());
    }
    std::printf("\n%-22s %-19s %-14s %-14s %-26s %s\n", "constraint", "type", "body1", "body2", "anchor (model, m)",
                "limit");
    for (const figure::FigureConstraint& c : f.constraints) {
        const Eigen::Vector3d a = f.bodies[static_cast<std::size_t>(c.body1)].loadPose.apply(c.frameInBody1.position);
        std::printf("%-22s %-19s %-14s %-14s (%7.3f %7.3f %7.3f)  %s\n", c.name.c_str(), figure::toString(c.type),
                    f.bodies[static_cast<std::size_t>(c.body1)].name.c_str(),
                    c.body2 >= 0 ? f.bodies[static_cast<std::size_t>(c.body2)].name.c_str() : "world", a.x(), a.y(),
                    a.z(), limitText(c).c_str());
    }
}

} // namespace

void addInspectCommand(CLI::App& app, int& exitCode) {
    auto* cmd =
        app.add_subcommand("inspect", "Build a figure and print its bodies, constraints, totals and findings\n"
                                      "Examples:\n  afb inspect --base . humanoid\n"
                                      "  afb inspect --af af/chain.af --mesh models/md5/props/chain/chain.md5mesh "
                                      "--pose models/md5/props/chain/af_pose.md5anim");
    struct Options {
        std::filesystem::path base = ".";
        std::string entity;
        std::filesystem::path af, mesh, pose;
        std::string name;
        std::vector<double> offset{0, 0, 0};
        double metresPerUnit = 0.0254;
        bool json = false;
        bool strict = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("entity", opt->entity, "entityDef to resolve in --base (or use --af/--mesh/--pose)");
    cmd->add_option("--base", opt->base, "Content folder holding af/, def/ and models/")->capture_default_str();
    cmd->add_option("--af", opt->af, "An .af file (instead of an entity)");
    cmd->add_option("--name", opt->name, "Figure name in --af (default: the first)");
    cmd->add_option("--mesh", opt->mesh, "The .md5mesh (with --af)");
    cmd->add_option("--pose", opt->pose, "The af_pose .md5anim (with --af)");
    cmd->add_option("--offset", opt->offset, "Model decl offset x y z, Doom units (with --af)")
        ->expected(3)
        ->check(finite());
    cmd->add_option("--unit", opt->metresPerUnit, "Metres per Doom unit")->check(positive())->capture_default_str();
    cmd->add_flag("--strict", opt->strict, "Refuse values the builder would repair (docs/format.md: hostile numbers)");
    cmd->add_flag("--json", opt->json,
                  "Print JSON: name, metresPerUnit, joints, totalMassKg, selfCollision, bodies[{name, joint, mod, "
                  "shape, vertices, volumeM3, massKg, centerOfMassM (model space), principalMomentsKgM2, "
                  "contactFriction, linearDamping, angularDamping, selfCollision, containedJoints}], "
                  "constraints[{name, type, body1, body2, anchorM, friction, limit{kind, ...Deg}}], findings{errors, "
                  "warnings}");
    cmd->callback([opt, &exitCode] {
        text::Diagnostics diags;
        figure::UnitSystem units;
        units.metresPerUnit = opt->metresPerUnit;
        std::optional<figure::LoadedFigure> loaded;
        if (!opt->af.empty()) {
            if (opt->mesh.empty() || opt->pose.empty()) usageError("--af needs --mesh and --pose");
            loaded = figure::loadFigureFiles(opt->af, opt->name, opt->mesh, opt->pose,
                                             {opt->offset[0], opt->offset[1], opt->offset[2]}, units, diags,
                                             figure::RootTranslation::OffsetAdded, opt->strict);
        } else if (!opt->entity.empty()) {
            auto lib = decl::Library::open(opt->base, diags);
            if (!lib || !findEntities(*lib, {opt->entity}, diags)) {
                printDiagnostics(diags);
                exitCode = kExitFailure;
                return;
            }
            loaded = figure::loadEntityFigure(*lib, opt->entity, units, diags, opt->strict);
        } else {
            usageError("give an ENTITY (with --base) or --af, --mesh and --pose");
        }
        if (opt->json) {
            nlohmann::json j = loaded ? figureJson(loaded->figure) : nlohmann::json::object();
            j["findings"] = diagnosticsJson(diags);
            j["schema"] = sim::schemaJson(sim::kInspectSchema);
            std::cout << j.dump(2) << "\n";
        } else if (loaded) {
            printFigure(loaded->figure);
        }
        if (!diags.empty()) std::cerr << "\nfindings:\n";
        printDiagnostics(diags);
        if (!loaded) exitCode = 1;
    });
}

} // namespace afb::cli
