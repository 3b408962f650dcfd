#pragma once
// One panel of a figure picture (Picture.h): the orthographic projection of a view and the figure's layers
// drawn into it with cairo. The page layout, legend and scale bar are Picture.cpp's.
#include <cairo.h>

#include "Picture.h"

namespace afb::cli {

/// An RGB colour, each channel in [0, 1].
struct Rgb {
    double r = 0, g = 0, b = 0;
};

/// The camera of a view: model-space unit directions of the page's right and up, and toward the viewer.
struct ViewAxes {
    Eigen::Vector3d right, up, toViewer;
};
ViewAxes viewAxes(View view);

/// Model space (metres) to page pixels for one panel; page y grows downward.
struct PanelMapping {
    ViewAxes axes;
    double pxPerM = 1;
    Eigen::Vector2d originPx = Eigen::Vector2d::Zero(); ///< page pixel of the model origin
    double x = 0, y = 0, width = 0, height = 0;         ///< the panel's drawing area on the page, pixels

    Eigen::Vector2d toPx(const Eigen::Vector3d& p) const {
        return {originPx.x() + p.dot(axes.right) * pxPerM, originPx.y() - p.dot(axes.up) * pxPerM};
    }
    /// Distance toward the viewer, metres: larger is nearer.
    double depth(const Eigen::Vector3d& p) const { return p.dot(axes.toViewer); }
};

/// What every panel of one picture shares.
struct PanelStyle {
    double glyphM = 0.1;        ///< length of limit cones, pyramids and hinge arms, metres
    double massPxPerSqrtKg = 1; ///< mass disc radius per √kg, so disc area is proportional to mass
    bool massLabels = false;    ///< write "12.3 kg" by each centre of mass (the first panel only)
};

/// The figure's bounds in `view`: min and max over body vertices, md5 joints (not the root) and anchors of
/// the page coordinates (right, up), metres.
std::pair<Eigen::Vector2d, Eigen::Vector2d> viewBounds(const figure::Figure& figure, const PictureRequest& request,
                                                       View view);

/// Whether the request's ground plane is drawn in the panel: a view with Z up, the ground inside the panel.
bool groundInView(const PictureRequest& request, const PanelMapping& panel);

/// Draws the requested layers of the figure into the panel, clipped to it.
void drawPanel(cairo_t* cr, const figure::Figure& figure, const PictureRequest& request, const PanelMapping& panel,
               const PanelStyle& style);

/// The colour that marks constraints of `type` (anchors and limits).
Rgb constraintColour(figure::JointType type);
/// The anchor mark of a constraint of `type`, centred on `at` (pixels); also used by the legend.
void drawAnchorMark(cairo_t* cr, figure::JointType type, const Eigen::Vector2d& at);
/// The fill colour of body `index`.
Rgb bodyColour(std::size_t index);
/// The md5 root joint's mark (the entity origin), centred on `at` (pixels).
void drawRootMark(cairo_t* cr, const Eigen::Vector2d& at);
/// The colour of the md5 skeleton.
Rgb skeletonColour();
/// The colour of the reference pose of a two-pose picture (PictureRequest::reference).
Rgb referencePoseColour();
/// The colour of the request's own pose in a two-pose picture.
Rgb ownPoseColour();

/// Body names at their centres of mass and constraint names at their anchors (PictureLayers::names), each on a
/// white halo, nudged apart where they would overlap.
void drawNames(cairo_t* cr, const figure::Figure& figure, const PictureRequest& request, const PanelMapping& panel);

} // namespace afb::cli
