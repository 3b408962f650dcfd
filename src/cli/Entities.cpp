#include "Commands.h"
#include "Suggest.h"

namespace afb::cli {

bool findEntities(const decl::Library& library, const std::vector<std::string>& entities,
                  text::Diagnostics& diagnostics) {
    bool all = true;
    for (const std::string& e : entities) {
        if (library.findEntityDef(e)) continue;
        diagnostics.error({library.baseDir().string(), 0, 0},
                          "entityDef '" + e + "' not found" + didYouMean(e, library.entityDefNames()));
        all = false;
    }
    return all;
}

} // namespace afb::cli
