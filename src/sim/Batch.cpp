// Run manifests and result files (Batch.h): JSON lines written once and read by line, results written atomically.
#include "afb/sim/Batch.h"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <thread>

#include <fcntl.h>
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

std::string manifestHead(std::size_t runs, const std::string& command, const std::string& build,
                         const std::string& precision, const json& plan) {
    return "\"runs\":" + std::to_string(runs) + ",\"command\":" + json(command).dump() +
           ",\"build\":" + json(build).dump() + ",\"precision\":" + json(precision).dump() + ",\"plan\":" + plan.dump();
}

std::uint64_t planHash(const PlannedRun& r) {
    return fnv1a(manifestHead(r.runs, r.command, r.build, r.precision, r.plan));
}

void writeManifest(std::ostream& out, const std::string& command, const std::string& build,
                   const std::string& precision, const PlanLines& lines) {
    // The same for every line: serialised once (a manifest of 100 000 lines is written in a fraction of a second).
    const std::string head =
        "," + manifestHead(lines.runs.size(), command, build, precision, lines.plan) + ",\"inputs\":";
    std::vector<std::string> inputSets;
    for (const json& set : lines.inputSets) inputSets.push_back(set.dump());
    std::string chunk;
    for (std::size_t i = 0; i < lines.runs.size(); ++i) {
        chunk += "{\"index\":";
        chunk += std::to_string(i);
        chunk += head;
        chunk += inputSets.at(lines.runs[i].first);
        chunk += ",\"run\":";
        chunk += lines.runs[i].second.dump();
        chunk += "}\n";
        if (chunk.size() < (1u << 20)) continue;
        out.write(chunk.data(), static_cast<std::streamsize>(chunk.size()));
        chunk.clear();
    }
    out.write(chunk.data(), static_cast<std::streamsize>(chunk.size()));
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
    else r->lineHash = fnv1a(line);
    return r;
}

std::optional<Manifest> readManifest(const std::filesystem::path& path, const std::function<bool(std::size_t)>& want,
                                     std::string& error, bool hashEvery) {
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
        if (hashEvery) m.lineHashes.push_back(fnv1a(line));
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
    const json header = {{"index", line.index},
                         {"runs", line.runs},
                         {"command", line.command},
                         {"build", line.build},
                         {"precision", line.precision},
                         {"plan", hashHex(planHash(line))},
                         {"line", hashHex(line.lineHash)},
                         {"inputs", hashHex(fnv1a(line.inputs.dump()))},
                         {"inputs_seen", hashHex(fnv1a(inputsSeen.dump()))},
                         {"host", host},
                         {"wall_s", wallSeconds}};
    return header.dump() + "\n" + result.dump() + "\n";
}

namespace {

// A file's bytes into `data` (reused between files: no allocation once it is large enough); false when unreadable.
bool slurp(const std::filesystem::path& path, std::string& data) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return false;
    data.clear();
    char buf[1 << 14];
    for (;;) {
        const ssize_t n = ::read(fd, buf, sizeof buf);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) {
            ::close(fd);
            return n == 0;
        }
        data.append(buf, static_cast<std::size_t>(n));
    }
}

// 16 hex digits back to their value; throws on anything else.
std::uint64_t hexHash(const json& v) {
    const std::string& s = v.get_ref<const std::string&>();
    std::uint64_t h = 0;
    if (s.size() != 16) throw std::runtime_error("a hash of 16 hex digits expected: '" + s + "'");
    for (char c : s) {
        const int d = c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : -1;
        if (d < 0) throw std::runtime_error("a hash of 16 hex digits expected: '" + s + "'");
        h = h << 4 | static_cast<std::uint64_t>(d);
    }
    return h;
}

// One result file's text into `r`; an empty string, or why it is not a result file.
std::string parseResult(const std::string& data, RunResult& r) {
    const std::size_t eol = data.find('\n');
    if (eol == std::string::npos || data.size() < eol + 3 || data.back() != '\n')
        return "not a result file (a header line and a result line)";
    try {
        const json h = json::parse(std::string_view(data.data(), eol));
        r.index = h.at("index").get<std::size_t>();
        r.runs = h.at("runs").get<std::size_t>();
        r.command = h.at("command").get<std::string>();
        r.build = h.at("build").get<std::string>();
        r.precision = h.at("precision").get<std::string>();
        r.plan = hexHash(h.at("plan"));
        r.line = hexHash(h.at("line"));
        r.inputs = hexHash(h.at("inputs"));
        r.inputsSeen = hexHash(h.at("inputs_seen"));
    } catch (const std::exception& e) {
        return std::string("not a result file: ") + e.what();
    }
    r.result.assign(data, eol + 1, data.size() - eol - 2);
    return {};
}

} // namespace

void forEachIndex(std::size_t n, const std::function<void(std::size_t)>& fn) {
    const std::size_t threads = std::min<std::size_t>({n, std::max(1u, std::thread::hardware_concurrency()), 8});
    std::atomic<std::size_t> next{0};
    std::exception_ptr first;
    std::mutex mutex;
    auto worker = [&] {
        for (std::size_t i = next++; i < n; i = next++) try {
                fn(i);
            } catch (...) {
                const std::lock_guard lock(mutex);
                if (!first) first = std::current_exception();
                next = n;
            }
    };
    std::vector<std::thread> pool;
    for (std::size_t t = 1; t < threads; ++t) pool.emplace_back(worker);
    worker();
    for (std::thread& t : pool) t.join();
    if (first) std::rethrow_exception(first);
}

std::map<std::size_t, RunResult> readResults(const std::filesystem::path& dir, std::vector<std::string>& errors) {
    std::vector<std::filesystem::path> files;
    std::error_code ec;
    for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
        const std::string name = entry.path().filename().string();
        if (name.size() > 9 && name.compare(0, 4, "run-") == 0 && name.compare(name.size() - 5, 5, ".json") == 0)
            files.push_back(entry.path());
    }
    // Read and their headers parsed on every core (a merge of 100 000 results is mostly this).
    std::vector<RunResult> read(files.size());
    std::vector<std::string> why(files.size());
    forEachIndex(files.size(), [&](std::size_t i) {
        thread_local std::string data;
        RunResult& r = read[i];
        why[i] = slurp(files[i], data) ? parseResult(data, r) : "cannot be read";
        if (why[i].empty() && resultPath(dir, r.index).filename() != files[i].filename())
            why[i] = "holds the result of index " + std::to_string(r.index);
        r.file = std::move(files[i]);
    });
    std::map<std::size_t, RunResult> out;
    for (std::size_t i = 0; i < read.size(); ++i) {
        if (!why[i].empty()) errors.push_back(read[i].file.string() + ": error: " + why[i]);
        else out.emplace_hint(out.end(), read[i].index, std::move(read[i]));
    }
    if (ec) errors.push_back(dir.string() + ": error: " + ec.message());
    return out;
}

std::filesystem::path planFilePath(const std::filesystem::path& dir, std::uint64_t hash) {
    return dir / ("plan-" + hashHex(hash) + ".json");
}

std::string planFileText(const PlannedRun& line) {
    return "{" + manifestHead(line.runs, line.command, line.build, line.precision, line.plan) + "}\n";
}

std::optional<PlannedRun> readPlanFile(const std::filesystem::path& path, std::uint64_t hash, std::string& error) {
    std::string data;
    if (!slurp(path, data)) {
        error = path.string() + ": error: cannot be read";
        return std::nullopt;
    }
    PlannedRun r;
    try {
        const json j = json::parse(data);
        r.runs = j.at("runs").get<std::size_t>();
        r.command = j.at("command").get<std::string>();
        r.build = j.at("build").get<std::string>();
        r.precision = j.at("precision").get<std::string>();
        r.plan = j.at("plan");
    } catch (const json::exception& e) {
        error = path.string() + ": error: not a plan file: " + e.what();
        return std::nullopt;
    }
    if (planHash(r) != hash) {
        error = path.string() + ": error: not the plan " + hashHex(hash) + " (its text was changed)";
        return std::nullopt;
    }
    return r;
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
