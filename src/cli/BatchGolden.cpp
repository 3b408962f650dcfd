// afb golden compare as a batch: one manifest line per golden file, compared by the same compareGolden and
// reported by the same JUnit, Markdown and picture writers as the one-process command. A failing pose's picture
// travels inside its result file (base64), so the merge needs nothing but the result files.
#include <algorithm>
#include <atomic>
#include <cstdint>
#include <fstream>
#include <iostream>
#include <iterator>
#include <stdexcept>

#include <unistd.h>

#include "Batch.h"
#include "Commands.h"
#include "GoldenCli.h"
#include "Usage.h"
#include "afb/sim/Batch.h"

namespace afb::cli {
namespace {

using nlohmann::json;

constexpr char kBase64[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

// Bytes as base64 (RFC 4648, padded).
std::string toBase64(const std::string& bytes) {
    std::string out;
    out.reserve((bytes.size() + 2) / 3 * 4);
    for (std::size_t i = 0; i < bytes.size(); i += 3) {
        const std::size_t n = std::min<std::size_t>(3, bytes.size() - i);
        std::uint32_t v = 0;
        for (std::size_t k = 0; k < 3; ++k) v = v << 8 | (k < n ? static_cast<unsigned char>(bytes[i + k]) : 0u);
        for (std::size_t k = 0; k < 4; ++k) out += k <= n ? kBase64[(v >> (18 - 6 * k)) & 63u] : '=';
    }
    return out;
}

// toBase64's text back to bytes; throws on anything that is not padded base64.
std::string fromBase64(const std::string& text) {
    if (text.size() % 4 != 0) throw std::runtime_error("base64 of a length not a multiple of 4");
    std::string out;
    for (std::size_t i = 0; i < text.size(); i += 4) {
        std::uint32_t v = 0;
        int pad = 0;
        for (std::size_t k = 0; k < 4; ++k) {
            const char c = text[i + k];
            const char* at = std::char_traits<char>::find(kBase64, 64, c);
            if (c == '=' && i + 4 == text.size() && k >= 2) ++pad;
            else if (!at || pad > 0) throw std::runtime_error("not base64");
            v = v << 6 | (at ? static_cast<std::uint32_t>(at - kBase64) : 0u);
        }
        for (int k = 0; k < 3 - pad; ++k) out += static_cast<char>((v >> (16 - 8 * k)) & 0xFFu);
    }
    return out;
}

json goldenPlanJson(const GoldenCompareCli& opt) {
    json files = json::array();
    for (const std::filesystem::path& f : opt.files) files.push_back(f.generic_string());
    return {{"base", "."},
            {"files", files},
            {"exact", opt.exact},
            {"ignore_inputs", opt.ignoreInputs},
            {"junit", opt.junit.generic_string()},
            {"report", opt.report.generic_string()}};
}

GoldenCompareCli goldenCliFromPlan(const json& plan) {
    GoldenCompareCli opt;
    for (const json& f : plan.at("files")) opt.files.emplace_back(f.get<std::string>());
    opt.exact = plan.at("exact").get<bool>();
    opt.ignoreInputs = plan.at("ignore_inputs").get<bool>();
    opt.junit = plan.at("junit").get<std::string>();
    opt.report = plan.at("report").get<std::string>();
    if (opt.files.empty()) throw std::runtime_error("a golden plan needs golden files");
    return opt;
}

// A compared golden, exactly (every field the reports write; the picture as its PNG bytes, base64).
json caseJson(const GoldenCase& c) {
    json missed = json::array();
    for (const JointMiss& m : c.missed)
        missed.push_back({m.joint, sim::exactNumber(m.movedM), sim::exactNumber(m.turnedDeg)});
    return {{"file", c.file.string()},
            {"entity", c.entity},
            {"passed", c.passed},
            {"errors", c.errors},
            {"warnings", c.warnings},
            {"worst", {sim::exactNumber(c.worstM), sim::exactNumber(c.worstDeg)}},
            {"tolerance", {sim::exactNumber(c.toleranceM), sim::exactNumber(c.toleranceDeg)}},
            {"missed", missed},
            {"notes", c.notes},
            {"seconds", sim::exactNumber(c.seconds)}};
}

GoldenCase caseFromJson(const json& j) {
    GoldenCase c;
    c.file = j.at("file").get<std::string>();
    c.entity = j.at("entity").get<std::string>();
    c.passed = j.at("passed").get<bool>();
    c.errors = j.at("errors").get<std::vector<std::string>>();
    c.warnings = j.at("warnings").get<std::string>();
    c.worstM = sim::fromExactNumber(j.at("worst").at(0));
    c.worstDeg = sim::fromExactNumber(j.at("worst").at(1));
    c.toleranceM = sim::fromExactNumber(j.at("tolerance").at(0));
    c.toleranceDeg = sim::fromExactNumber(j.at("tolerance").at(1));
    for (const json& m : j.at("missed"))
        c.missed.push_back({m.at(0).get<std::string>(), sim::fromExactNumber(m.at(1)), sim::fromExactNumber(m.at(2))});
    c.notes = j.at("notes").get<std::vector<std::string>>();
    c.seconds = sim::fromExactNumber(j.at("seconds"));
    return c;
}

class GoldenJob : public BatchJob {
  public:
    explicit GoldenJob(const json& plan) : m_opt(goldenCliFromPlan(plan)) {}

    json runOne(const json& run) const override {
        const auto i = run.at("golden").get<std::size_t>();
        if (i >= m_opt.files.size() || run.at("file").get<std::string>() != m_opt.files[i].generic_string())
            throw std::runtime_error("not a run of this plan: " + run.dump());
        // A failing pose is drawn into a folder of this run's own, and its picture kept in the result.
        GoldenCompareCli opt = m_opt;
        static std::atomic<unsigned> serial{0};
        char host[128] = "host";
        ::gethostname(host, sizeof host - 1);
        if (!opt.report.empty())
            opt.report =
                std::filesystem::temp_directory_path() /
                ("afb-golden-" + std::string(host) + "-" + std::to_string(::getpid()) + "-" + std::to_string(serial++));
        std::error_code ec;
        if (!opt.report.empty() && !std::filesystem::create_directories(opt.report, ec))
            throw std::runtime_error("cannot create " + opt.report.string());
        std::vector<std::filesystem::path> pictures;
        const GoldenCase c = compareGolden(m_opt.files[i], opt, pictures);
        json result = caseJson(c);
        if (!pictures.empty()) { // a picture name taken: the drawing's bytes, or "" when it failed
            std::ifstream png(opt.report / c.picture, std::ios::binary);
            result["picture"] = c.picture.empty()
                                    ? ""
                                    : toBase64({std::istreambuf_iterator<char>(png), std::istreambuf_iterator<char>()});
        }
        if (!opt.report.empty()) std::filesystem::remove_all(opt.report, ec);
        return result;
    }

    int merge(const std::vector<std::string_view>& results, const std::filesystem::path& out) override {
        if (results.size() != m_opt.files.size()) throw std::runtime_error("the results are not the plan's runs");
        GoldenCompareCli opt = m_opt;
        if (!out.empty()) {
            if (!opt.report.empty()) opt.report = out;
            if (!opt.junit.empty() && opt.junit != "-") opt.junit = out / "junit.xml";
        }
        std::error_code ec;
        if (!out.empty()) std::filesystem::create_directories(out, ec);
        if (!opt.report.empty() && !ec) std::filesystem::create_directories(opt.report, ec);
        if (ec) {
            std::cerr << "afb merge: cannot create " << (out.empty() ? opt.report : out).string() << ": "
                      << ec.message() << "\n";
            return kExitFailure;
        }
        std::vector<GoldenCase> cases;
        std::vector<std::filesystem::path> pictures;
        for (const std::string_view text : results) {
            const json j = json::parse(text);
            cases.push_back(caseFromJson(j));
            GoldenCase& c = cases.back();
            if (const auto picture = j.find("picture"); picture != j.end() && !opt.report.empty()) {
                const std::filesystem::path name = goldenPictureName(c, pictures);
                if (const std::string png = fromBase64(picture->get<std::string>()); !png.empty()) {
                    std::ofstream(opt.report / name, std::ios::binary) << png;
                    c.picture = name;
                }
            }
            printGoldenCase(c, goldenTextStream(opt));
        }
        return finishGoldenCompare(opt, cases, pictures.size());
    }

  private:
    GoldenCompareCli m_opt;
};

} // namespace

std::unique_ptr<BatchJob> makeGoldenJob(const json& plan, std::string& error) {
    try {
        return std::make_unique<GoldenJob>(plan);
    } catch (const std::exception& e) {
        error = std::string("golden plan: ") + e.what();
    }
    return nullptr;
}

void addPlanGolden(CLI::App* plan, int& exitCode, const std::shared_ptr<std::string>& manifest,
                   const PlanEmitter& emit) {
    auto* golden = plan->add_subcommand("golden", "Plan afb golden compare: one line per golden file\n"
                                                  "Examples:\n"
                                                  "  afb plan golden compare --junit goldens.xml tests/golden/*.json "
                                                  "--manifest runs.jsonl");
    golden->require_subcommand(1);
    auto* cmd = golden->add_subcommand("compare", "Plan afb golden compare: one line per golden file\n"
                                                  "Examples:\n"
                                                  "  afb plan golden compare --report report tests/golden/*.json "
                                                  "--manifest runs.jsonl");
    auto opt = std::make_shared<GoldenCompareCli>();
    addGoldenCompareOptions(cmd, *opt);
    cmd->add_option("--manifest", *manifest, "Manifest to write, JSON lines ('-': stdout)")->capture_default_str();
    cmd->callback([opt, &exitCode, emit] {
        PlanOutput out{"golden", {goldenPlanJson(*opt), {}, {}}};
        for (std::size_t i = 0; i < opt->files.size(); ++i) {
            out.lines.inputSets.push_back(goldenInputs(opt->files[i], "."));
            out.lines.runs.emplace_back(i, json{{"file", opt->files[i].generic_string()}, {"golden", i}});
        }
        exitCode = emit(out);
    });
}

} // namespace afb::cli
