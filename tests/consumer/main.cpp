// Downstream smoke test: parse a tiny inline .af with the installed/exported afbullet.
// Exits 0 iff it parsed exactly one decl with the expected number of bodies.
#include <cstdio>
#include <string_view>

#include <afb/Version.h>
#include <afb/afb.h>

namespace {

constexpr std::string_view kAf = R"(
articulatedFigure consumer_test {
settings {
	model "consumer_model"
	totalMass 100
}
body "waist" {
	joint "origin"
	mod orientation
	model box( ( -8, -8, -8 ), ( 8, 8, 8 ) )
	origin ( 0, 0, 40 )
	density 0.02
}
body "chest" {
	joint "chest"
	mod orientation
	model cylinder( ( -10, -10, -12 ), ( 10, 10, 12 ), 6 )
	origin ( 0, 0, 64 )
	density 0.02
}
universalJoint "waist_chest" {
	body1 "chest"
	body2 "waist"
	anchor ( 0, 0, 52 )
	shafts ( 0, 0, 1 ), ( 0, 0, -1 )
	coneLimit ( 0, 0, 1 ), 30
}
}
)";

constexpr std::size_t kExpectedBodies = 2;

} // namespace

int main() {
    afb::text::Diagnostics diags;
    const auto file = afb::decl::parseAf(kAf, "consumer.af", diags);
    if (!diags.empty()) std::fprintf(stderr, "%s\n", diags.str().c_str());
    if (!file) {
        std::fprintf(stderr, "consumer: parseAf failed\n");
        return 1;
    }
    if (file->decls.size() != 1) {
        std::fprintf(stderr, "consumer: expected 1 decl, got %zu\n", file->decls.size());
        return 1;
    }
    const auto& decl = file->decls.front();
    if (decl.bodies.size() != kExpectedBodies) {
        std::fprintf(stderr, "consumer: expected %zu bodies, got %zu\n", kExpectedBodies, decl.bodies.size());
        return 1;
    }
    std::printf("consumer: afbullet %s parsed '%s' with %zu bodies and %zu constraints\n", AFB_VERSION_STRING,
                decl.name.c_str(), decl.bodies.size(), decl.constraints.size());
    return 0;
}
