#include "Usage.h"

#include <cmath>
#include <iostream>
#include <limits>
#include <sstream>

#include "Suggest.h"

namespace afb::cli {
namespace {

// "afb", "afb drop", "afb golden record": the command as typed.
std::string commandPath(const CLI::App& cmd) {
    if (cmd.get_parent() == nullptr) return "afb";
    return commandPath(*cmd.get_parent()) + " " + cmd.get_name();
}

std::vector<std::string> optionNames(const CLI::App& cmd) {
    std::vector<std::string> names;
    for (const CLI::Option* o : cmd.get_options()) {
        for (const std::string& n : o->get_lnames()) names.push_back("--" + n);
        for (const std::string& n : o->get_snames()) names.push_back("-" + n);
    }
    return names;
}

std::vector<std::string> commandNames(const CLI::App& cmd) {
    std::vector<std::string> names;
    for (const CLI::App* sub : cmd.get_subcommands([](const CLI::App* s) { return !s->get_name().empty(); }))
        names.push_back(sub->get_name());
    return names;
}

std::string joined(const std::vector<std::string>& names) {
    std::string s;
    for (const std::string& n : names) s += (s.empty() ? "" : ", ") + n;
    return s;
}

// What was wrong, without the command's name: a word the command line has and no command knows first (an unknown
// option, command or argument), else CLI11's own message.
std::string describe(const CLI::App& cmd, const CLI::ParseError& error) {
    for (const std::string& word : cmd.remaining(false)) {
        if (word.size() > 1 && word[0] == '-') {
            const std::string name = word.substr(0, word.find('='));
            return "unknown option '" + name + "'" + didYouMean(name, optionNames(cmd));
        }
        if (!commandNames(cmd).empty() && cmd.get_subcommands().empty())
            return "unknown command '" + word + "'" + didYouMean(word, commandNames(cmd));
        return "unexpected argument '" + word + "'";
    }
    if (!commandNames(cmd).empty() && cmd.get_subcommands().empty())
        return "no command given (" + joined(commandNames(cmd)) + ")";
    return error.what();
}

// The command to blame: the first one along the parsed chain that was left a word it does not take, else the
// last command parsed.
const CLI::App& blamed(const CLI::App& app) {
    const CLI::App* cmd = &app;
    while (cmd->remaining(false).empty() && !cmd->get_subcommands().empty()) cmd = cmd->get_subcommands().front();
    return *cmd;
}

std::string number(double v) { return CLI::detail::to_string(v); }

// A check of a real number: `accept` says whether a finite value is allowed; `rule` names the allowed values.
CLI::Validator realCheck(std::function<bool(double)> accept, const std::string& rule, const std::string& desc) {
    return CLI::Validator(
        [accept, rule](std::string& text) -> std::string {
            double v = 0;
            if (!CLI::detail::lexical_cast(text, v)) return "Value " + text + " is not a number";
            if (!std::isfinite(v) || !accept(v)) return "Value " + text + " is not " + rule;
            return {};
        },
        desc);
}

class OneLineListFormatter : public CLI::Formatter {
  public:
    std::string make_subcommand(const CLI::App* sub) const override {
        std::stringstream out;
        const std::string& description = sub->get_description();
        CLI::detail::format_help(out, sub->get_display_name(true), description.substr(0, description.find('\n')),
                                 column_width_);
        return out.str();
    }
};

} // namespace

std::shared_ptr<CLI::Formatter> helpFormatter() { return std::make_shared<OneLineListFormatter>(); }

void usageError(const std::string& message) { throw CLI::ValidationError(message); }

int reportParseError(const CLI::App& app, const CLI::ParseError& error) {
    if (error.get_exit_code() == 0) return app.exit(error);
    const CLI::App& cmd = blamed(app);
    std::cerr << commandPath(cmd) << ": " << describe(cmd, error) << "\n"
              << "Run '" << commandPath(cmd) << " --help' for the "
              << (commandNames(cmd).empty() ? "options" : "commands") << ".\n";
    return kExitUsage;
}

void checkStepCount(const std::string& option, double seconds, double hz) {
    if (seconds * hz > std::numeric_limits<int>::max())
        usageError(option + " " + number(seconds) + " at --hz " + number(hz) + ": more steps than a run can count");
}

CLI::Validator positive() {
    return realCheck([](double v) { return v > 0; }, "a positive number", "POSITIVE");
}
CLI::Validator nonNegative() {
    return realCheck([](double v) { return v >= 0; }, "a number >= 0", "NONNEGATIVE");
}
CLI::Validator finite() {
    return realCheck([](double) { return true; }, "a finite number", "");
}
CLI::Validator within(double lo, double hi) {
    const std::string range = "in [" + number(lo) + " - " + number(hi) + "]";
    return realCheck([lo, hi](double v) { return v >= lo && v <= hi; }, range, range);
}

} // namespace afb::cli
