// afb chart's choices on hand-made data (Pareto front, cheapest within bounds, points from runs, method specs),
// a tiny matrix whose results do not depend on the number of threads, and the tracking panel's points.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "EntityFixture.h"
#include "afb/sim/Chart.h"
#include "afb/sim/RawRagdoll.h"
#include "afb/sim/TrackChart.h"

using namespace afb;
using sim::ChartPoint;

namespace {

ChartPoint point(const char* label, double cost, double anchorMm, double limitDeg, double penMm,
                 std::optional<double> settle, bool exploded = false) {
    ChartPoint p;
    p.figure = "f";
    p.label = label;
    p.costUs = p.costMinUs = p.costMaxUs = cost;
    p.anchorM = anchorMm / 1000.0;
    p.limitDeg = limitDeg;
    p.penetrationM = penMm / 1000.0;
    p.settleS = settle;
    p.exploded = exploded;
    return p;
}

} // namespace

TEST_CASE("chart: the Pareto front keeps exactly the non-dominated points", "[sim][chart]") {
    using V = std::vector<std::vector<double>>;
    // (cost, error): b is dominated by a (cheaper and better); d by c; e ties c exactly and is kept with it.
    const V two = {{1, 10}, {2, 11}, {3, 5}, {4, 6}, {3, 5}, {10, 1}};
    CHECK(sim::paretoFront(two) == std::vector<std::size_t>{0, 2, 4, 5});
    // Equal cost, different error: only the better one.
    CHECK(sim::paretoFront(V{{1, 2}, {1, 3}}) == std::vector<std::size_t>{0});
    // Three objectives: a point worse in two but best in the third stays.
    CHECK(sim::paretoFront(V{{1, 1, 9}, {2, 2, 1}, {3, 3, 9}}) == std::vector<std::size_t>{0, 1});
    CHECK(sim::paretoFront(V{}).empty());
    CHECK(sim::paretoFront(V{{5, 5}}) == std::vector<std::size_t>{0});
    // Infinity (never settled) is worse than any finite value.
    const double inf = std::numeric_limits<double>::infinity();
    CHECK(sim::paretoFront(V{{1, inf}, {2, 3}, {3, inf}}) == std::vector<std::size_t>{0, 1});
}

TEST_CASE("chart: the front of chart points uses the cost and the chosen errors", "[sim][chart]") {
    const std::vector<ChartPoint> points = {
        point("raw", 1.0, 150, 60, 100, std::nullopt),
        point("fast", 2.0, 30, 20, 80, 3.0),
        point("slow-and-bad", 3.0, 40, 25, 90, 4.0),
        point("exact", 5.0, 10, 10, 20, 2.0),
        point("boom", 0.5, 1, 1, 1, 1.0, true), // would dominate everything, but exploded: no choice
        point("asleep", 0.0, 1, 1, 1, 0.0),     // never awake: no cost to compare
    };
    CHECK(sim::chartFront(points, {sim::ChartMetric::Anchor}) == std::vector<std::size_t>{0, 1, 3});
    const std::vector<sim::ChartMetric> all(std::begin(sim::kChartMetrics), std::end(sim::kChartMetrics));
    CHECK(sim::chartFront(points, all) == std::vector<std::size_t>{0, 1, 3});
    // In cost and settle time alone, raw (never at rest) is still the cheapest method: on the front.
    CHECK(sim::chartFront(points, {sim::ChartMetric::Settle}) == std::vector<std::size_t>{0, 1, 3});
    CHECK(sim::chartFront(points, {sim::ChartMetric::Penetration}) == std::vector<std::size_t>{0, 1, 3});
    CHECK(std::isinf(sim::metricValue(points[0], sim::ChartMetric::Settle)));
    CHECK(sim::metricValue(points[1], sim::ChartMetric::Anchor) == Approx(30));
}

TEST_CASE("chart: the cheapest method within bounds", "[sim][chart]") {
    const std::vector<ChartPoint> points = {
        point("raw", 1.0, 150, 60, 100, std::nullopt),
        point("boom", 0.5, 5, 1, 1, 1.0, true), // cheapest and accurate, but it exploded
        point("fast", 2.0, 30, 20, 80, 3.0),
        point("exact", 5.0, 10, 10, 20, 2.0),
        point("exact-twin", 5.0, 10, 10, 20, 2.0),
    };
    sim::ChartBounds none;
    CHECK_FALSE(none.any());
    CHECK(sim::cheapestWithin(points, none) == 0u);
    sim::ChartBounds anchor;
    anchor.anchorM = 0.035;
    CHECK(sim::cheapestWithin(points, anchor) == 2u);
    anchor.anchorM = 0.010; // a bound met exactly counts as met; the first of a tie wins
    CHECK(sim::cheapestWithin(points, anchor) == 3u);
    anchor.anchorM = 0.001;
    CHECK_FALSE(sim::cheapestWithin(points, anchor));
    sim::ChartBounds settle;
    settle.settleS = 100.0; // demands coming to rest: raw never does
    CHECK(sim::cheapestWithin(points, settle) == 2u);
    sim::ChartBounds mixed;
    mixed.limitDeg = 25;
    mixed.penetrationM = 0.05;
    CHECK(sim::cheapestWithin(points, mixed) == 3u);
}

TEST_CASE("chart: the summary recommends only a method inside the bounds it names", "[sim][chart]") {
    // raw is the cheapest that does not explode but is far off at the joints; fast is within the default bounds
    // (10 mm, 5°, 20 mm) only in anchor; exact is within all of them.
    const std::vector<ChartPoint> points = {
        point("raw", 1.0, 98, 34, 25, std::nullopt),
        point("fast", 2.0, 9, 14, 25, 3.0),
        point("exact", 5.0, 0.1, 0.2, 5, 2.0),
    };
    const sim::ChartOptions options;
    const std::string given = sim::chartSummaryMarkdown(points, options, {}, 3);
    CHECK_THAT(given, Catch::Contains("Cheapest within anchor ≤ 10 mm, limit ≤ 5°, penetration ≤ 20 mm (the default "
                                      "bounds; set others with --max-anchor-error"));
    CHECK_THAT(given, Catch::Contains("): `exact`."));
    CHECK_THAT(given, !Catch::Contains("does not explode"));
    sim::ChartBounds loose;
    loose.anchorM = 0.2;
    const std::string wide = sim::chartSummaryMarkdown(points, options, loose, 3);
    CHECK_THAT(wide, Catch::Contains("Cheapest within anchor ≤ 200 mm: `raw`."));
    sim::ChartBounds tight;
    tight.anchorM = 0.00001;
    CHECK_THAT(sim::chartSummaryMarkdown(points, options, tight, 3),
               Catch::Contains("Cheapest within anchor ≤ 0.01 mm: none of the methods charted."));
}

TEST_CASE("chart: points fold runs into median cost and worst errors", "[sim][chart]") {
    std::vector<sim::ChartRun> runs;
    // Method "m" on figure 0: two heights × three repeats. Cost per repeat = (sum of CPU ms) / (sum of body-steps).
    const double cpuMs[3][2] = {{1.0, 3.0}, {2.0, 2.0}, {10.0, 10.0}};
    for (int r = 0; r < 3; ++r)
        for (int h = 0; h < 2; ++h) {
            sim::ChartRun run;
            run.label = "m";
            run.figure = 0;
            run.heightM = h == 0 ? 1.0 : 10.0;
            run.repeat = r;
            run.result.awakeStepCpuMs = cpuMs[r][h];
            run.result.awakeBodySteps = 1000;
            run.result.maxAnchorErrorM = h == 0 ? 0.01 : 0.05;
            run.result.maxLimitViolationDeg = h == 0 ? 7 : 3;
            run.result.maxPenetrationM = 0.02;
            run.result.settleTimeS = h == 0 ? 2.0 : 4.0;
            runs.push_back(run);
        }
    runs[1].result.settleTimeS.reset(); // one run never came to rest
    // A fourth repeat in which nothing was ever awake has no cost to give and does not count.
    sim::ChartRun asleep = runs[0];
    asleep.repeat = 3;
    asleep.result.awakeBodySteps = 0;
    asleep.result.awakeStepCpuMs = 0;
    runs.push_back(asleep);
    const std::vector<ChartPoint> points = sim::chartPoints(runs, {"fig"}, {{"m", bullet::Method{}}});
    REQUIRE(points.size() == 1);
    const ChartPoint& p = points[0];
    CHECK(p.figure == "fig");
    // Repeats cost 4, 4 and 20 ms per 2000 body-steps: 2, 2 and 10 µs; median 2.
    CHECK(p.costUs == Approx(2.0));
    CHECK(p.costMinUs == Approx(2.0));
    CHECK(p.costMaxUs == Approx(10.0));
    CHECK(p.anchorM == Approx(0.05));
    CHECK(p.limitDeg == Approx(7));
    CHECK_FALSE(p.settleS);
    CHECK_FALSE(p.exploded);
}

TEST_CASE("chart: method specs are a name and knob overrides", "[sim][chart]") {
    std::string error;
    auto m = sim::parseChartMethod("default:substeps=2:iterations=30", error);
    REQUIRE(m);
    CHECK(m->label == "default:substeps=2:iterations=30");
    CHECK(m->method.name == "default");
    CHECK(m->method.substeps == 2);
    CHECK(m->method.iterations == 30);
    auto raw = sim::parseChartMethod("raw:substeps=4", error);
    REQUIRE(raw);
    CHECK(sim::isRaw(raw->method));
    CHECK(raw->method.substeps == 4);
    CHECK_FALSE(sim::parseChartMethod("nonsense", error));
    CHECK(error.find("unknown method") != std::string::npos);
    CHECK_FALSE(sim::parseChartMethod("default:substeps", error));
    CHECK_FALSE(sim::parseChartMethod("default:no-such-knob=1", error));
    CHECK_FALSE(sim::parseChartMethod("default:substeps=0", error));
    CHECK_FALSE(sim::parseChartMethod("raw:speculative-limits=on", error));
    CHECK(error.find("speculative-limits") != std::string::npos);
}

TEST_CASE("chart: a small matrix gives the same results on one thread and on two", "[sim][chart]") {
    const std::vector<figure::Figure> figures = {test::loadEntity("chain").figure};
    sim::ChartOptions o;
    std::string error;
    o.methods = {*sim::parseChartMethod("raw", error), *sim::parseChartMethod("fast", error)};
    o.heightsM = {1.0};
    o.repeats = 2;
    o.seconds = 0.5;
    o.threads = 1;
    int calls = 0, lastDone = -1;
    const std::vector<sim::ChartRun> one = sim::runChart(figures, o, [&](int done, int total) {
        ++calls;
        CHECK(total == 4);
        CHECK(done >= lastDone);
        lastDone = done;
    });
    CHECK(calls > 0);
    CHECK(lastDone == 4);
    o.threads = 2;
    const std::vector<sim::ChartRun> two = sim::runChart(figures, o);
    REQUIRE(one.size() == 4);
    REQUIRE(two.size() == 4);
    for (std::size_t i = 0; i < one.size(); ++i) {
        INFO(one[i].label << " repeat " << one[i].repeat);
        CHECK(one[i].label == two[i].label);
        CHECK(one[i].repeat == two[i].repeat);
        CHECK(one[i].result.maxAnchorErrorM == two[i].result.maxAnchorErrorM);
        CHECK(one[i].result.maxLimitViolationDeg == two[i].result.maxLimitViolationDeg);
        CHECK(one[i].result.maxPenetrationM == two[i].result.maxPenetrationM);
        CHECK(one[i].result.awakeBodySteps == two[i].result.awakeBodySteps);
        CHECK(one[i].result.stepCpuMs > 0);
        CHECK(one[i].result.awakeStepCpuMs <= one[i].result.stepCpuMs);
    }
    CHECK(one[0].label == "raw");
    CHECK(one[2].label == "fast");
    const std::string csv = sim::chartRunsCsv(one);
    CHECK(csv.rfind("method_label,height_m,hz,repeat,figure,", 0) == 0);
    CHECK(std::count(csv.begin(), csv.end(), '\n') == 5);
}

TEST_CASE("chart: the tracking panel has one point per method and strength, stronger motors closer to the walk",
          "[sim][chart][track]") {
    const auto loaded = test::loadEntity("humanoid");
    text::Diagnostics diags;
    const auto walk = decl::loadMd5Anim(test::sourceDir() / "models/md5/humanoid/walk.md5anim", diags);
    REQUIRE(walk);
    sim::TrackChartOptions o;
    std::string error;
    o.methods = {*sim::parseChartMethod("default", error)};
    o.strengths = {0.25, 4};
    o.repeats = 2;
    o.track.seconds = 1.5;
    const auto points = sim::runTrackChart({loaded.figure}, *walk, o, diags);
    INFO(diags.str());
    REQUIRE(points);
    REQUIRE(points->size() == 2);
    const sim::TrackChartPoint& weak = (*points)[0];
    const sim::TrackChartPoint& strong = (*points)[1];
    CHECK(weak.figure == "humanoid");
    CHECK(weak.label == "default");
    CHECK(weak.strength == 0.25);
    CHECK(strong.strength == 4);
    // Sixteen times the gains follow the walk more closely, down to the floor of the arms' twist that the universal
    // shoulders lock (measured 13.8 mm / 4.27° against 15.8 mm / 4.43° over these 1.5 s).
    CHECK(strong.trackingRmsMm < 0.95 * weak.trackingRmsMm);
    CHECK(strong.trackingRmsDeg < weak.trackingRmsDeg);
    for (const sim::TrackChartPoint& p : *points) {
        CHECK(p.costUs > 0);
        CHECK(p.costMinUs <= p.costUs);
        CHECK(p.costUs <= p.costMaxUs);
        CHECK_FALSE(p.exploded);
    }
    const std::string md = sim::trackChartMarkdown(*points, o);
    CHECK(md.find("## humanoid") != std::string::npos);
    CHECK(md.find("| default | 0.25 |") != std::string::npos);
    CHECK(md.find("| default | 4.00 |") != std::string::npos);
}
