#pragma once
// The command line's own errors: exit code 2 with one message naming what was wrong (and, for a misspelt command
// or option, the closest valid one), and the checks that refuse option values that make no sense.
#include <memory>
#include <string>

#include <CLI/CLI.hpp>

namespace afb::cli {

/// Exit codes of every command: 0 success; 1 a failed check or bad input (a file that cannot be read or is
/// malformed, an entity that is not there); 2 a command line that makes no sense.
inline constexpr int kExitFailure = 1;
inline constexpr int kExitUsage = 2;

/// The help formatter of every command: a command's line in its parent's list is the first line of its
/// description, so the examples that follow it appear in the command's own help alone. Set it on the app before
/// the commands are added (they take their parent's).
std::shared_ptr<CLI::Formatter> helpFormatter();

/// Refuses the command line from a command's callback: main reports `afb COMMAND: message` and exits 2.
[[noreturn]] void usageError(const std::string& message);

/// Reports an error of CLI11's parse (or usageError) on stderr and returns the exit code: 0 after printing the
/// help or the version, else 2.
int reportParseError(const CLI::App& app, const CLI::ParseError& error);

/// Refuses a simulated time that is more steps at `hz` than a step count holds (2^31 - 1); `option` names the time.
void checkStepCount(const std::string& option, double seconds, double hz);

/// Option checks for real numbers; each also refuses NaN and infinities.
/// A number > 0.
CLI::Validator positive();
/// A number >= 0.
CLI::Validator nonNegative();
/// A finite number.
CLI::Validator finite();
/// A number in [lo, hi].
CLI::Validator within(double lo, double hi);

} // namespace afb::cli
