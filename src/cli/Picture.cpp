// Figure pictures: page layout (title, one panel per view at one common scale, legend, scale bar) and the
// cairo surfaces that write PNG and SVG.
#include "Picture.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <numbers>

#include <cairo-svg.h>

#include "PictureView.h"

namespace afb::cli {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;

// Page layout, pixels (PNG) or points (SVG).
constexpr double kMargin = 20, kTitleBand = 60, kLabelBand = 22, kPanelPad = 16, kPanelGap = 14;
constexpr double kMaxFigureHeight = 640;  // the tallest view's figure, without padding
constexpr double kMaxFiguresWidth = 1400; // all views' figures side by side, without padding
constexpr double kMinPanelWidth = 200, kMinPageWidth = 960;
constexpr double kLegendRow = 24, kLegendFont = 12, kSwatchWidth = 26;
constexpr double kMaxMassRadius = 11; // the heaviest body's disc

using CairoPtr = std::unique_ptr<cairo_t, decltype(&cairo_destroy)>;
using SurfacePtr = std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)>;

const char* viewLabel(View view) {
    switch (view) {
    case View::Front: return "front (from +X)";
    case View::Side: return "side (from \u2212Y)";
    case View::Top: return "top (from +Z)";
    }
    return "";
}

const char* typeLabel(figure::JointType type) {
    switch (type) {
    case figure::JointType::Fixed: return "fixed";
    case figure::JointType::BallAndSocket: return "ball and socket";
    case figure::JointType::Universal: return "universal";
    case figure::JointType::Hinge: return "hinge";
    case figure::JointType::Slider: return "slider";
    case figure::JointType::Spring: return "spring";
    }
    return "";
}

// The largest 1, 2 or 5 × 10ⁿ metres no longer than `maxM`.
double niceLength(double maxM) {
    const double decade = std::pow(10.0, std::floor(std::log10(maxM)));
    for (double k : {5.0, 2.0, 1.0})
        if (k * decade <= maxM) return k * decade;
    return decade;
}

std::string format(const char* fmt, double value) {
    char buf[64];
    std::snprintf(buf, sizeof buf, fmt, value);
    return buf;
}

void setFont(cairo_t* cr, double size, bool bold = false) {
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                           bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr, size);
}
double textWidth(cairo_t* cr, const std::string& text) {
    cairo_text_extents_t e;
    cairo_text_extents(cr, text.c_str(), &e);
    return e.x_advance;
}
void text(cairo_t* cr, double x, double y, const std::string& s) {
    cairo_move_to(cr, x, y);
    cairo_show_text(cr, s.c_str());
}

// A legend entry: a swatch drawn in a kSwatchWidth-wide box whose left middle is the given point, and a text.
struct LegendItem {
    std::function<void(cairo_t*, Vector2d)> swatch;
    std::string label;
};

struct Layout {
    double width = 0, height = 0;
    double pxPerM = 1;
    std::vector<PanelMapping> panels;
    double legendTop = 0;
    std::vector<Vector2d> legendAt; // per legend item: the swatch's left middle
    double scaleBarM = 0;
    Vector2d scaleBarAt = Vector2d::Zero(); // left end of the bar
};

// Bounds of the load pose: limit glyphs and mass discs are sized from it, so pictures of one figure at
// different times share their glyphs.
double loadPoseDiagonal(const figure::Figure& figure) {
    Vector3d lo = Vector3d::Constant(1e30), hi = Vector3d::Constant(-1e30);
    for (const figure::FigureBody& b : figure.bodies)
        for (const Vector3d& v : b.shape.vertices) {
            lo = lo.cwiseMin(b.loadPose.apply(v));
            hi = hi.cwiseMax(b.loadPose.apply(v));
        }
    return lo.x() > hi.x() ? 1.0 : (hi - lo).norm();
}

std::vector<LegendItem> legendItems(const figure::Figure& figure, const PictureRequest& request,
                                    const PanelStyle& style, bool groundShown) {
    std::vector<LegendItem> items;
    const PictureLayers& show = request.show;
    if (request.reference) {
        for (const auto& pose : {std::pair{referencePoseColour(), request.reference->label},
                                 std::pair{ownPoseColour(), request.reference->ownLabel}})
            items.push_back({[colour = pose.first](cairo_t* cr, Vector2d at) {
                                 cairo_rectangle(cr, at.x() + 1, at.y() - 6, 24, 12);
                                 cairo_set_source_rgba(cr, colour.r, colour.g, colour.b, 0.6);
                                 cairo_fill_preserve(cr);
                                 cairo_set_source_rgb(cr, colour.r * 0.5, colour.g * 0.5, colour.b * 0.5);
                                 cairo_set_line_width(cr, 1);
                                 cairo_stroke(cr);
                             },
                             pose.second});
    } else if (show.bodies)
        items.push_back({[](cairo_t* cr, Vector2d at) {
                             for (int k = 0; k < 3; ++k) {
                                 const Rgb c = bodyColour(static_cast<std::size_t>(k));
                                 cairo_rectangle(cr, at.x() + 1 + 8 * k, at.y() - 6, 8, 12);
                                 cairo_set_source_rgb(cr, c.r, c.g, c.b);
                                 cairo_fill_preserve(cr);
                                 cairo_set_source_rgb(cr, c.r * 0.5, c.g * 0.5, c.b * 0.5);
                                 cairo_set_line_width(cr, 1);
                                 cairo_stroke(cr);
                             }
                         },
                         std::to_string(figure.bodies.size()) + " bodies"});
    if (show.skeleton)
        items.push_back({[](cairo_t* cr, Vector2d at) {
                             const Rgb c = skeletonColour();
                             cairo_set_source_rgb(cr, c.r, c.g, c.b);
                             cairo_set_line_width(cr, 1.6);
                             cairo_move_to(cr, at.x() + 3, at.y() + 4);
                             cairo_line_to(cr, at.x() + 23, at.y() - 4);
                             cairo_stroke(cr);
                             for (double x : {3.0, 23.0}) {
                                 cairo_arc(cr, at.x() + x, at.y() + (x < 10 ? 4 : -4), 2.4, 0, 2 * std::numbers::pi);
                                 cairo_fill(cr);
                             }
                         },
                         "md5 skeleton (" + std::to_string(figure.skeleton.jointCount()) + " joints)"});
    if (show.skeleton)
        items.push_back(
            {[](cairo_t* cr, Vector2d at) { drawRootMark(cr, at + Vector2d(13, 0)); }, "root joint (entity origin)"});
    if (show.joints) {
        for (int t = 0; t <= static_cast<int>(figure::JointType::Spring); ++t) {
            const auto type = static_cast<figure::JointType>(t);
            const auto n = std::count_if(figure.constraints.begin(), figure.constraints.end(),
                                         [&](const figure::FigureConstraint& c) { return c.type == type; });
            if (n == 0) continue;
            items.push_back({[type](cairo_t* cr, Vector2d at) { drawAnchorMark(cr, type, at + Vector2d(13, 0)); },
                             std::string(typeLabel(type)) + " (" + std::to_string(n) + ")"});
        }
    }
    const bool anyLimit = std::any_of(figure.constraints.begin(), figure.constraints.end(),
                                      [](const figure::FigureConstraint& c) { return c.limit.index() != 0; });
    if (show.limits && anyLimit)
        items.push_back({[](cairo_t* cr, Vector2d at) {
                             cairo_set_source_rgb(cr, 0.4, 0.4, 0.4);
                             cairo_set_line_width(cr, 1.1);
                             cairo_move_to(cr, at.x() + 2, at.y());
                             cairo_line_to(cr, at.x() + 22, at.y() - 7);
                             cairo_move_to(cr, at.x() + 2, at.y());
                             cairo_line_to(cr, at.x() + 22, at.y() + 7);
                             cairo_stroke(cr);
                             cairo_save(cr);
                             cairo_translate(cr, at.x() + 22, at.y());
                             cairo_scale(cr, 0.35, 1);
                             cairo_arc(cr, 0, 0, 7, 0, 2 * std::numbers::pi);
                             cairo_restore(cr);
                             cairo_stroke(cr);
                             cairo_set_line_width(cr, 2);
                             cairo_move_to(cr, at.x() + 2, at.y());
                             cairo_line_to(cr, at.x() + 18, at.y() + 2);
                             cairo_stroke(cr);
                         },
                         "limits: cone, pyramid, hinge arc (thick: body1's shaft; faint: seen end-on)"});
    if (show.mass) {
        double heaviest = 0;
        for (const figure::FigureBody& b : figure.bodies) heaviest = std::max(heaviest, b.massKg);
        const double reference = heaviest > 0 ? niceLength(heaviest) : 1.0;
        const double radius = style.massPxPerSqrtKg * std::sqrt(reference);
        items.push_back({[radius](cairo_t* cr, Vector2d at) {
                             cairo_arc(cr, at.x() + 13, at.y(), radius, 0, 2 * std::numbers::pi);
                             cairo_set_source_rgba(cr, 0.1, 0.1, 0.1, 0.22);
                             cairo_fill_preserve(cr);
                             cairo_set_source_rgba(cr, 0.1, 0.1, 0.1, 0.7);
                             cairo_set_line_width(cr, 0.8);
                             cairo_stroke(cr);
                         },
                         "centre of mass, area \u221d mass (this: " + format("%g", reference) + " kg)"});
    }
    if (groundShown)
        items.push_back({[](cairo_t* cr, Vector2d at) {
                             cairo_rectangle(cr, at.x() + 1, at.y() - 1, 24, 7);
                             cairo_set_source_rgb(cr, 0.90, 0.87, 0.80);
                             cairo_fill(cr);
                             cairo_move_to(cr, at.x() + 1, at.y() - 1);
                             cairo_line_to(cr, at.x() + 25, at.y() - 1);
                             cairo_set_source_rgb(cr, 0.45, 0.40, 0.32);
                             cairo_set_line_width(cr, 1.2);
                             cairo_stroke(cr);
                         },
                         "ground"});
    return items;
}

// The panels, side by side at one scale, centred on the page.
Layout layOutPanels(const figure::Figure& figure, const PictureRequest& request, double glyphM) {
    Layout layout;
    std::vector<std::pair<Vector2d, Vector2d>> bounds;
    double tallest = 0, widths = 0;
    for (View v : request.views) {
        auto [lo, hi] = viewBounds(figure, request, v);
        lo -= Vector2d::Constant(glyphM); // room for the limit glyphs at the outermost anchors
        hi += Vector2d::Constant(glyphM);
        bounds.emplace_back(lo, hi);
        tallest = std::max(tallest, hi.y() - lo.y());
        widths += hi.x() - lo.x();
    }
    layout.pxPerM = std::min(kMaxFigureHeight / std::max(tallest, 0.05), kMaxFiguresWidth / std::max(widths, 0.05));

    const double panelHeight = tallest * layout.pxPerM + 2 * kPanelPad;
    double x = kMargin;
    const double top = kMargin + kTitleBand + kLabelBand;
    for (std::size_t i = 0; i < request.views.size(); ++i) {
        const auto& [lo, hi] = bounds[i];
        PanelMapping p;
        p.axes = viewAxes(request.views[i]);
        p.pxPerM = layout.pxPerM;
        p.x = x;
        p.y = top;
        p.width = std::max(kMinPanelWidth, (hi.x() - lo.x()) * layout.pxPerM + 2 * kPanelPad);
        p.height = panelHeight;
        const Vector2d centre = 0.5 * (lo + hi);
        p.originPx = {p.x + 0.5 * p.width - centre.x() * p.pxPerM, p.y + 0.5 * p.height + centre.y() * p.pxPerM};
        layout.panels.push_back(p);
        x += p.width + kPanelGap;
    }
    layout.width = std::max(kMinPageWidth, x - kPanelGap + kMargin);
    const double panelsWidth = x - kPanelGap - kMargin; // centre the panels on a wider page
    const double shift = 0.5 * (layout.width - 2 * kMargin - panelsWidth);
    for (PanelMapping& p : layout.panels) {
        p.x += shift;
        p.originPx.x() += shift;
    }

    layout.legendTop = top + panelHeight + 18;
    return layout;
}

// The legend flows in rows below the panels; the scale bar sits at the right of its first row.
void layOutLegend(cairo_t* measure, Layout& layout, const std::vector<LegendItem>& legend) {
    layout.scaleBarM = niceLength(150.0 / layout.pxPerM);
    const double scaleBlock = layout.scaleBarM * layout.pxPerM + 60;
    setFont(measure, kLegendFont);
    double lx = kMargin, ly = layout.legendTop + kLegendRow / 2;
    const double right = layout.width - kMargin - scaleBlock;
    for (const LegendItem& item : legend) {
        const double w = kSwatchWidth + 6 + textWidth(measure, item.label) + 18;
        if (lx + w > right && lx > kMargin) {
            lx = kMargin;
            ly += kLegendRow;
        }
        layout.legendAt.emplace_back(lx, ly);
        lx += w;
    }
    layout.scaleBarAt = {layout.width - kMargin - layout.scaleBarM * layout.pxPerM - 10,
                         layout.legendTop + kLegendRow / 2 + 4};
    layout.height = ly + kLegendRow / 2 + kMargin;
}

void drawScaleBar(cairo_t* cr, const Layout& layout) {
    const double length = layout.scaleBarM * layout.pxPerM, x = layout.scaleBarAt.x(), y = layout.scaleBarAt.y();
    constexpr int kSegments = 4;
    for (int k = 0; k < kSegments; ++k) {
        cairo_rectangle(cr, x + length * k / kSegments, y - 3, length / kSegments, 6);
        k % 2 ? cairo_set_source_rgb(cr, 1, 1, 1) : cairo_set_source_rgb(cr, 0.15, 0.15, 0.15);
        cairo_fill(cr);
    }
    cairo_rectangle(cr, x, y - 3, length, 6);
    cairo_set_source_rgb(cr, 0.15, 0.15, 0.15);
    cairo_set_line_width(cr, 1);
    cairo_stroke(cr);
    setFont(cr, 11);
    text(cr, x - 3, y - 7, "0");
    const std::string label = format("%g m", layout.scaleBarM);
    text(cr, x + length - textWidth(cr, label) / 2, y - 7, label);
}

void drawPage(cairo_t* cr, const figure::Figure& figure, const PictureRequest& request, const Layout& layout,
              const PanelStyle& style, const std::vector<LegendItem>& legend) {
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_paint(cr);

    cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
    setFont(cr, 21, true);
    text(cr, kMargin, kMargin + 20, request.title);
    setFont(cr, 12.5);
    cairo_set_source_rgb(cr, 0.35, 0.35, 0.35);
    std::string facts = request.subtitle.empty() ? "" : request.subtitle + "  \u00b7  ";
    facts += "figure " + figure.name + ", " + std::to_string(figure.bodies.size()) + " bodies, " +
             std::to_string(figure.constraints.size()) + " constraints, " + format("%.1f kg", figure.totalMassKg);
    text(cr, kMargin, kMargin + 42, facts);

    for (std::size_t i = 0; i < layout.panels.size(); ++i) {
        const PanelMapping& p = layout.panels[i];
        cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
        setFont(cr, 13, true);
        text(cr, p.x + 2, p.y - 7, viewLabel(request.views[i]));
        cairo_rectangle(cr, p.x, p.y, p.width, p.height);
        cairo_set_source_rgb(cr, 0.975, 0.975, 0.97);
        cairo_fill_preserve(cr);
        cairo_set_source_rgb(cr, 0.82, 0.82, 0.8);
        cairo_set_line_width(cr, 1);
        cairo_stroke(cr);
        PanelStyle panelStyle = style;
        panelStyle.massLabels = style.massLabels && i == 0;
        drawPanel(cr, figure, request, p, panelStyle);
    }

    for (std::size_t i = 0; i < legend.size(); ++i) {
        cairo_save(cr);
        cairo_new_path(cr);
        legend[i].swatch(cr, layout.legendAt[i]);
        cairo_restore(cr);
        cairo_set_source_rgb(cr, 0.15, 0.15, 0.15);
        setFont(cr, kLegendFont);
        text(cr, layout.legendAt[i].x() + kSwatchWidth + 6, layout.legendAt[i].y() + 4, legend[i].label);
    }
    drawScaleBar(cr, layout);
}

} // namespace

const char* viewName(View view) {
    switch (view) {
    case View::Front: return "front";
    case View::Side: return "side";
    case View::Top: return "top";
    }
    return "";
}

std::optional<std::string> drawPicture(const figure::Figure& figure, const PictureRequest& request,
                                       const std::filesystem::path& out) {
    const std::string extension = out.extension().string();
    if (extension != ".png" && extension != ".svg") return out.string() + ": the picture must be a .png or .svg file";
    if (request.views.empty()) return std::string("no view to draw");
    if (request.bodies.size() != figure.bodies.size()) return std::string("one body transform per body expected");

    PanelStyle style;
    // Limit glyphs short enough that the glyphs of neighbouring joints (shoulders, hips) seldom cross.
    style.glyphM = std::clamp(0.045 * loadPoseDiagonal(figure), 0.02, 0.2);
    double heaviest = 0;
    for (const figure::FigureBody& b : figure.bodies) heaviest = std::max(heaviest, b.massKg);
    style.massPxPerSqrtKg = heaviest > 0 ? kMaxMassRadius / std::sqrt(heaviest) : 0;
    style.massLabels = true;
    Layout layout = layOutPanels(figure, request, style.glyphM);
    const bool groundShown = std::any_of(layout.panels.begin(), layout.panels.end(),
                                         [&](const PanelMapping& p) { return groundInView(request, p); });
    const std::vector<LegendItem> legend = legendItems(figure, request, style, groundShown);
    SurfacePtr scratch(cairo_image_surface_create(CAIRO_FORMAT_RGB24, 1, 1), cairo_surface_destroy);
    CairoPtr measure(cairo_create(scratch.get()), cairo_destroy);
    layOutLegend(measure.get(), layout, legend);
    const int width = static_cast<int>(std::ceil(layout.width)), height = static_cast<int>(std::ceil(layout.height));

    const bool png = extension == ".png";
    SurfacePtr surface(png ? cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height)
                           : cairo_svg_surface_create(out.c_str(), width, height),
                       cairo_surface_destroy);
    {
        CairoPtr cr(cairo_create(surface.get()), cairo_destroy);
        drawPage(cr.get(), figure, request, layout, style, legend);
        if (cairo_status(cr.get()) != CAIRO_STATUS_SUCCESS)
            return out.string() + ": " + cairo_status_to_string(cairo_status(cr.get()));
    }
    cairo_status_t status = CAIRO_STATUS_SUCCESS;
    if (png) status = cairo_surface_write_to_png(surface.get(), out.c_str());
    cairo_surface_finish(surface.get());
    if (status == CAIRO_STATUS_SUCCESS) status = cairo_surface_status(surface.get());
    if (status != CAIRO_STATUS_SUCCESS) return out.string() + ": " + cairo_status_to_string(status);
    return std::nullopt;
}

} // namespace afb::cli
