// Affine transforms as 4x4 matrices, named dest_from_src (world_from_local).
#pragma once
#include "core/geometry.h"
#include <Eigen/Dense>

namespace lpt {

struct Transform {
    Eigen::Matrix4f m = Eigen::Matrix4f::Identity();
    Eigen::Matrix4f inv = Eigen::Matrix4f::Identity();

    Transform() = default;
    explicit Transform(const Eigen::Matrix4f& mat) : m(mat), inv(mat.inverse()) {}

    Vec3f point(const Vec3f& p) const { return (m.topLeftCorner<3, 3>() * p + m.topRightCorner<3, 1>()); }
    Vec3f vector(const Vec3f& v) const { return m.topLeftCorner<3, 3>() * v; }
    /// Normals transform with the inverse transpose.
    Vec3f normal(const Vec3f& n) const { return inv.topLeftCorner<3, 3>().transpose() * n; }
    Transform operator*(const Transform& o) const { return Transform(m * o.m); }

    static Transform translate(const Vec3f& t);
    static Transform scale(const Vec3f& s);
    /// Rotation about `axis` by `degrees` (right-handed).
    static Transform rotate(const Vec3f& axis, float degrees);
    /// Mitsuba's look-at: local +z toward target, +y toward up, +x = up × dir (image left).
    static Transform look_at(const Vec3f& origin, const Vec3f& target, const Vec3f& up);
};

}  // namespace lpt
