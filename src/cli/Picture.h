#pragma once
// Headless pictures of a figure for `afb draw`: orthographic views of the bodies, the md5 skeleton, the
// constraint anchors, the limits and the masses, drawn with cairo to PNG or SVG, with a legend and a scale
// bar in metres.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "afb/figure/Figure.h"

namespace afb::cli {

/// An orthographic view of model space (X forward, Y left, Z up).
enum class View {
    Front, ///< from +X looking toward −X: the figure's face; Y to the right, Z up
    Side,  ///< from −Y (the figure's right) looking toward +Y: facing right, X to the right, Z up
    Top,   ///< from +Z looking down: X up the page, −Y to the right
};

/// What a picture shows; every layer is on by default.
struct PictureLayers {
    bool bodies = true;   ///< body polytopes, filled and outlined, back to front
    bool joints = true;   ///< constraint anchors, one mark per constraint, coloured by type
    bool limits = true;   ///< cone and pyramid outlines, hinge arcs, at the anchors
    bool mass = true;     ///< centre-of-mass discs with area proportional to mass; labels in the first view
    bool skeleton = true; ///< md5 joints as dots, lines to their parents
    bool names = false;   ///< body names at their centres of mass, constraint names at their anchors
};

/// A second pose of the same figure, drawn beneath the request's own (a golden report: the recorded pose beneath
/// the settled one). With one, each pose is drawn in a colour of its own, named in the legend.
struct PictureReference {
    std::vector<figure::Transform> bodies; ///< one per figure body, in the frame of PictureRequest::bodies
    std::vector<figure::Transform> joints; ///< one per md5 joint, same frame
    std::string label;                     ///< the legend's name of this pose, e.g. "golden pose (recorded)"
    std::string ownLabel;                  ///< the legend's name of the request's own pose, e.g. "settled pose"
};

/// A figure in one pose, and how to picture it.
struct PictureRequest {
    std::string title;    ///< e.g. the entity name
    std::string subtitle; ///< e.g. the pose: "load pose", "drop from 1 m, t = 0.50 s"
    std::vector<View> views{View::Front, View::Side, View::Top}; ///< panels, left to right
    PictureLayers show;
    /// One body frame (centre of mass, principal axes) per figure body, in the figure's model space at spawn,
    /// metres. The load pose is each body's `loadPose`.
    std::vector<figure::Transform> bodies;
    /// One per md5 joint, same frame, metres.
    std::vector<figure::Transform> joints;
    /// Height of a ground plane (normal +Z) in the same frame, metres; drawn in the front and side views when
    /// it falls inside the panel.
    std::optional<double> groundZ;
    /// A pose drawn beneath this one, each in one colour; none: bodies in their own colours.
    std::optional<PictureReference> reference;
};

/// Draws `request` of `figure` into `out`, PNG or SVG by its extension (".png", ".svg"). Returns an error
/// message on failure (unknown extension, a file that cannot be written).
std::optional<std::string> drawPicture(const figure::Figure& figure, const PictureRequest& request,
                                       const std::filesystem::path& out);

/// The view's name as `--view` spells it ("front", "side", "top").
const char* viewName(View view);

} // namespace afb::cli
