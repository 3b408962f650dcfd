#pragma once
// The one place drop results, drop scenarios and methods are serialised (JSON and CSV), for `afb drop`,
// `afb golden` and anything else that records a run.
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "afb/bullet/Method.h"
#include "afb/sim/Drop.h"

namespace afb::sim {

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
