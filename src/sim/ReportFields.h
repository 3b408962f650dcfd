// A report as a table of fields (name, meaning, value of a result): one table feeds the JSON object, the CSV header
// and row (with the method's knobs after the fields) and the --help text, so the three never disagree. Internal to
// the sim layer (Report.cpp for drops, TrackReport.cpp for tracking runs).
#pragma once

#include <functional>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "afb/bullet/Method.h"
#include "afb/sim/Report.h"

namespace afb::sim::detail {

template <class Result>
struct ReportField {
    std::string_view name;
    std::string_view help;
    std::function<nlohmann::json(const Result&)> value;
};

template <class Result>
nlohmann::json fieldsJson(const std::vector<ReportField<Result>>& fields, const Result& r) {
    nlohmann::json j = nlohmann::json::object();
    for (const ReportField<Result>& f : fields) j[std::string(f.name)] = f.value(r);
    return j;
}

template <class Result>
std::string fieldsCsvHeader(const std::vector<ReportField<Result>>& fields) {
    std::string out;
    for (const ReportField<Result>& f : fields) out += (out.empty() ? "" : ",") + std::string(f.name);
    for (const bullet::MethodKnob& k : bullet::methodKnobs()) out += ",method." + std::string(k.name);
    return out;
}

template <class Result>
std::string fieldsCsvRow(const std::vector<ReportField<Result>>& fields, const Result& r,
                         const bullet::Method& method) {
    std::string out;
    for (const ReportField<Result>& f : fields) out += (out.empty() ? "" : ",") + csvCell(f.value(r));
    for (const bullet::MethodKnob& k : bullet::methodKnobs()) out += "," + bullet::knobValue(method, k);
    return out;
}

template <class Result>
std::string fieldsHelp(const std::vector<ReportField<Result>>& fields) {
    std::ostringstream out;
    out << "Fields (JSON and CSV):";
    for (const ReportField<Result>& f : fields) out << "\n  " << f.name << ": " << f.help;
    return out.str();
}

} // namespace afb::sim::detail
