// Run manifests and result files (sim/Batch.h): lines written and read back by index, results that round-trip
// every double bit for bit (NaN and infinities too), atomic writes, and a matrix run line by line equal to the
// matrix run at once.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "EntityFixture.h"
#include "afb/sim/Batch.h"
#include "afb/sim/Chart.h"
#include "afb/sim/Report.h"

using namespace afb;
using nlohmann::json;

namespace {

std::filesystem::path scratch(const std::string& name) {
    const auto dir = std::filesystem::temp_directory_path() / ("afb_test_batch_" + name);
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

} // namespace

TEST_CASE("a manifest is read back line by line, only the selected lines parsed") {
    const auto dir = scratch("manifest");
    std::vector<json> runs;
    for (int i = 0; i < 5; ++i) runs.push_back({{"yaw", i}});
    {
        std::ofstream out(dir / "m.jsonl");
        sim::PlanLines lines{{{"yaws", 5}}, {json::object(), {{"af/a.af", "0123"}}}, {}};
        for (std::size_t i = 0; i < runs.size(); ++i) lines.runs.emplace_back(i % 2, runs[i]);
        sim::writeManifest(out, "stress", "build X", "float", lines);
    }
    std::string error;
    const auto m = sim::readManifest(
        dir / "m.jsonl", [](std::size_t i) { return i % 2 == 1; }, error);
    REQUIRE(m);
    CHECK(m->runs == 5);
    REQUIRE(m->lines.size() == 2);
    CHECK(m->lines[0].index == 1);
    CHECK(m->lines[1].index == 3);
    CHECK(m->lines[1].run.at("yaw") == 3);
    CHECK(m->lines[1].plan.at("yaws") == 5);
    CHECK(m->lines[1].build == "build X");
    CHECK(m->lines[1].inputs.at("af/a.af") == "0123");
    CHECK(m->lines[0].inputs.at("af/a.af") == "0123");

    // A line that is not JSON is an error with its file and line.
    {
        std::ofstream out(dir / "bad.jsonl");
        std::ifstream in(dir / "m.jsonl");
        std::string line;
        for (int i = 0; std::getline(in, line); ++i) out << (i == 2 ? std::string("{\"index\": 2,") : line) << "\n";
    }
    const auto bad = sim::readManifest(
        dir / "bad.jsonl", [](std::size_t) { return true; }, error);
    CHECK_FALSE(bad);
    CHECK(error.find("bad.jsonl:3:") != std::string::npos);
    CHECK(error.find("error:") != std::string::npos);
    // Lines out of order are refused: a result file is named by its line's position.
    {
        std::ofstream out(dir / "swapped.jsonl");
        std::ifstream in(dir / "m.jsonl");
        std::vector<std::string> lines;
        for (std::string line; std::getline(in, line);) lines.push_back(line);
        std::swap(lines[0], lines[1]);
        for (const std::string& line : lines) out << line << "\n";
    }
    CHECK_FALSE(sim::readManifest(
        dir / "swapped.jsonl", [](std::size_t) { return true; }, error));
    CHECK(error.find("holds index 1") != std::string::npos);
}

TEST_CASE("exact numbers round-trip every double, NaN and infinities included") {
    for (double v : {0.1, -0.0, 1e-310, 1.0 / 3.0, 123456789.123456789, std::numeric_limits<double>::max(),
                     std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()}) {
        const json j = json::parse(sim::exactNumber(v).dump());
        CHECK(sameBits(sim::fromExactNumber(j), v));
    }
    CHECK(std::isnan(sim::fromExactNumber(json::parse(sim::exactNumber(std::nan("")).dump()))));
    CHECK_THROWS(sim::fromExactNumber(json("seven")));
}

TEST_CASE("a drop result round-trips exactly, and its reports are equal") {
    sim::DropOptions options;
    options.seconds = 0.5;
    options.count = 2;
    const sim::DropResult result = sim::runDrop(test::loadEntity("chain").figure, options);
    REQUIRE_FALSE(result.finalPose.empty());
    const sim::DropResult back = sim::dropResultFromExact(json::parse(sim::dropResultExact(result).dump()));
    CHECK(sim::dropCsvRow(back) == sim::dropCsvRow(result));
    CHECK(sim::dropResultJson(back).dump() == sim::dropResultJson(result).dump());
    REQUIRE(back.firstBodies.size() == result.firstBodies.size());
    CHECK(back.firstBodies.back().rotation == result.firstBodies.back().rotation);
    CHECK(back.firstSpawn.position == result.firstSpawn.position);
}

TEST_CASE("stress runs one by one equal the matrix, through their result files") {
    std::vector<const sim::StressScenario*> scenarios = {sim::findStressScenario("tiny-bodies")};
    std::string error;
    std::vector<sim::StressMethod> methods = {*sim::parseStressMethod("fast", error),
                                              *sim::parseStressMethod("default", error)};
    const std::vector<sim::StressResult> matrix = sim::runStressMatrix(scenarios, methods, {}, {}, 2, 2);
    std::vector<sim::StressResult> single;
    for (const sim::StressMethod& m : methods)
        for (std::size_t k = 0; k < 2; ++k) {
            const double yaw = sim::stressYawDeg(k, 2);
            const auto setup = sim::yawedSetup(*scenarios[0]->build({}), yaw);
            const json j = sim::stressResultExact(sim::runStressRun(setup, scenarios[0]->name, m, {}, yaw));
            single.push_back(sim::stressResultFromExact(json::parse(j.dump())));
        }
    // Every field but the CPU time is the same: the tables, Markdown and JSON agree once it is set alike.
    REQUIRE(single.size() == matrix.size());
    for (std::size_t i = 0; i < single.size(); ++i) single[i].cpuMs = matrix[i].cpuMs;
    const sim::StressThresholds th;
    CHECK(sim::stressJson(single, methods, th) == sim::stressJson(matrix, methods, th));
    CHECK(sim::stressMarkdown(single, methods, th) == sim::stressMarkdown(matrix, methods, th));
}

TEST_CASE("result files are written atomically and read back by index") {
    const auto dir = scratch("results");
    sim::PlannedRun line{3, 4, "stress", "build X", "float", {{"yaws", 4}}, json::object(), {{"yaw", 3}}};
    REQUIRE(sim::writeAtomically(sim::resultPath(dir, 3), sim::resultFileText(line, json::object(), {{"v", 1}}, 0.5))
                .empty());
    CHECK(sim::resultPath(dir, 3).filename() == "run-000003.json");
    // A temporary file left by a killed run and a result misnamed are not results; the second is an error.
    std::ofstream(dir / ".run-000002.json.tmp.host.1") << "{\"partial";
    std::filesystem::copy_file(sim::resultPath(dir, 3), sim::resultPath(dir, 1));
    std::vector<std::string> errors;
    const auto results = sim::readResults(dir, errors);
    REQUIRE(results.size() == 1);
    const sim::RunResult& r = results.at(3);
    CHECK(json::parse(r.result).at("v") == 1);
    CHECK(r.index == 3);
    CHECK(r.runs == 4);
    CHECK(r.build == "build X");
    // The header names the line by hashes: the plan's (its head), the planned and the found input sets'.
    CHECK(r.plan ==
          sim::fnv1a(R"("runs":4,"command":"stress","build":"build X","precision":"float","plan":{"yaws":4})"));
    CHECK(r.inputs == sim::fnv1a("{}"));
    CHECK(r.inputsSeen == r.inputs);
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].find("run-000001.json: error: holds the result of index 3") != std::string::npos);
    // Writing into a folder that does not exist fails with a message and leaves nothing.
    CHECK_FALSE(sim::writeAtomically(dir / "no" / "run-000000.json", "x").empty());
}

TEST_CASE("a manifest line is named by the hash of its text, its plan by a plan file") {
    const auto dir = scratch("hashes");
    {
        std::ofstream out(dir / "m.jsonl");
        sim::PlanLines lines;
        lines.plan = json{{"yaws", 2}};
        lines.inputSets.push_back(json{{"af/a.af", "0123"}});
        lines.runs.emplace_back(0, json{{"yaw", 0}});
        lines.runs.emplace_back(0, json{{"yaw", 1}});
        sim::writeManifest(out, "stress", "build X", "float", lines);
    }
    std::ifstream in(dir / "m.jsonl");
    std::vector<std::string> texts;
    for (std::string line; std::getline(in, line);) texts.push_back(line);
    REQUIRE(texts.size() == 2);
    std::string error;
    const auto m = sim::readManifest(
        dir / "m.jsonl", [](std::size_t i) { return i == 1; }, error, true);
    REQUIRE(m);
    REQUIRE(m->lineHashes.size() == 2);
    CHECK(m->lineHashes[0] == sim::fnv1a(texts[0]));
    CHECK(m->lineHashes[1] == sim::fnv1a(texts[1]));
    REQUIRE(m->lines.size() == 1);
    CHECK(m->lines[0].lineHash == m->lineHashes[1]);
    // The plan file holds the head every line shares, and reads back as the same plan.
    const sim::PlannedRun& line = m->lines[0];
    const std::uint64_t hash = sim::planHash(line);
    CHECK(texts[0].find(sim::manifestHead(2, "stress", "build X", "float", json{{"yaws", 2}})) != std::string::npos);
    REQUIRE(sim::writeAtomically(sim::planFilePath(dir, hash), sim::planFileText(line)).empty());
    const auto plan = sim::readPlanFile(sim::planFilePath(dir, hash), hash, error);
    REQUIRE(plan);
    CHECK(plan->plan == line.plan);
    CHECK(plan->build == "build X");
    // A plan file whose text was changed is not the plan it is named after.
    std::ofstream(sim::planFilePath(dir, hash))
        << R"({"runs":2,"command":"stress","build":"build Y","precision":"float","plan":{"yaws":2}})";
    CHECK_FALSE(sim::readPlanFile(sim::planFilePath(dir, hash), hash, error));
    CHECK(error.find("not the plan") != std::string::npos);
}
