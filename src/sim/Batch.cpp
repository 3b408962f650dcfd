// Run manifests and result files (Batch.h): JSON lines written once and read by line, results written atomically.
#include "afb/sim/Batch.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>
#include <system_error>

#include <unistd.h>

#include "afb/text/Files.h"

namespace afb::sim {

using nlohmann::json;

std::uint64_t fnv1a(std::string_view data, std::uint64_t h) {
    for (unsigned char c : data) {
        h ^= c;
        h *= 1099511628211ull;
    }
    return h;
}

std::string hashHex(std::uint64_t v) {
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
    return buf;
}

std::string fileHash(const std::filesystem::path& p) {
    text::Diagnostics d;
    const auto data = text::readFile(p, d);
    return data ? hashHex(fnv1a(*data)) : "missing";
}

void writeManifest(std::ostream& out, const std::string& command, const std::string& build,
                   const std::string& precision, const PlanLines& lines) {
    // The same for every line: serialised once (a manifest of 100 000 lines is written in a fraction of a second).
    const std::string head = ",\"runs\":" + std::to_string(lines.runs.size()) + ",\"command\":" + json(command).dump() +
                             ",\"build\":" + json(build).dump() + ",\"precision\":" + json(precision).dump() +
                             ",\"plan\":" + lines.plan.dump() + ",\"inputs\":";
    std::vector<std::string> inputSets;
    for (const json& set : lines.inputSets) inputSets.push_back(set.dump());
    std::string line;
    for (std::size_t i = 0; i < lines.runs.size(); ++i) {
        line = "{\"index\":" + std::to_string(i);
        line += head;
        line += inputSets.at(lines.runs[i].first);
        line += ",\"run\":";
        line += lines.runs[i].second.dump();
        line += "}\n";
        out << line;
    }
}

json manifestLineJson(const PlannedRun& r) {
    return {{"index", r.index},         {"runs", r.runs}, {"command", r.command}, {"build", r.build},
            {"precision", r.precision}, {"plan", r.plan}, {"inputs", r.inputs},   {"run", r.run}};
}

namespace {

std::optional<PlannedRun> lineFromJson(const json& j, std::string& what) {
    try {
        PlannedRun r;
        r.index = j.at("index").get<std::size_t>();
        r.runs = j.at("runs").get<std::size_t>();
        r.command = j.at("command").get<std::string>();
        r.build = j.at("build").get<std::string>();
        r.precision = j.at("precision").get<std::string>();
        r.plan = j.at("plan");
        r.inputs = j.at("inputs");
        r.run = j.at("run");
        if (!r.plan.is_object() || !r.inputs.is_object() || !r.run.is_object())
            what = "plan, inputs and run must be objects";
        else if (r.index >= r.runs) what = "index " + std::to_string(r.index) + " is not below runs";
        else return r;
    } catch (const json::exception& e) {
        what = std::string("not a manifest line: ") + e.what();
    }
    return std::nullopt;
}

} // namespace

std::optional<PlannedRun> parseManifestLine(std::string_view line, const std::string& where, std::string& error) {
    json j;
    try {
        j = json::parse(line);
    } catch (const json::parse_error& e) {
        error = where + ":" + std::to_string(e.byte == 0 ? 1 : e.byte) + ": error: not JSON: " + e.what();
        return std::nullopt;
    }
    std::string what;
    auto r = lineFromJson(j, what);
    if (!r) error = where + ":1: error: " + what;
    return r;
}

std::optional<Manifest> readManifest(const std::filesystem::path& path, const std::function<bool(std::size_t)>& want,
                                     std::string& error) {
    text::Diagnostics diags;
    const auto data = text::readFile(path, diags);
    if (!data) {
        error = diags.str();
        return std::nullopt;
    }
    Manifest m;
    std::size_t at = 0;
    while (at < data->size()) {
        std::size_t end = data->find('\n', at);
        if (end == std::string::npos) end = data->size();
        const std::string_view line(data->data() + at, end - at);
        const std::size_t index = m.runs;
        at = end + 1;
        if (line.empty()) continue;
        ++m.runs;
        if (!want(index)) continue;
        const std::string where = path.string() + ":" + std::to_string(index + 1);
        auto run = parseManifestLine(line, where, error);
        if (!run) return std::nullopt;
        if (run->index != index) {
            error = where + ":1: error: line " + std::to_string(index + 1) + " holds index " +
                    std::to_string(run->index) + " (lines must stay in plan order)";
            return std::nullopt;
        }
        m.lines.push_back(std::move(*run));
    }
    for (const PlannedRun& r : m.lines)
        if (r.runs != m.runs) {
            error = path.string() + ":" + std::to_string(r.index + 1) + ":1: error: planned " + std::to_string(r.runs) +
                    " runs, the manifest has " + std::to_string(m.runs) + " lines";
            return std::nullopt;
        }
    return m;
}

std::filesystem::path resultPath(const std::filesystem::path& dir, std::size_t index) {
    char name[48];
    std::snprintf(name, sizeof name, "run-%06zu.json", index);
    return dir / name;
}

std::string writeAtomically(const std::filesystem::path& path, const std::string& text) {
    char host[128] = "host";
    ::gethostname(host, sizeof host - 1);
    const std::filesystem::path tmp =
        path.parent_path() / ("." + path.filename().string() + ".tmp." + host + "." + std::to_string(::getpid()));
    std::FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f) return "cannot write " + tmp.string();
    const bool written =
        std::fwrite(text.data(), 1, text.size(), f) == text.size() && std::fflush(f) == 0 && ::fsync(::fileno(f)) == 0;
    const bool closed = std::fclose(f) == 0;
    std::error_code ec;
    if (written && closed) std::filesystem::rename(tmp, path, ec);
    if (!written || !closed || ec) {
        std::filesystem::remove(tmp, ec);
        return "cannot write " + path.string();
    }
    return {};
}

std::string resultFileText(const PlannedRun& line, const json& inputsSeen, const json& result, double wallSeconds) {
    char host[128] = "";
    ::gethostname(host, sizeof host - 1);
    const json j = {{"line", manifestLineJson(line)},
                    {"inputs_seen", inputsSeen},
                    {"host", host},
                    {"wall_s", wallSeconds},
                    {"result", result}};
    return j.dump() + "\n";
}

std::map<std::size_t, RunResult> readResults(const std::filesystem::path& dir, std::vector<std::string>& errors) {
    std::map<std::size_t, RunResult> out;
    std::error_code ec;
    for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
        const std::string name = entry.path().filename().string();
        if (name.rfind("run-", 0) != 0 || entry.path().extension() != ".json") continue;
        text::Diagnostics diags;
        const auto data = text::readFile(entry.path(), diags);
        RunResult r;
        r.file = entry.path();
        std::string what;
        try {
            const json j = data ? json::parse(*data) : json();
            auto line = lineFromJson(j.at("line"), what);
            if (line) {
                r.line = std::move(*line);
                r.inputsSeen = j.at("inputs_seen");
                r.result = j.at("result");
                if (resultPath(dir, r.line.index).filename() == entry.path().filename()) {
                    out.emplace(r.line.index, std::move(r));
                    continue;
                }
                what = "holds the result of index " + std::to_string(r.line.index);
            }
        } catch (const json::exception& e) {
            what = std::string("not a result file: ") + e.what();
        }
        errors.push_back(entry.path().string() + ": error: " + what);
    }
    if (ec) errors.push_back(dir.string() + ": error: " + ec.message());
    return out;
}

json exactNumber(double v) {
    if (std::isnan(v)) return "nan";
    if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
    return v;
}

double fromExactNumber(const json& v) {
    if (v.is_string()) {
        const std::string s = v.get<std::string>();
        if (s == "nan") return std::numeric_limits<double>::quiet_NaN();
        if (s == "inf") return std::numeric_limits<double>::infinity();
        if (s == "-inf") return -std::numeric_limits<double>::infinity();
    }
    return v.get<double>(); // throws type_error on anything but a number
}

} // namespace afb::sim
