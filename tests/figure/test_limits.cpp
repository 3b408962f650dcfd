// Limit excess (figure/Limits.h) against closed forms: cone angles, pyramid edges and corners
// (docs/format.md §4.3), hinge ranges centred, off-centre and across ±180° (§4.5), and invariance under a
// common rotation.
#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>

#include <Eigen/Geometry>

#include "afb/figure/Limits.h"

using afb::figure::ConeLimit;
using afb::figure::FigureConstraint;
using afb::figure::HingeRange;
using afb::figure::JointType;
using afb::figure::limitExcessRad;
using afb::figure::PyramidLimit;
using Eigen::AngleAxisd;
using Eigen::Matrix3d;
using Eigen::Vector3d;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kMargin = 1e-12;

Matrix3d about(const Vector3d& axis, double deg) { return AngleAxisd(deg * kDeg, axis.normalized()).matrix(); }

FigureConstraint coneConstraint(double halfDeg) {
    FigureConstraint c;
    c.type = JointType::BallAndSocket;
    c.body2 = 1;
    c.limit = ConeLimit{Vector3d::UnitX(), Vector3d::UnitX(), halfDeg * kDeg};
    return c;
}

// Basis f = X, l = Y, u = Z in body2; shaft X in body1.
FigureConstraint pyramidConstraint(double half1Deg, double half2Deg) {
    FigureConstraint c;
    c.type = JointType::BallAndSocket;
    c.body2 = 1;
    c.limit = PyramidLimit{Matrix3d::Identity(), Vector3d::UnitX(), half1Deg * kDeg, half2Deg * kDeg};
    return c;
}

// Hinge about `axisInBoth` (the frames' Z), frames equal at the load pose.
FigureConstraint hingeConstraint(double lowerDeg, double upperDeg, const Vector3d& axis = Vector3d::UnitZ()) {
    FigureConstraint c;
    c.type = JointType::Hinge;
    c.body2 = 1;
    const Matrix3d frame = Eigen::Quaterniond::FromTwoVectors(Vector3d::UnitZ(), axis).toRotationMatrix();
    c.frameInBody1.rotation = frame;
    c.frameInBody2.rotation = frame;
    c.limit = HingeRange{lowerDeg * kDeg, upperDeg * kDeg};
    return c;
}

// The shaft direction (1, tan a, tan b): planar angles exactly a and b.
Matrix3d shaftAt(double aDeg, double bDeg) {
    const Vector3d s = Vector3d(1, std::tan(aDeg * kDeg), std::tan(bDeg * kDeg)).normalized();
    return Eigen::Quaterniond::FromTwoVectors(Vector3d::UnitX(), s).toRotationMatrix();
}

double excessDeg(const FigureConstraint& c, const Matrix3d& body1, const Matrix3d& body2 = Matrix3d::Identity()) {
    return limitExcessRad(c, body1, body2) / kDeg;
}

} // namespace

TEST_CASE("limit excess: cone = angle from the axis minus the half angle (§4.3)", "[figure][limits]") {
    const FigureConstraint c = coneConstraint(30);
    const auto& cone = std::get<ConeLimit>(c.limit);
    CHECK(excessDeg(c, Matrix3d::Identity()) == Approx(0).margin(kMargin));
    CHECK(excessDeg(c, about(Vector3d::UnitZ(), 20)) == Approx(0).margin(kMargin));
    CHECK(excessDeg(c, about(Vector3d::UnitZ(), 30)) == Approx(0).margin(1e-5));
    CHECK(excessDeg(c, about(Vector3d::UnitZ(), 50)) == Approx(20).margin(1e-9));
    CHECK(excessDeg(c, about(Vector3d(0, 1, 1), -75)) == Approx(45).margin(1e-9));  // any direction off the axis
    CHECK(excessDeg(c, about(Vector3d::UnitY(), 180)) == Approx(150).margin(1e-5)); // anti-parallel
    CHECK(afb::figure::coneAngleRad(cone, about(Vector3d::UnitZ(), 50), Matrix3d::Identity()) / kDeg ==
          Approx(50).margin(1e-9));
    // The axis is fixed in body2: turning body2 along with body1 changes nothing; turning it back undoes it.
    CHECK(excessDeg(c, about(Vector3d::UnitZ(), 50), about(Vector3d::UnitZ(), 50)) == Approx(0).margin(1e-5));
    CHECK(excessDeg(c, about(Vector3d::UnitZ(), 50), about(Vector3d::UnitZ(), 15)) == Approx(5).margin(1e-9));
    // Twist about the shaft is free (acos is steep at 0°: a rounding error of 1e-16 reads as 1e-6°).
    CHECK(excessDeg(c, about(Vector3d::UnitX(), 120)) == Approx(0).margin(1e-5));
}

TEST_CASE("limit excess: pyramid = the larger planar-angle excess, edges and corners (§4.3)", "[figure][limits]") {
    const FigureConstraint c = pyramidConstraint(30, 20); // ±30° towards ±l, ±20° towards ±u
    const auto& p = std::get<PyramidLimit>(c.limit);

    const Eigen::Vector2d angles = afb::figure::pyramidPlanarAnglesRad(p, shaftAt(40, -25), Matrix3d::Identity());
    CHECK(angles.x() / kDeg == Approx(40).margin(1e-9));
    CHECK(angles.y() / kDeg == Approx(-25).margin(1e-9));

    // Edges: one planar angle only.
    CHECK(excessDeg(c, shaftAt(25, 0)) == Approx(0).margin(kMargin));
    CHECK(excessDeg(c, shaftAt(40, 0)) == Approx(10).margin(1e-9));
    CHECK(excessDeg(c, shaftAt(-40, 0)) == Approx(10).margin(1e-9));
    CHECK(excessDeg(c, shaftAt(0, 27)) == Approx(7).margin(1e-9));
    CHECK(excessDeg(c, shaftAt(0, -27)) == Approx(7).margin(1e-9));
    // A turn about u sweeps the (f, l) angle alone: a rotation by 35° is 5° past the 30° edge.
    CHECK(excessDeg(c, about(Vector3d::UnitZ(), 35)) == Approx(5).margin(1e-9));
    // Corners: the shaft at (29°, 19°) is 33° from f, outside a 30° cone but inside the pyramid.
    CHECK(excessDeg(c, shaftAt(29, 19)) == Approx(0).margin(kMargin));
    CHECK(excessDeg(c, shaftAt(40, 25)) == Approx(10).margin(1e-9));  // the larger of 10° and 5°
    CHECK(excessDeg(c, shaftAt(-32, -28)) == Approx(8).margin(1e-9)); // the larger of 2° and 8°
    // The basis is fixed in body2.
    const Matrix3d turn = about(Vector3d(1, 2, 3), 70);
    CHECK(excessDeg(c, turn * shaftAt(40, 25), turn) == Approx(10).margin(1e-9));
}

TEST_CASE("limit excess: hinge ranges, off-centre and across ±180° (§4.5)", "[figure][limits]") {
    const Vector3d z = Vector3d::UnitZ();
    SECTION("centred: limit 0, 90, 0 gives ±45°") {
        const FigureConstraint c = hingeConstraint(-45, 45);
        CHECK(excessDeg(c, Matrix3d::Identity()) == Approx(0).margin(kMargin));
        CHECK(excessDeg(c, about(z, 44)) == Approx(0).margin(kMargin));
        CHECK(excessDeg(c, about(z, 60)) == Approx(15).margin(1e-9));
        CHECK(excessDeg(c, about(z, -50)) == Approx(5).margin(1e-9));
        CHECK(excessDeg(c, about(z, 180)) == Approx(135).margin(1e-9)); // the far side of the circle
    }
    SECTION("off-centre: limit 30, 90, 0 gives [−75°, 15°]") {
        const FigureConstraint c = hingeConstraint(-75, 15);
        CHECK(excessDeg(c, Matrix3d::Identity()) == Approx(0).margin(kMargin));
        CHECK(excessDeg(c, about(z, 30)) == Approx(15).margin(1e-9));
        CHECK(excessDeg(c, about(z, -80)) == Approx(5).margin(1e-9));
        CHECK(excessDeg(c, about(z, -70)) == Approx(0).margin(kMargin));
        CHECK(afb::figure::hingeAngleRad(c, about(z, -70), Matrix3d::Identity()) / kDeg == Approx(-70).margin(1e-9));
    }
    SECTION("a range that excludes the load pose") {
        const FigureConstraint c = hingeConstraint(20, 80);
        CHECK(excessDeg(c, Matrix3d::Identity()) == Approx(20).margin(1e-9));
        CHECK(excessDeg(c, about(z, 50)) == Approx(0).margin(kMargin));
    }
    SECTION("across ±180°: [150°, 210°] is the 60° around the back, not its complement") {
        const FigureConstraint c = hingeConstraint(150, 210);
        CHECK(excessDeg(c, about(z, 170)) == Approx(0).margin(kMargin));
        CHECK(excessDeg(c, about(z, -170)) == Approx(0).margin(kMargin)); // = 190°
        CHECK(excessDeg(c, about(z, 140)) == Approx(10).margin(1e-9));
        CHECK(excessDeg(c, about(z, -140)) == Approx(10).margin(1e-9)); // = 220°
        CHECK(excessDeg(c, Matrix3d::Identity()) == Approx(150).margin(1e-9));
    }
    SECTION("φ is body1 relative to body2, right-handed about the frames' Z, whatever the axis") {
        const Vector3d axis(0.3, -1, 0.5);
        const FigureConstraint c = hingeConstraint(-10, 10, axis);
        CHECK(afb::figure::hingeAngleRad(c, about(axis, 25), Matrix3d::Identity()) / kDeg == Approx(25).margin(1e-9));
        CHECK(afb::figure::hingeAngleRad(c, Matrix3d::Identity(), about(axis, 25)) / kDeg == Approx(-25).margin(1e-9));
        CHECK(excessDeg(c, about(axis, 25)) == Approx(15).margin(1e-9));
        CHECK(excessDeg(c, about(axis, 179)) == Approx(169).margin(1e-9));
        CHECK(excessDeg(c, about(axis, -179)) == Approx(169).margin(1e-9));
        // A small bend off the axis (which the hinge's own rows prevent) does not read as hinge excess.
        CHECK(excessDeg(c, Matrix3d::Identity(), about(axis.cross(Vector3d::UnitX()), 5)) == Approx(0).margin(kMargin));
    }
}

TEST_CASE("limit excess: none without a limit / a common rotation (a world constraint's spawn) changes nothing",
          "[figure][limits]") {
    FigureConstraint free;
    free.type = JointType::BallAndSocket;
    CHECK(limitExcessRad(free, about(Vector3d::UnitX(), 90), Matrix3d::Identity()) == 0.0);

    const Matrix3d spawn = about(Vector3d(-2, 1, 0.5), 130);
    const FigureConstraint cone = coneConstraint(30);
    const FigureConstraint pyramid = pyramidConstraint(30, 20);
    const FigureConstraint hinge = hingeConstraint(-75, 15);
    CHECK(excessDeg(cone, spawn * about(Vector3d::UnitZ(), 50), spawn) == Approx(20).margin(1e-9));
    CHECK(excessDeg(pyramid, spawn * shaftAt(-32, -28), spawn) == Approx(8).margin(1e-9));
    CHECK(excessDeg(hinge, spawn * about(Vector3d::UnitZ(), 30), spawn) == Approx(15).margin(1e-9));
}
