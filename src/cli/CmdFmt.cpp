// afb fmt FILE.af: canonical text on stdout (or --check: exit 1 when the file is not canonical).
#include <iostream>

#include "Commands.h"
#include "afb/decl/AfParser.h"
#include "afb/text/Files.h"

namespace afb::cli {

void addFmtCommand(CLI::App& app, int& exitCode) {
    auto* cmd = app.add_subcommand("fmt", "Print an .af file in canonical form (blocks in file order, keys in a "
                                          "fixed order, shortest exact numbers)\n"
                                          "Examples:\n  afb fmt af/chain.af > chain.af\n"
                                          "  afb fmt --check af/humanoid.af");
    struct Options {
        std::filesystem::path file;
        bool check = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("file", opt->file, "The .af file")->required();
    cmd->add_flag("--check", opt->check, "Print nothing; exit 1 when the file differs from its canonical form");
    cmd->callback([opt, &exitCode] {
        text::Diagnostics diags;
        const std::optional<std::string> data = text::readFile(opt->file, diags);
        std::optional<decl::AfFile> af;
        if (data) af = decl::parseAf(*data, opt->file.string(), diags);
        printDiagnostics(diags);
        if (!af) {
            exitCode = 1;
            return;
        }
        const std::string canonical = decl::writeAf(*af);
        if (!opt->check) {
            std::cout << canonical;
        } else if (canonical != *data) {
            std::cerr << opt->file.string() << ": not in canonical form (run: afb fmt " << opt->file.string() << ")\n";
            exitCode = 1;
        }
    });
}

} // namespace afb::cli
