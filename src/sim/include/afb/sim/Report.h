#pragma once
// The one place drop results, drop scenarios and methods are serialised (JSON and CSV), for `afb drop`,
// `afb golden` and anything else that records a run.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "afb/bullet/Method.h"
#include "afb/sim/Drop.h"

namespace afb::sim {

/// What a JSON report of afb is: its name ("afbullet-drop", …) and the version of its fields. Every JSON document a
/// command writes for people's tools carries it as "schema": {"name": …, "version": …}; the version grows when a
/// field changes its meaning, unit or type, or goes away (a new field does not change it). docs/cli.md lists them.
struct ReportSchema {
    std::string_view name;
    int version;
};
inline constexpr ReportSchema kDropSchema{"afbullet-drop", 1};       ///< afb drop --json
inline constexpr ReportSchema kTrackSchema{"afbullet-track", 1};     ///< afb track --json
inline constexpr ReportSchema kStressSchema{"afbullet-stress", 1};   ///< afb stress's stress.json
inline constexpr ReportSchema kGoldenSchema{"afbullet-golden", 1};   ///< afb golden record's files
inline constexpr ReportSchema kInspectSchema{"afbullet-inspect", 1}; ///< afb inspect --json
inline constexpr ReportSchema kResolveSchema{"afbullet-resolve", 1}; ///< afb resolve --json
inline constexpr ReportSchema kParseSchema{"afbullet-parse", 1};     ///< afb parse --json (each line)
inline constexpr ReportSchema kGenSchema{"afbullet-gen", 1};         ///< afb gen --json
inline constexpr ReportSchema kMethodsSchema{"afbullet-methods", 1}; ///< afb methods --json
inline constexpr ReportSchema kMethodSchema{"afbullet-method", 1};   ///< afb methods NAME --json

/// {"name": …, "version": …}, the value of a report's "schema" member.
nlohmann::json schemaJson(const ReportSchema& schema);
/// Whether a document read back (a golden file) can be read as `schema`: its "schema" names it at this version or
/// an older one, or it has no "schema" (written before reports carried one: version 1). Else an error message.
std::string checkSchema(const nlohmann::json& document, const ReportSchema& schema);

/// A value that may be absent, as JSON: the number, or null.
nlohmann::json jsonOrNull(const std::optional<double>& value);
/// A report field as a CSV cell: null empty, booleans 1 / 0, text quoted where it holds a comma, quote or newline.
std::string csvCell(const nlohmann::json& value);

/// The method as JSON: {"name": …, "<knob>": value, …} (numbers as numbers, flags as booleans, enums as text).
nlohmann::json methodJson(const bullet::Method& method);
/// Reads a method written by methodJson: starts from the named preset (or the default) and applies every knob
/// present. Returns an error message, or an empty string.
std::string methodFromJson(const nlohmann::json& j, bullet::Method& method);
/// The knobs (bullet::methodKnobs) that a method written as JSON does not name: methodFromJson gives them the
/// preset's value of today, which a record made before they existed never ran. Empty for a non-object.
std::vector<std::string> missingKnobs(const nlohmann::json& method);

/// A drop scenario as JSON (height, count, seed, seconds, hz, sleeping and the method).
nlohmann::json dropOptionsJson(const DropOptions& options);
/// Reads dropOptionsJson's output; also reads the scenarios recorded before methods existed (top-level
/// "substeps", "iterations", "joint_iterations"). Returns an error message, or an empty string.
std::string dropOptionsFromJson(const nlohmann::json& j, DropOptions& options);

/// A pose (entity transform excluded) as a JSON array of {"joint", "position", "quaternion"}.
nlohmann::json poseJson(const std::vector<JointPose>& pose);

/// One drop result as JSON: every scalar field, the method and the final pose.
nlohmann::json dropResultJson(const DropResult& result);
/// The CSV header of dropCsvRow (scalar fields and the method's knobs; no pose).
std::string dropCsvHeader();
/// One drop result as a CSV row (no newline).
std::string dropCsvRow(const DropResult& result);
/// What each report field means, for --help.
std::string dropFieldsHelp();

} // namespace afb::sim
