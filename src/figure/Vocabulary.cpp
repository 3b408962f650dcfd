#include "afb/figure/Vocabulary.h"

namespace afb::figure {

const char* toString(ShapeType type) {
    switch (type) {
    case ShapeType::Box: return "box";
    case ShapeType::Octahedron: return "octahedron";
    case ShapeType::Dodecahedron: return "dodecahedron";
    case ShapeType::Cylinder: return "cylinder";
    case ShapeType::Cone: return "cone";
    case ShapeType::Bone: return "bone";
    }
    return "?";
}

const char* toString(JointType type) {
    switch (type) {
    case JointType::Fixed: return "fixed";
    case JointType::BallAndSocket: return "ballAndSocketJoint";
    case JointType::Universal: return "universalJoint";
    case JointType::Hinge: return "hinge";
    case JointType::Slider: return "slider";
    case JointType::Spring: return "spring";
    }
    return "?";
}

} // namespace afb::figure
