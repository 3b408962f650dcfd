// libFuzzer target: parseAf on arbitrary bytes, plus the round-trip property — whatever parses must be written
// back by writeAf to text that parses to an equal AfFile (locations excepted; SourceLocation compares equal).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include "afb/decl/AfParser.h"
#include "afb/text/Diagnostics.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view src(reinterpret_cast<const char*>(data), size);
    afb::text::Diagnostics diags;
    const auto file = afb::decl::parseAf(src, "fuzz.af", diags);
    if (!file) {
        if (!diags.hasErrors()) std::abort(); // a failed parse must say why
        return 0;
    }

    const std::string written = afb::decl::writeAf(*file);
    afb::text::Diagnostics diags2;
    const auto again = afb::decl::parseAf(written, "written.af", diags2);
    if (!again) {
        std::fprintf(stderr, "round trip: writeAf output does not parse:\n%s\n--- written text ---\n%s\n",
                     diags2.str().c_str(), written.c_str());
        std::abort();
    }
    if (!(*again == *file)) {
        std::fprintf(stderr, "round trip: parseAf(writeAf(f)) != f\n--- written text ---\n%s\n", written.c_str());
        std::abort();
    }
    // The canonical form is a fixed point.
    if (afb::decl::writeAf(*again) != written) {
        std::fprintf(stderr, "round trip: writeAf is not idempotent\n--- written text ---\n%s\n", written.c_str());
        std::abort();
    }
    return 0;
}
