// libFuzzer target: parseDef on arbitrary bytes. It must either succeed or fail with an error diagnostic;
// crashes, sanitizer reports, hangs and runaway allocations (e.g. trusting a huge count) are bugs.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "afb/decl/Def.h"
#include "afb/text/Diagnostics.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view src(reinterpret_cast<const char*>(data), size);
    afb::text::Diagnostics diags;
    const auto parsed = afb::decl::parseDef(src, "fuzz.def", diags);
    if (!parsed && !diags.hasErrors()) std::abort(); // a failed parse must say why
    return 0;
}
