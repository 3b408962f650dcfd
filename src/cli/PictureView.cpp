// One panel of a figure picture: bodies back to front, skeleton, anchors, limits and masses in one view.
#include "PictureView.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>

namespace afb::cli {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;
constexpr double kMarkPx = 4.5; // half size of an anchor mark

void setColour(cairo_t* cr, const Rgb& c, double alpha = 1.0) { cairo_set_source_rgba(cr, c.r, c.g, c.b, alpha); }
Rgb scaled(const Rgb& c, double k) { return {c.r * k, c.g * k, c.b * k}; }

void moveTo(cairo_t* cr, const Vector2d& p) { cairo_move_to(cr, p.x(), p.y()); }
void lineTo(cairo_t* cr, const Vector2d& p) { cairo_line_to(cr, p.x(), p.y()); }
void line(cairo_t* cr, const Vector2d& a, const Vector2d& b) {
    moveTo(cr, a);
    lineTo(cr, b);
}
void polyline(cairo_t* cr, const std::vector<Vector2d>& points, bool closed) {
    for (std::size_t i = 0; i < points.size(); ++i) i == 0 ? moveTo(cr, points[i]) : lineTo(cr, points[i]);
    if (closed) cairo_close_path(cr);
}

// Any two unit vectors that make a right-handed orthonormal basis with `axis`.
std::pair<Vector3d, Vector3d> perpendicular(const Vector3d& axis) {
    const Vector3d helper = std::abs(axis.x()) < 0.9 ? Vector3d::UnitX() : Vector3d::UnitY();
    const Vector3d u = axis.cross(helper).normalized();
    return {u, axis.cross(u)};
}

// Body2's frame at the pose: the body, or the spawn frame itself for a constraint to the world.
figure::Transform body2Frame(const PictureRequest& request, const figure::FigureConstraint& c) {
    return c.body2 >= 0 ? request.bodies[static_cast<std::size_t>(c.body2)] : figure::Transform{};
}

struct Face {
    double depth;
    std::size_t body;
    double facing; // cosine between the outward normal and the direction to the viewer
    std::vector<Vector2d> px;
};

// Painter's order: the faces turned toward the viewer, farthest first. The polytopes are convex, so culling
// the back faces leaves only the order between bodies to get right, which centroid depth does for touching
// limbs. With a `tint`, every body is filled in that one colour at `alpha` (a pose of a two-pose picture).
void drawBodies(cairo_t* cr, const figure::Figure& figure, const PictureRequest& request, const PanelMapping& panel,
                const std::optional<Rgb>& tint = std::nullopt, double alpha = 1.0) {
    std::vector<Face> faces;
    for (std::size_t i = 0; i < figure.bodies.size(); ++i) {
        const figure::BodyShape& shape = figure.bodies[i].shape;
        std::vector<Vector3d> world;
        for (const Vector3d& v : shape.vertices) world.push_back(request.bodies[i].apply(v));
        for (const std::vector<int>& loop : shape.faces) {
            Vector3d normal = Vector3d::Zero(), centroid = Vector3d::Zero(); // Newell's normal of the loop
            for (std::size_t k = 0; k < loop.size(); ++k) {
                const Vector3d& a = world[static_cast<std::size_t>(loop[k])];
                const Vector3d& b = world[static_cast<std::size_t>(loop[(k + 1) % loop.size()])];
                normal += Vector3d((a.y() - b.y()) * (a.z() + b.z()), (a.z() - b.z()) * (a.x() + b.x()),
                                   (a.x() - b.x()) * (a.y() + b.y()));
                centroid += a;
            }
            if (loop.size() < 3 || normal.norm() == 0) continue;
            const double facing = normal.normalized().dot(panel.axes.toViewer);
            // A face seen edge-on shows nothing but its outline, which its neighbours draw; culling it by a margin
            // wider than rounding keeps a pose that differs only by rounding (float spawn transforms) the same
            // picture, where a face at ±1e-8 would be drawn as a one-pixel line or not.
            if (facing <= 1e-4) continue;
            Face f{panel.depth(centroid / static_cast<double>(loop.size())), i, facing, {}};
            for (int v : loop) f.px.push_back(panel.toPx(world[static_cast<std::size_t>(v)]));
            faces.push_back(std::move(f));
        }
    }
    // Depths within a hundredth of a millimetre are a tie, kept in body order: faces of touching bodies at one
    // depth would otherwise swap with rounding and redraw their shared edge in the other body's outline.
    const auto level = [](double depth) { return std::llround(depth * 1e5); };
    std::stable_sort(faces.begin(), faces.end(),
                     [&](const Face& a, const Face& b) { return level(a.depth) < level(b.depth); });
    cairo_set_line_width(cr, 1.0);
    cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
    for (const Face& f : faces) {
        const Rgb base = tint ? *tint : bodyColour(f.body);
        polyline(cr, f.px, true);
        setColour(cr, scaled(base, 0.78 + 0.22 * f.facing), alpha); // faces turned away are darker
        cairo_fill_preserve(cr);
        setColour(cr, scaled(base, 0.5), tint ? 0.8 : 1.0);
        cairo_stroke(cr);
    }
}

void drawSkeleton(cairo_t* cr, const figure::Figure& figure, const PictureRequest& request, const PanelMapping& panel,
                  const Rgb& colour = skeletonColour()) {
    const figure::Skeleton& skeleton = figure.skeleton;
    const std::size_t n = std::min(request.joints.size(), static_cast<std::size_t>(skeleton.jointCount()));
    setColour(cr, colour, 0.9);
    cairo_set_line_width(cr, 1.6);
    cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
    // The root (joint 0, "origin" in id's models) is the entity origin, not a bone end: no line leads to it,
    // and it is drawn as a ring (after a drop it can lie far from the bodies, as the engine places it).
    for (std::size_t j = 1; j < n; ++j) {
        const int parent = skeleton.parent(static_cast<int>(j));
        if (parent <= 0) continue;
        line(cr, panel.toPx(request.joints[j].position),
             panel.toPx(request.joints[static_cast<std::size_t>(parent)].position));
    }
    cairo_stroke(cr);
    for (std::size_t j = 1; j < n; ++j) {
        const Vector2d p = panel.toPx(request.joints[j].position);
        cairo_new_sub_path(cr);
        cairo_arc(cr, p.x(), p.y(), 2.4, 0, 2 * std::numbers::pi);
    }
    setColour(cr, colour);
    cairo_fill_preserve(cr);
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_set_line_width(cr, 0.8);
    cairo_stroke(cr);
    if (n > 0) drawRootMark(cr, panel.toPx(request.joints[0].position));
}

// A cone of half angle `halfAngle` about `axis` from `apex`: its rim, then four generators in `generators` (their
// colour and opacity).
void drawCone(cairo_t* cr, const PanelMapping& panel, const Vector3d& apex, const Vector3d& axis, double halfAngle,
              double length, const std::pair<Rgb, double>& generators) {
    const auto [u, v] = perpendicular(axis);
    std::vector<Vector2d> rim;
    constexpr int kSides = 48;
    for (int k = 0; k < kSides; ++k) {
        const double phi = 2 * std::numbers::pi * k / kSides;
        rim.push_back(panel.toPx(apex + length * (std::cos(halfAngle) * axis +
                                                  std::sin(halfAngle) * (std::cos(phi) * u + std::sin(phi) * v))));
    }
    polyline(cr, rim, true);
    cairo_stroke(cr);
    setColour(cr, generators.first, generators.second);
    for (int k = 0; k < kSides; k += kSides / 4) line(cr, panel.toPx(apex), rim[static_cast<std::size_t>(k)]);
    cairo_stroke(cr);
}

// How much of a limit glyph about `axis` a view shows, in [0, 1]: 1 when the axis lies in the page, 0 when it
// points at the viewer. A cone seen end-on is a circle round its joint that says little about the limit and hides
// its neighbours (the shoulders in a side view, the hips and spine from above): it is drawn faint, its generators
// fading out (smoothly: a threshold would flip between two poses equal but for rounding).
double inPage(const PanelMapping& panel, const Vector3d& axis) {
    const double along = axis.normalized().dot(panel.axes.toViewer);
    return std::sqrt(std::max(0.0, 1.0 - along * along));
}

// A pyramid: the four edges where both projected angles are at their limits, and the rim joining them.
void drawPyramid(cairo_t* cr, const PanelMapping& panel, const Vector3d& apex, const Eigen::Matrix3d& basis,
                 double halfAngle1, double halfAngle2, double length) {
    const double t1 = std::tan(std::min(halfAngle1, 1.5)), t2 = std::tan(std::min(halfAngle2, 1.5)); // < 86°
    std::vector<Vector2d> rim;
    for (const auto& [s1, s2] : std::array<std::pair<double, double>, 4>{{{1, 1}, {1, -1}, {-1, -1}, {-1, 1}}}) {
        const Vector3d edge = (basis.col(0) + s1 * t1 * basis.col(1) + s2 * t2 * basis.col(2)).normalized();
        rim.push_back(panel.toPx(apex + length * edge));
    }
    polyline(cr, rim, true);
    cairo_stroke(cr);
    for (const Vector2d& corner : rim) line(cr, panel.toPx(apex), corner);
    cairo_stroke(cr);
}

// A hinge: the sector φ ∈ [lower, upper] about frame2's Z from its X (docs/format.md §4.5), and the axis itself.
void drawHingeArc(cairo_t* cr, const PanelMapping& panel, const figure::Transform& frame2, const figure::HingeRange& h,
                  double radius) {
    const Vector3d o = frame2.position, x = frame2.rotation.col(0), y = frame2.rotation.col(1);
    const Vector3d z = frame2.rotation.col(2);
    const double span = std::min(h.upperRad - h.lowerRad, 2 * std::numbers::pi);
    const int steps = std::max(2, static_cast<int>(std::ceil(span / (std::numbers::pi / 36))));
    std::vector<Vector2d> sector{panel.toPx(o)};
    for (int k = 0; k <= steps; ++k) {
        const double phi = h.lowerRad + span * k / steps;
        sector.push_back(panel.toPx(o + radius * (std::cos(phi) * x + std::sin(phi) * y)));
    }
    polyline(cr, sector, true);
    cairo_stroke(cr);
    const double dash[] = {3.0, 2.0};
    cairo_set_dash(cr, dash, 2, 0);
    line(cr, panel.toPx(o - 0.5 * radius * z), panel.toPx(o + 0.5 * radius * z));
    cairo_stroke(cr);
    cairo_set_dash(cr, nullptr, 0, 0);
}

void drawLimits(cairo_t* cr, const figure::Figure& figure, const PictureRequest& request, const PanelMapping& panel,
                double glyphM) {
    cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
    for (const figure::FigureConstraint& c : figure.constraints) {
        if (std::holds_alternative<std::monostate>(c.limit)) continue;
        const figure::Transform& body1 = request.bodies[static_cast<std::size_t>(c.body1)];
        const figure::Transform body2 = body2Frame(request, c);
        const figure::Transform frame2 = body2 * c.frameInBody2;
        const Rgb colour = constraintColour(c.type);
        Vector3d shaft = Vector3d::Zero();
        double shaftLength = glyphM * 1.15;
        // Faint where the view shows little of the glyph (see inPage); a hinge's arc lies across its axis.
        double shown = 1;
        cairo_set_line_width(cr, 0.9);
        if (const auto* cone = std::get_if<figure::ConeLimit>(&c.limit)) {
            const Vector3d axis = body2.rotation * cone->axisInBody2;
            shown = inPage(panel, axis);
            setColour(cr, colour, 0.15 + 0.65 * shown);
            drawCone(cr, panel, frame2.position, axis, cone->halfAngleRad, glyphM,
                     {colour, (0.15 + 0.65 * shown) * shown * shown}); // generators fade out end-on
            shaft = body1.rotation * cone->shaftInBody1;
        } else if (const auto* p = std::get_if<figure::PyramidLimit>(&c.limit)) {
            shown = inPage(panel, body2.rotation * p->basisInBody2.col(0));
            setColour(cr, colour, 0.15 + 0.65 * shown);
            drawPyramid(cr, panel, frame2.position, body2.rotation * p->basisInBody2, p->halfAngle1Rad,
                        p->halfAngle2Rad, glyphM);
            shaft = body1.rotation * p->shaftInBody1;
        } else if (const auto* h = std::get_if<figure::HingeRange>(&c.limit)) {
            shown = std::abs(frame2.rotation.col(2).dot(panel.axes.toViewer));
            setColour(cr, colour, 0.15 + 0.65 * shown);
            drawHingeArc(cr, panel, frame2, *h, 0.6 * glyphM);
            shaft = (body1 * c.frameInBody1).rotation.col(0); // body1's side of the angle φ
            shaftLength = 0.7 * glyphM;
        }
        // The shaft: where body1 points now, to read against the limit's outline.
        setColour(cr, scaled(colour, 0.7), 0.3 + 0.6 * shown);
        cairo_set_line_width(cr, 1.6);
        line(cr, panel.toPx(frame2.position), panel.toPx(frame2.position + shaftLength * shaft));
        cairo_stroke(cr);
    }
}

void zigzag(cairo_t* cr, const Vector2d& a, const Vector2d& b) {
    const Vector2d d = b - a;
    const double length = d.norm();
    if (length < 1) return;
    const Vector2d n = Vector2d(-d.y(), d.x()) / length * 3.5;
    constexpr int kTeeth = 10;
    moveTo(cr, a);
    for (int k = 1; k < kTeeth; ++k) lineTo(cr, a + d * (double(k) / kTeeth) + (k % 2 ? n : Vector2d(-n)));
    lineTo(cr, b);
}

void drawAnchors(cairo_t* cr, const figure::Figure& figure, const PictureRequest& request, const PanelMapping& panel) {
    // Nearest anchors last, like the bodies.
    std::vector<std::pair<double, std::size_t>> order;
    for (std::size_t i = 0; i < figure.constraints.size(); ++i) {
        const figure::FigureConstraint& c = figure.constraints[i];
        order.emplace_back(panel.depth((request.bodies[static_cast<std::size_t>(c.body1)] * c.frameInBody1).position),
                           i);
    }
    std::stable_sort(order.begin(), order.end());
    for (const auto& [depth, i] : order) {
        const figure::FigureConstraint& c = figure.constraints[i];
        const Vector2d anchor1 =
            panel.toPx((request.bodies[static_cast<std::size_t>(c.body1)] * c.frameInBody1).position);
        if (c.type == figure::JointType::Spring) {
            const Vector2d anchor2 = panel.toPx((body2Frame(request, c) * c.frameInBody2).position);
            setColour(cr, constraintColour(c.type));
            cairo_set_line_width(cr, 1.3);
            zigzag(cr, anchor1, anchor2);
            cairo_stroke(cr);
            drawAnchorMark(cr, c.type, anchor2);
        }
        drawAnchorMark(cr, c.type, anchor1);
    }
}

void drawMasses(cairo_t* cr, const figure::Figure& figure, const PictureRequest& request, const PanelMapping& panel,
                const PanelStyle& style) {
    for (std::size_t i = 0; i < figure.bodies.size(); ++i) {
        const Vector2d p = panel.toPx(request.bodies[i].position);
        const double radius = style.massPxPerSqrtKg * std::sqrt(std::max(0.0, figure.bodies[i].massKg));
        cairo_new_sub_path(cr);
        cairo_arc(cr, p.x(), p.y(), radius, 0, 2 * std::numbers::pi);
        cairo_set_source_rgba(cr, 0.1, 0.1, 0.1, 0.22);
        cairo_fill_preserve(cr);
        cairo_set_source_rgba(cr, 0.1, 0.1, 0.1, 0.7);
        cairo_set_line_width(cr, 0.8);
        cairo_stroke(cr);
    }
    if (!style.massLabels) return;
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr, 10.5);
    for (std::size_t i = 0; i < figure.bodies.size(); ++i) {
        const Vector2d p = panel.toPx(request.bodies[i].position);
        const double radius = style.massPxPerSqrtKg * std::sqrt(std::max(0.0, figure.bodies[i].massKg));
        char text[32];
        std::snprintf(text, sizeof text, "%.1f kg", figure.bodies[i].massKg);
        cairo_move_to(cr, p.x() + radius * 0.7 + 2, p.y() - radius * 0.7 - 2);
        cairo_text_path(cr, text);
        cairo_set_source_rgba(cr, 1, 1, 1, 0.85); // a halo keeps the label readable over any body
        cairo_set_line_width(cr, 3.0);
        cairo_stroke_preserve(cr);
        cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
        cairo_fill(cr);
    }
}

void drawGround(cairo_t* cr, const PictureRequest& request, const PanelMapping& panel) {
    if (!groundInView(request, panel)) return;
    const double y = panel.toPx(Vector3d(0, 0, *request.groundZ)).y();
    cairo_rectangle(cr, panel.x, y, panel.width, panel.y + panel.height - y);
    cairo_set_source_rgb(cr, 0.90, 0.87, 0.80);
    cairo_fill(cr);
    cairo_move_to(cr, panel.x, y);
    cairo_line_to(cr, panel.x + panel.width, y);
    cairo_set_source_rgb(cr, 0.45, 0.40, 0.32);
    cairo_set_line_width(cr, 1.2);
    cairo_stroke(cr);
}

// Model axes X, Y, Z (red, green, blue) in the panel's corner; an axis toward or away from the viewer is a ⊙
// / ⊗.
void drawAxesGizmo(cairo_t* cr, const PanelMapping& panel) {
    const Vector2d o(panel.x + 40, panel.y + panel.height - 26);
    const std::array<Rgb, 3> colours{{{0.80, 0.15, 0.15}, {0.15, 0.60, 0.15}, {0.15, 0.30, 0.85}}};
    const char* names[3] = {"X", "Y", "Z"};
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_BOLD);
    cairo_set_font_size(cr, 10);
    cairo_set_line_width(cr, 1.5);
    for (int a = 0; a < 3; ++a) {
        const Vector3d axis = Vector3d::Unit(a);
        const Vector2d d(axis.dot(panel.axes.right), -axis.dot(panel.axes.up));
        setColour(cr, colours[static_cast<std::size_t>(a)]);
        Vector2d label;
        if (d.norm() < 0.1) {
            cairo_new_sub_path(cr);
            cairo_arc(cr, o.x(), o.y(), 4.5, 0, 2 * std::numbers::pi);
            cairo_stroke(cr);
            if (axis.dot(panel.axes.toViewer) > 0) {
                cairo_arc(cr, o.x(), o.y(), 1.5, 0, 2 * std::numbers::pi);
                cairo_fill(cr);
            } else {
                line(cr, o + Vector2d(-3, -3), o + Vector2d(3, 3));
                line(cr, o + Vector2d(-3, 3), o + Vector2d(3, -3));
                cairo_stroke(cr);
            }
            label = o + Vector2d(-14, -4);
        } else {
            const Vector2d tip = o + 18 * d, side(-d.y(), d.x());
            line(cr, o, tip);
            cairo_stroke(cr);
            moveTo(cr, tip + 4 * d);
            lineTo(cr, tip + 3 * side);
            lineTo(cr, tip - 3 * side);
            cairo_close_path(cr);
            cairo_fill(cr);
            label = tip + 10 * d + Vector2d(-3.5, 3.5);
        }
        cairo_move_to(cr, label.x(), label.y());
        cairo_show_text(cr, names[a]);
    }
}

} // namespace

bool groundInView(const PictureRequest& request, const PanelMapping& panel) {
    if (!request.groundZ || std::abs(panel.axes.up.z()) < 0.99) return false;
    const double y = panel.toPx(Vector3d(0, 0, *request.groundZ)).y();
    return y >= panel.y && y <= panel.y + panel.height;
}

ViewAxes viewAxes(View view) {
    switch (view) {
    case View::Front: return {Vector3d::UnitY(), Vector3d::UnitZ(), Vector3d::UnitX()};
    case View::Side: return {Vector3d::UnitX(), Vector3d::UnitZ(), -Vector3d::UnitY()};
    case View::Top: return {-Vector3d::UnitY(), Vector3d::UnitX(), Vector3d::UnitZ()};
    }
    return {};
}

std::pair<Vector2d, Vector2d> viewBounds(const figure::Figure& figure, const PictureRequest& request, View view) {
    const ViewAxes axes = viewAxes(view);
    Vector2d lo = Vector2d::Constant(1e30), hi = Vector2d::Constant(-1e30);
    auto add = [&](const Vector3d& p) {
        const Vector2d q(p.dot(axes.right), p.dot(axes.up));
        lo = lo.cwiseMin(q);
        hi = hi.cwiseMax(q);
    };
    for (std::size_t i = 0; i < figure.bodies.size() && i < request.bodies.size(); ++i)
        for (const Vector3d& v : figure.bodies[i].shape.vertices) add(request.bodies[i].apply(v));
    for (std::size_t j = 1; j < request.joints.size(); ++j) add(request.joints[j].position); // not the root
    for (const figure::FigureConstraint& c : figure.constraints) {
        add((request.bodies[static_cast<std::size_t>(c.body1)] * c.frameInBody1).position);
        add((body2Frame(request, c) * c.frameInBody2).position);
    }
    if (request.reference) {
        PictureRequest reference = request;
        reference.bodies = request.reference->bodies;
        reference.joints = request.reference->joints;
        reference.reference.reset();
        const auto [rlo, rhi] = viewBounds(figure, reference, view);
        if (rlo.x() <= rhi.x()) {
            lo = lo.cwiseMin(rlo);
            hi = hi.cwiseMax(rhi);
        }
    }
    if (lo.x() > hi.x()) return {Vector2d::Zero(), Vector2d::Zero()};
    return {lo, hi};
}

void drawPanel(cairo_t* cr, const figure::Figure& figure, const PictureRequest& request, const PanelMapping& panel,
               const PanelStyle& style) {
    cairo_save(cr);
    cairo_rectangle(cr, panel.x, panel.y, panel.width, panel.height);
    cairo_clip(cr);
    drawGround(cr, request, panel);
    std::optional<Rgb> tint; // with a reference pose: each pose in its colour, the reference beneath
    if (request.reference) {
        tint = ownPoseColour();
        PictureRequest reference = request;
        reference.bodies = request.reference->bodies;
        reference.joints = request.reference->joints;
        if (request.show.bodies) drawBodies(cr, figure, reference, panel, referencePoseColour(), 0.45);
        if (request.show.skeleton) drawSkeleton(cr, figure, reference, panel, scaled(referencePoseColour(), 0.6));
    }
    if (request.show.bodies) drawBodies(cr, figure, request, panel, tint, tint ? 0.55 : 1.0);
    if (request.show.limits) drawLimits(cr, figure, request, panel, style.glyphM);
    if (request.show.skeleton) drawSkeleton(cr, figure, request, panel, tint ? scaled(*tint, 0.6) : skeletonColour());
    if (request.show.mass) drawMasses(cr, figure, request, panel, style);
    if (request.show.joints) drawAnchors(cr, figure, request, panel);
    if (request.show.names) drawNames(cr, figure, request, panel);
    drawAxesGizmo(cr, panel);
    cairo_restore(cr);
}

Rgb constraintColour(figure::JointType type) {
    switch (type) {
    case figure::JointType::Fixed: return {0.35, 0.35, 0.35};
    case figure::JointType::BallAndSocket: return {0.84, 0.15, 0.16};
    case figure::JointType::Universal: return {0.55, 0.30, 0.75};
    case figure::JointType::Hinge: return {0.10, 0.42, 0.80};
    case figure::JointType::Slider: return {0.10, 0.60, 0.25};
    case figure::JointType::Spring: return {0.95, 0.50, 0.05};
    }
    return {};
}

void drawAnchorMark(cairo_t* cr, figure::JointType type, const Vector2d& at) {
    const double r = kMarkPx, x = at.x(), y = at.y();
    cairo_new_path(cr);
    switch (type) {
    case figure::JointType::BallAndSocket:
    case figure::JointType::Spring: cairo_arc(cr, x, y, r, 0, 2 * std::numbers::pi); break;
    case figure::JointType::Universal:
        cairo_move_to(cr, x, y - r * 1.25);
        cairo_line_to(cr, x + r * 1.25, y);
        cairo_line_to(cr, x, y + r * 1.25);
        cairo_line_to(cr, x - r * 1.25, y);
        cairo_close_path(cr);
        break;
    case figure::JointType::Hinge: cairo_rectangle(cr, x - r, y - r, 2 * r, 2 * r); break;
    case figure::JointType::Slider:
        cairo_move_to(cr, x, y - r * 1.2);
        cairo_line_to(cr, x + r * 1.1, y + r * 0.8);
        cairo_line_to(cr, x - r * 1.1, y + r * 0.8);
        cairo_close_path(cr);
        break;
    case figure::JointType::Fixed:
        cairo_move_to(cr, x - r, y - r * 0.35);
        for (const auto& [px, py] : std::array<std::pair<double, double>, 11>{{{-0.35, -0.35},
                                                                               {-0.35, -1},
                                                                               {0.35, -1},
                                                                               {0.35, -0.35},
                                                                               {1, -0.35},
                                                                               {1, 0.35},
                                                                               {0.35, 0.35},
                                                                               {0.35, 1},
                                                                               {-0.35, 1},
                                                                               {-0.35, 0.35},
                                                                               {-1, 0.35}}})
            cairo_line_to(cr, x + r * px, y + r * py);
        cairo_close_path(cr);
        break;
    }
    setColour(cr, constraintColour(type));
    cairo_fill_preserve(cr);
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_set_line_width(cr, 1.0);
    cairo_stroke(cr);
}

Rgb bodyColour(std::size_t index) {
    // Soft, distinct hues: neighbouring bodies (decl order follows the limbs) differ, anchors and limits
    // stand out.
    static constexpr std::array<Rgb, 8> kPalette{{{0.68, 0.80, 0.93},
                                                  {0.96, 0.80, 0.62},
                                                  {0.72, 0.88, 0.70},
                                                  {0.94, 0.72, 0.74},
                                                  {0.80, 0.75, 0.91},
                                                  {0.93, 0.88, 0.62},
                                                  {0.66, 0.88, 0.88},
                                                  {0.88, 0.78, 0.70}}};
    return kPalette[index % kPalette.size()];
}

void drawRootMark(cairo_t* cr, const Vector2d& at) {
    cairo_new_path(cr);
    cairo_arc(cr, at.x(), at.y(), 4.0, 0, 2 * std::numbers::pi);
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_fill_preserve(cr);
    setColour(cr, skeletonColour());
    cairo_set_line_width(cr, 1.5);
    cairo_stroke(cr);
}

Rgb skeletonColour() { return {0.12, 0.12, 0.18}; }

Rgb referencePoseColour() { return {0.20, 0.45, 0.85}; }
Rgb ownPoseColour() { return {0.95, 0.55, 0.10}; }

} // namespace afb::cli
