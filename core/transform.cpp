#include "core/transform.h"
#include <stdexcept>

namespace lpt {

Transform Transform::translate(const Vec3f& t) {
    Eigen::Matrix4f m = Eigen::Matrix4f::Identity();
    m.topRightCorner<3, 1>() = t;
    return Transform(m);
}

Transform Transform::scale(const Vec3f& s) {
    Eigen::Matrix4f m = Eigen::Matrix4f::Identity();
    m(0, 0) = s.x();
    m(1, 1) = s.y();
    m(2, 2) = s.z();
    return Transform(m);
}

Transform Transform::rotate(const Vec3f& axis, float degrees) {
    Eigen::Matrix4f m = Eigen::Matrix4f::Identity();
    m.topLeftCorner<3, 3>() = Eigen::AngleAxisf(degrees * kPi / 180.f, axis.normalized()).toRotationMatrix();
    return Transform(m);
}

Transform Transform::look_at(const Vec3f& origin, const Vec3f& target, const Vec3f& up) {
    // Each degenerate case named: all three used to read "'up' is parallel to the view direction".
    if ((target - origin).norm() == 0.f) throw std::invalid_argument("look_at: 'origin' and 'target' coincide");
    if (up.norm() == 0.f) throw std::invalid_argument("look_at: 'up' has zero length");
    Vec3f dir = (target - origin).normalized();
    Vec3f left = up.normalized().cross(dir);
    if (left.norm() < 1e-6f) throw std::invalid_argument("look_at: 'up' is parallel to the view direction");
    left.normalize();
    Vec3f new_up = dir.cross(left);
    Eigen::Matrix4f m = Eigen::Matrix4f::Identity();
    m.block<3, 1>(0, 0) = left;
    m.block<3, 1>(0, 1) = new_up;
    m.block<3, 1>(0, 2) = dir;
    m.block<3, 1>(0, 3) = origin;
    return Transform(m);
}

}  // namespace lpt
