#pragma once
// Small fixed-size types shared by the MLS-MPM engine (envs/mpm/). Eigen's fixed-size 3-vectors
// and 3x3 matrices: no heap, no alignment requirement, fully unrolled products.
#include <Eigen/Dense>

namespace dsb::mpm {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Vec4 = Eigen::Vector4d;  // a grid node's momentum and mass (q_x, q_y, q_z, m): two SSE2 packets

}  // namespace dsb::mpm
