// Names in a figure picture (afb draw --show names): bodies at their centres of mass, constraints at their
// anchors, each set where it overlaps no name placed before it.
#include <algorithm>
#include <array>
#include <cmath>
#include <optional>

#include "PictureView.h"

namespace afb::cli {
namespace {

using Eigen::Vector2d;

// A name's box on the page, pixels.
struct Box {
    double x0, y0, x1, y1;
    bool overlaps(const Box& o) const { return x0 < o.x1 && o.x0 < x1 && y0 < o.y1 && o.y0 < y1; }
};

struct Label {
    std::string text;
    Vector2d at; // the point it names, pixels
    Rgb colour;
    bool bold;
};

// Where a name goes: the first of a few places round its point, nearest first, whose box overlaps no box in
// `placed` and stays in the panel; the first place when none is free.
Box place(cairo_t* cr, const Label& label, const PanelMapping& panel, const std::vector<Box>& placed) {
    cairo_text_extents_t e;
    cairo_text_extents(cr, label.text.c_str(), &e);
    const double w = e.x_advance + 4, h = 13;
    // Directions round the point: above, right, below, left, then the corners.
    const std::array<Vector2d, 8> directions{{{0, -1}, {1, 0}, {0, 1}, {-1, 0}, {1, -1}, {-1, -1}, {1, 1}, {-1, 1}}};
    std::optional<Box> first;
    for (double gap : {5.0, 18.0, 34.0}) {
        for (const Vector2d& d : directions) {
            // The box's centre, `gap` pixels beyond the box's half extent in the direction.
            const Vector2d centre = label.at + Vector2d(d.x() * (w / 2 + gap), d.y() * (h / 2 + gap));
            const Box box{centre.x() - w / 2, centre.y() - h / 2, centre.x() + w / 2, centre.y() + h / 2};
            if (!first) first = box;
            bool free = box.x0 >= panel.x && box.x1 <= panel.x + panel.width && box.y0 >= panel.y &&
                        box.y1 <= panel.y + panel.height;
            for (const Box& b : placed) free = free && !b.overlaps(box);
            if (free) return box;
        }
    }
    return *first;
}

void drawLabel(cairo_t* cr, const Label& label, const Box& box) {
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                           label.bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
    const Vector2d centre(0.5 * (box.x0 + box.x1), 0.5 * (box.y0 + box.y1));
    // A hair line from the point to a name set beside it.
    if ((centre - label.at).norm() > 12) {
        cairo_set_source_rgba(cr, label.colour.r, label.colour.g, label.colour.b, 0.6);
        cairo_set_line_width(cr, 0.7);
        const double nearX = std::clamp(label.at.x(), box.x0, box.x1), nearY = std::clamp(label.at.y(), box.y0, box.y1);
        cairo_move_to(cr, label.at.x(), label.at.y());
        cairo_line_to(cr, nearX, nearY);
        cairo_stroke(cr);
    }
    cairo_move_to(cr, box.x0 + 2, box.y1 - 3);
    cairo_text_path(cr, label.text.c_str());
    cairo_set_source_rgba(cr, 1, 1, 1, 0.9); // a halo keeps the name readable over any body or line
    cairo_set_line_width(cr, 3.0);
    cairo_stroke_preserve(cr);
    cairo_set_source_rgb(cr, label.colour.r, label.colour.g, label.colour.b);
    cairo_fill(cr);
}

} // namespace

void drawNames(cairo_t* cr, const figure::Figure& figure, const PictureRequest& request, const PanelMapping& panel) {
    std::vector<Label> labels;
    // Bodies first: their names are the ones a reader looks for; constraints fit round them.
    for (std::size_t i = 0; i < figure.bodies.size() && i < request.bodies.size(); ++i)
        labels.push_back({figure.bodies[i].name, panel.toPx(request.bodies[i].position), skeletonColour(), true});
    for (const figure::FigureConstraint& c : figure.constraints) {
        const figure::Transform& body1 = request.bodies[static_cast<std::size_t>(c.body1)];
        const Rgb colour = constraintColour(c.type);
        labels.push_back({c.name,
                          panel.toPx((body1 * c.frameInBody1).position),
                          {colour.r * 0.75, colour.g * 0.75, colour.b * 0.75},
                          false});
    }
    cairo_save(cr);
    cairo_set_font_size(cr, 10);
    std::vector<Box> placed;
    for (const Label& label : labels) {
        cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                               label.bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
        placed.push_back(place(cr, label, panel, placed));
        drawLabel(cr, label, placed.back());
    }
    cairo_restore(cr);
}

} // namespace afb::cli
