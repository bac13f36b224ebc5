#include "envs/cloth/pan_surface.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "common/det_math.hpp"
#include "common/error.hpp"

namespace dsb::cloth {

namespace {

// [z]_x: z x a = (-a_y, a_x, 0)
Mat3 z_cross() {
  Mat3 m = Mat3::Zero();
  m(0, 1) = -1.0;
  m(1, 0) = 1.0;
  return m;
}

Mat3 rotation(double c, double s) {
  Mat3 r;
  r << c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0;
  return r;
}

// d R / d theta
Mat3 rotation_derivative(double c, double s) {
  Mat3 r;
  r << -s, -c, 0.0, c, -s, 0.0, 0.0, 0.0, 0.0;
  return r;
}

}  // namespace

void PanShape::validate() const {
  auto fail = [](const std::string& field, const std::string& why) { throw ConfigError("pan", field, why); };
  if (!(std::isfinite(radius) && radius > 0.0)) fail("radius", "must be finite and > 0");
  if (!(std::isfinite(flat_radius) && flat_radius > 0.0 && flat_radius < radius))
    fail("flat_radius", "must be in (0, radius)");
  if (!(std::isfinite(rim_height) && rim_height >= 0.0)) fail("rim_height", "must be finite and >= 0");
  if (!(std::isfinite(thickness) && thickness > 0.0)) fail("thickness", "must be finite and > 0");
}

void PanShape::profile(double r, double& h, double& dh, double& d2h) const {
  // h = H u^3, u = (r - r_f) / (R - r_f) on the rim, 0 on the disc
  if (r <= flat_radius) {
    h = dh = d2h = 0.0;
    return;
  }
  const double w = radius - flat_radius;
  const double u = (r - flat_radius) / w;
  h = rim_height * u * u * u;
  dh = 3.0 * rim_height * u * u / w;
  d2h = 6.0 * rim_height * u / (w * w);
}

PanSurface::PanSurface(PanShape shape) : shape_(shape) {
  shape_.validate();
  set_path(std::vector<PanPose>(2), 1e-3);
}

void PanSurface::set_path(std::span<const PanPose> path, double dt) {
  if (path.size() < 2) throw std::invalid_argument("pan: a path needs at least 2 rows (one step)");
  if (!(dt > 0.0)) throw std::invalid_argument("pan: dt must be > 0");
  dt_ = dt;
  path_.assign(path.begin(), path.end());
  trig_.resize(path_.size());
  for (std::size_t t = 0; t < path_.size(); ++t) dm::sincos(path_[t].tilt, &trig_[t].s, &trig_[t].c);
}

void PanSurface::set_pose(int t, const PanPose& pose) {
  path_.at(t) = pose;
  dm::sincos(pose.tilt, &trig_[t].s, &trig_[t].c);
}

Vec3 PanSurface::to_world(const PanPose& p, const Vec3& local) {
  double s = 0.0, c = 1.0;
  dm::sincos(p.tilt, &s, &c);
  return Vec3(p.x, p.y, 0.0) + rotation(c, s) * local;
}

bool PanSurface::local_normal(const Vec3& l, double& distance, Vec3& n, Mat3& dn_dl) const {
  const double r = std::sqrt(l.x() * l.x() + l.z() * l.z());
  if (r > shape_.radius) return false;
  double h = 0.0, dh = 0.0, d2h = 0.0;
  shape_.profile(r, h, dh, d2h);
  // N = (-g l_x, 1, -g l_z), g = h'(r) / r; |N| = sqrt(1 + h'^2)
  const double g = r > shape_.flat_radius ? dh / r : 0.0;
  const double norm = std::sqrt(1.0 + dh * dh);
  distance = (l.y() - h) / norm;
  if (!(distance > -shape_.thickness)) return false;
  const Vec3 N(-g * l.x(), 1.0, -g * l.z());
  n = N / norm;
  // dN/dl with g' = (h'' r - h') / r^2; zero on the disc
  Mat3 dN = Mat3::Zero();
  if (r > shape_.flat_radius) {
    const double gp = (d2h * r - dh) / (r * r);
    const double a = gp / r;
    dN(0, 0) = -(g + a * l.x() * l.x());
    dN(0, 2) = -a * l.x() * l.z();
    dN(2, 0) = -a * l.x() * l.z();
    dN(2, 2) = -(g + a * l.z() * l.z());
  }
  // d(N/|N|) = (I - n n^T) dN / |N|
  dn_dl = (Mat3::Identity() - n * n.transpose()) * dN / norm;
  return true;
}

SurfaceSample PanSurface::sample(int step, const Vec3& x) const {
  SurfaceSample q;
  const int t = step;
  const PanPose& p = path_[t];
  const PanPose& p1 = path_[std::min(std::size_t(t) + 1, path_.size() - 1)];  // still after the last row
  const Mat3 R = rotation(trig_[t].c, trig_[t].s);
  const Vec3 d = x - Vec3(p.x, p.y, 0.0);
  const Vec3 l = R.transpose() * d;
  double distance = 0.0;
  Vec3 n;
  Mat3 dn_dl;
  if (!local_normal(l, distance, n, dn_dl)) {
    q.distance = 1.0;  // no pan here (beyond the rim or under the shell)
    return q;
  }
  q.distance = distance;
  q.normal = R * n;
  q.dnormal_dx = R * dn_dl * R.transpose();
  // rigid velocity of the chord: vc + omega z x (x - c)
  const double omega = (p1.tilt - p.tilt) / dt_;
  q.velocity = Vec3((p1.x - p.x) / dt_, (p1.y - p.y) / dt_, 0.0) + omega * Vec3(-d.y(), d.x(), 0.0);
  q.dvelocity_dx = omega * z_cross();
  return q;
}

void PanSurface::sample_adjoint(int step, const Vec3& x, const Vec3& normal_bar, const Vec3& velocity_bar,
                                std::span<double> param_bar) const {
  const int t = step;
  const PanPose& p = path_[t];
  const PanPose& p1 = path_[std::min(std::size_t(t) + 1, path_.size() - 1)];  // still after the last row
  const double c = trig_[t].c, s = trig_[t].s;
  const Mat3 R = rotation(c, s);
  const Vec3 d = x - Vec3(p.x, p.y, 0.0);
  const Vec3 l = R.transpose() * d;
  double distance = 0.0;
  Vec3 n;
  Mat3 dn_dl;
  if (!local_normal(l, distance, n, dn_dl)) return;  // the sample was constant (no contact)
  double* row0 = param_bar.data() + 3 * std::size_t(t);
  // normal n_w = R n(l), l = R^T (x - c): dn_w/dc = -R dn_dl R^T,
  // dn_w/dtheta = R' n + R dn_dl R'^T d
  const Mat3 Dx = R * dn_dl * R.transpose();
  const Vec3 c_bar_n = -(Dx.transpose() * normal_bar);
  const Mat3 Rp = rotation_derivative(c, s);
  const Vec3 dn_dtheta = Rp * n + R * (dn_dl * (Rp.transpose() * d));
  row0[0] += c_bar_n.x();
  row0[1] += c_bar_n.y();
  row0[2] += normal_bar.dot(dn_dtheta);
  // velocity u = vc + omega z x (x - c): vc = (c1 - c0) / dt, omega = (theta1 - theta0) / dt (a
  // sample at the last row is still: no velocity to differentiate)
  if (std::size_t(t) + 1 >= path_.size()) return;
  double* row1 = row0 + 3;
  const double omega = (p1.tilt - p.tilt) / dt_;
  const double vx_bar = velocity_bar.x() / dt_, vy_bar = velocity_bar.y() / dt_;
  const double omega_bar = velocity_bar.dot(Vec3(-d.y(), d.x(), 0.0)) / dt_;
  row1[0] += vx_bar;
  row1[1] += vy_bar;
  row1[2] += omega_bar;
  row0[0] -= vx_bar;
  row0[1] -= vy_bar;
  row0[2] -= omega_bar;
  // through d = x - c: c_bar -= (omega [z]_x)^T u_bar = omega (u_bar_y, -u_bar_x)
  row0[0] -= omega * velocity_bar.y();
  row0[1] += omega * velocity_bar.x();
}

}  // namespace dsb::cloth
