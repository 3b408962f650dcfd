// Found by fuzz_e2e: the bundled props with `anchor1` written twice in spring 'cone_bone' (so its anchor2
// is the model origin, 2 m from the cone it is fixed in) and the bone made 25 times heavier than the cone. The
// spring starts 1.5 m past its rest length on that 2 m lever: its explicit force was thousands of times what the
// step can integrate, and the figure reached NaN within a dozen steps. The spring's impulse is now bounded by the
// row's effective mass (SpringConstraint); within the bound it is the engine's force unchanged.
#include <catch2/catch.hpp>

#include <cmath>

#include "MutationSweep.h"
#include "TestSupport.h"
#include "afb/detail/Constraints.h"

namespace {

using afb::test::MutationTarget;

MutationTarget props() {
    std::vector<MutationTarget> targets = afb::test::entityTargets(afb::test::sourceDir(), {"props"});
    REQUIRE(targets.size() == 1);
    return targets.front();
}

/// `text` with the first `from` after `after` replaced by `to`.
std::string replaced(std::string text, const std::string& after, const std::string& from, const std::string& to) {
    const std::size_t at = text.find(from, text.find(after));
    REQUIRE(at != std::string::npos);
    return text.replace(at, from.size(), to);
}

/// Kinetic energy (translation and rotation) of the ragdoll's bodies, J.
double kineticEnergy(const afb::figure::Figure& figure, const afb::bullet::Ragdoll& ragdoll) {
    double energy = 0;
    const std::vector<afb::figure::BodyState> states = ragdoll.bodyStates();
    for (std::size_t i = 0; i < states.size(); ++i) {
        const afb::figure::FigureBody& b = figure.bodies[i];
        const Eigen::Vector3d w = states[i].pose.rotation.transpose() * states[i].angularVelocity; // principal axes
        energy += 0.5 * b.massKg * states[i].linearVelocity.squaredNorm() + 0.5 * w.cwiseProduct(w).dot(b.inertiaKgM2);
    }
    return energy;
}

} // namespace

TEST_CASE("a spring far past its maxLength on a long lever simulates finite and settles", "[bullet][hostile]") {
    const MutationTarget target = props();
    std::string text = replaced(target.afText, "spring \"cone_bone\"", "anchor2 joint", "anchor1 joint");
    text = replaced(text, "body \"bone\"", "density 0.208333", "density 5.208333");
    afb::text::Diagnostics findings;
    std::optional<afb::figure::Figure> figure = afb::test::buildVariant(target, text, false, findings);
    INFO(findings.str());
    REQUIRE(figure);
    CHECK(findings.str().find("spring 'cone_bone': no anchor2") != std::string::npos);
    CHECK(findings.str().find("above maxLength") != std::string::npos);

    // The energy the figure can release: the quadratic spring's k·x³/3 at its load length (docs/format.md §4.7), and
    // every body's centre of mass falling to the ground plane.
    const afb::figure::Figure& f = *figure;
    double available = 0;
    for (const afb::figure::FigureConstraint& c : f.constraints) {
        if (c.type != afb::figure::JointType::Spring) continue;
        const auto& b1 = f.bodies[static_cast<std::size_t>(c.body1)];
        const auto& b2 = f.bodies[static_cast<std::size_t>(c.body2)];
        const double length =
            ((b2.loadPose * c.frameInBody2).position - (b1.loadPose * c.frameInBody1).position).norm();
        const double x = length - c.spring.restLengthM;
        const double k = x > 0 ? c.spring.stretchNPerM2 : c.spring.compressNPerM2;
        available += k * std::abs(x * x * x) / 3;
    }
    for (const afb::figure::FigureBody& b : f.bodies) available += b.massKg * 9.81 * b.loadPose.position.z();

    afb::sim::Scene scene(afb::bullet::Method{});
    const afb::bullet::Ragdoll& ragdoll = scene.spawn(afb::bullet::RagdollAsset::create(f));
    double peak = 0;
    for (int step = 0; step < 180; ++step) {
        scene.step(1.0 / 60.0);
        REQUIRE(afb::test::sceneFinite(scene));
        peak = std::max(peak, kineticEnergy(f, ragdoll));
    }
    INFO("peak kinetic energy " << peak << " J, available " << available << " J");
    CHECK(peak < available);
    CHECK(kineticEnergy(f, ragdoll) < 0.01 * available); // 3 s later it has settled
}

TEST_CASE("within its bound a spring applies the engine's force unchanged", "[bullet][hostile]") {
    // The bundled springs (props' chain of shapes, the buggy's suspension) through a 2 s drop from 1 m.
    for (const char* entity : {"props", "buggy"}) {
        const std::vector<MutationTarget> targets = afb::test::entityTargets(afb::test::sourceDir(), {entity});
        REQUIRE(targets.size() == 1);
        afb::text::Diagnostics findings;
        std::optional<afb::figure::Figure> figure =
            afb::test::buildVariant(targets.front(), targets.front().afText, false, findings);
        REQUIRE(figure);
        afb::sim::Scene scene(afb::bullet::Method{});
        btTransform raised = btTransform::getIdentity();
        raised.setOrigin(btVector3(0, 0, 1));
        afb::bullet::Ragdoll& ragdoll = scene.spawn(afb::bullet::RagdollAsset::create(*figure),
                                                    afb::bullet::SpawnOptions{.entityTransform = raised});
        int springs = 0;
        for (int step = 0; step < 120; ++step) {
            scene.step(1.0 / 60.0);
            for (std::size_t i = 0; i < figure->constraints.size(); ++i) {
                const auto* spring =
                    dynamic_cast<const afb::bullet::SpringConstraint*>(ragdoll.constraint(static_cast<int>(i)));
                if (!spring) continue;
                ++springs;
                INFO(entity << " " << figure->constraints[i].name << " step " << step);
                CHECK(spring->impulse(btScalar(1.0 / 60)) == Approx(spring->force() / 60).margin(1e-6));
            }
        }
        CHECK(springs >= 4 * 120);
    }
}
