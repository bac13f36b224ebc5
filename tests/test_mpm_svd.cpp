// envs/mpm/svd3: the 3x3 SVD (accuracy, conventions, rank-deficient and clustered inputs, the
// batch form's bits) and its adjoints against central differences.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "common/det_math.hpp"
#include "common/rng.hpp"
#include "envs/mpm/svd3.hpp"

namespace {

using dsb::Rng;
using namespace dsb::mpm;
namespace dm = dsb::dm;

constexpr double kEps = std::numeric_limits<double>::epsilon();
// Bounds in units of eps (Frobenius norms). Measured maxima over these inputs: reconstruction
// ~10, U^T U - I ~8, V^T V - I ~16 (V accumulates 15 rotations, U 3), singular values ~12 eps
// of sigma_max off Eigen's JacobiSVD.
constexpr double kRecC = 16.0;
constexpr double kOrthUC = 12.0;
constexpr double kOrthVC = 24.0;
constexpr double kSigmaTol = 1e-14;  // relative to sigma_max

Mat3 gaussian(Rng& rng) {
  Mat3 m;
  for (int i = 0; i < 9; ++i) m(i) = rng.normal();
  return m;
}

Mat3 rotation(Rng& rng) {
  Eigen::Quaterniond q(rng.normal(), rng.normal(), rng.normal(), rng.normal());
  return q.normalized().toRotationMatrix();
}

// R1 diag(s) R2 with seeded random rotations
std::function<Mat3(Rng&)> rotated(Vec3 s) {
  return [s](Rng& rng) { return Mat3(rotation(rng) * s.asDiagonal() * rotation(rng)); };
}

struct Family {
  std::string name;
  int count;
  std::function<Mat3(Rng&)> make;
};

std::vector<Family> families() {
  const double e9 = 1e-9;
  return {
      {"gaussian", 6000, gaussian},
      {"gaussian x 1e8", 1000, [](Rng& r) { return Mat3(1e8 * gaussian(r)); }},
      {"gaussian x 1e-8", 1000, [](Rng& r) { return Mat3(1e-8 * gaussian(r)); }},
      {"I + 1e-6 gaussian", 2000, [](Rng& r) { return Mat3(Mat3::Identity() + 1e-6 * gaussian(r)); }},
      {"rotation", 1000, rotation},
      {"R (1,1,-1) R", 500, rotated(Vec3(1, 1, -1))},
      {"R (2,1,1) R", 500, rotated(Vec3(2, 1, 1))},
      {"R (1,1,0.5) R", 500, rotated(Vec3(1, 1, 0.5))},
      {"R (1,1+1e-9,1-1e-9) R", 500, rotated(Vec3(1, 1 + e9, 1 - e9))},
      {"R (1+1e-9,1,-1) R", 500, rotated(Vec3(1 + e9, 1, -1))},
      {"R (3,2,-1) R", 500, rotated(Vec3(3, 2, -1))},
      {"R (1,1e-4,1e-8) R", 500, rotated(Vec3(1, 1e-4, 1e-8))},
      {"R (1,1e-8,1e-9) R", 500, rotated(Vec3(1, 1e-8, 1e-9))},
      {"rank 2 R (1,0.5,0) R", 500, rotated(Vec3(1, 0.5, 0))},
      {"rank 2 R (1,1,0) R", 500, rotated(Vec3(1, 1, 0))},
      {"rank 1 R (1,0,0) R", 500, rotated(Vec3(1, 0, 0))},
      {"rank 1 a b^T", 500,
       [](Rng& r) {
         const Vec3 a(r.normal(), r.normal(), r.normal()), b(r.normal(), r.normal(), r.normal());
         return Mat3(a * b.transpose());
       }},
      {"zero column", 500,
       [](Rng& r) {
         Mat3 m = gaussian(r);
         m.col(static_cast<int>(r.below(3))).setZero();
         return m;
       }},
  };
}

// fixed hard cases
std::vector<Mat3> special_inputs() {
  std::vector<Mat3> out;
  const double e9 = 1e-9;
  for (const Vec3& d : {Vec3(1, 1, 1), Vec3(2, 1, 1), Vec3(1, 1, 0.5), Vec3(1, 1 + e9, 1 - e9), Vec3(1, 2, 3),
                        Vec3(-1, 1, 1), Vec3(-1, -1, -1), Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 0, 1), Vec3(0, 1, 1),
                        Vec3(1e-8, 1e-8, 1e-8), Vec3(1e8, 1e8, 1e8), Vec3(1e8, 1, 1e-8), Vec3(0.5, -2, 1)})
    out.push_back(d.asDiagonal());
  Mat3 p;
  p << 0, 1, 0, 0, 0, 1, 1, 0, 0;
  out.push_back(p);   // cyclic permutation
  out.push_back(-p);  // det < 0
  Mat3 z = Mat3::Zero();
  z(1, 2) = 3.0;  // rank 1, one entry
  out.push_back(z);
  return out;
}

struct ForwardStats {
  double rec = 0, orth_u = 0, orth_v = 0, sigma = 0;
};

// every property of one decomposition, with the worst errors collected into `st`
void check_svd(const Mat3& A, const Svd3& s, ForwardStats& st, const std::string& what) {
  ASSERT_TRUE(s.U.allFinite() && s.V.allFinite() && s.sigma.allFinite()) << what;
  const double na = A.norm();
  const double rec = (A - s.U * s.sigma.asDiagonal() * s.V.transpose()).norm();
  const double ou = (s.U.transpose() * s.U - Mat3::Identity()).norm();
  const double ov = (s.V.transpose() * s.V - Mat3::Identity()).norm();
  EXPECT_LE(rec, kRecC * kEps * na) << what;
  EXPECT_LE(ou, kOrthUC * kEps) << what;
  EXPECT_LE(ov, kOrthVC * kEps) << what;
  EXPECT_NEAR(s.U.determinant(), 1.0, 1e-14) << what;
  EXPECT_NEAR(s.V.determinant(), 1.0, 1e-14) << what;
  EXPECT_GE(s.sigma(1), 0.0) << what;
  EXPECT_GE(s.sigma(0), s.sigma(1)) << what;
  EXPECT_GE(s.sigma(1), std::fabs(s.sigma(2))) << what;
  // the sign of det A, where it is not lost in round-off (rank-deficient inputs have det ~ 0)
  const double det = A.determinant();
  if (std::fabs(det) > 1e-6 * na * na * na) {
    EXPECT_EQ(det < 0, s.sigma(2) < 0) << what;
  }
  const Vec3 ref = Eigen::JacobiSVD<Mat3>(A).singularValues();
  const Vec3 got(s.sigma(0), s.sigma(1), std::fabs(s.sigma(2)));
  const double dsig = (got - ref).cwiseAbs().maxCoeff();
  EXPECT_LE(dsig, kSigmaTol * ref(0)) << what;
  if (na > 0) {
    st.rec = std::max(st.rec, rec / (kEps * na));
    st.sigma = std::max(st.sigma, dsig / (kEps * ref(0)));
  }
  st.orth_u = std::max(st.orth_u, ou / kEps);
  st.orth_v = std::max(st.orth_v, ov / kEps);
}

// all inputs of the forward tests, in a fixed order
std::vector<Mat3> all_inputs() {
  std::vector<Mat3> out = special_inputs();
  Rng rng(20240611);
  for (const Family& f : families())
    for (int n = 0; n < f.count; ++n) out.push_back(f.make(rng));
  return out;
}

TEST(MpmSvd, ForwardOnRandomAndHardFamilies) {
  Rng rng(20240611);
  ForwardStats all;
  for (const Family& f : families()) {
    ForwardStats st;
    for (int n = 0; n < f.count; ++n) {
      const Mat3 A = f.make(rng);
      check_svd(A, svd3(A), st, f.name + " #" + std::to_string(n));
      if (HasFatalFailure()) return;
    }
    std::printf("  %-24s max errors / eps: reconstruction %5.2f  U %5.2f  V %5.2f  sigma %5.2f\n", f.name.c_str(),
                st.rec, st.orth_u, st.orth_v, st.sigma);
    all.rec = std::max(all.rec, st.rec);
    all.orth_u = std::max(all.orth_u, st.orth_u);
    all.orth_v = std::max(all.orth_v, st.orth_v);
    all.sigma = std::max(all.sigma, st.sigma);
  }
  const std::vector<Mat3> special = special_inputs();
  for (std::size_t n = 0; n < special.size(); ++n)
    check_svd(special[n], svd3(special[n]), all, "special #" + std::to_string(n));
  std::printf("  %-24s max errors / eps: reconstruction %5.2f  U %5.2f  V %5.2f  sigma %5.2f\n", "all", all.rec,
              all.orth_u, all.orth_v, all.sigma);
}

TEST(MpmSvd, ExactCasesAndRankDeficient) {
  const Svd3 z = svd3(Mat3::Zero());
  EXPECT_EQ(z.sigma, Vec3::Zero());
  EXPECT_EQ(z.U, Mat3::Identity());
  EXPECT_EQ(z.V, Mat3::Identity());
  const Svd3 id = svd3(Mat3::Identity());
  EXPECT_EQ(id.sigma, Vec3(1, 1, 1));  // no rotation is taken: the off-diagonals are exactly 0
  EXPECT_EQ(id.U, Mat3::Identity());
  const Svd3 neg = svd3(-Mat3::Identity());
  EXPECT_EQ(neg.sigma, Vec3(1, 1, -1));
  const Svd3 d = svd3(Vec3(1, 3, 2).asDiagonal());
  EXPECT_EQ(d.sigma, Vec3(3, 2, 1));  // sorted; a diagonal input is decomposed exactly
}

TEST(MpmSvd, BatchIsBitIdenticalToScalar) {
  std::vector<Mat3> in = all_inputs();
  in.push_back(Mat3::Identity());  // a count that is not a multiple of the batch width
  std::vector<Svd3> scalar(in.size()), batch(in.size());
  for (std::size_t i = 0; i < in.size(); ++i) scalar[i] = svd3(in[i]);
  svd3_batch(in.data(), batch.data(), in.size());
  EXPECT_EQ(0, std::memcmp(scalar.data(), batch.data(), in.size() * sizeof(Svd3)));
  // every position in a chunk and every tail length
  for (std::size_t len = 1; len <= 17; ++len) {
    std::vector<Svd3> part(len);
    svd3_batch(in.data() + 3, part.data(), len);
    EXPECT_EQ(0, std::memcmp(scalar.data() + 3, part.data(), len * sizeof(Svd3))) << len;
  }
}

// The bits of svd3 over seeded inputs, recorded: the same on every x86-64 CPU and with -O2, -O3
// and -O3 -march=native (checked when recorded); a change of the algorithm changes this number.
TEST(MpmSvd, RecordRestoresTheFactorsToAFewUlps) {
  // the reverse pass keeps V as a quaternion and sigma, and rebuilds U = A V / sigma
  double worst_u = 0.0, worst_v = 0.0;
  int fallbacks = 0;
  for (const Mat3& A : all_inputs()) {
    const Svd3 s = svd3(A);
    const Svd3 r = restore_svd(record_svd(s), A);
    const bool tiny = !(std::abs(s.sigma[2]) >= 1e-6 * s.sigma[0] && std::abs(s.sigma[1]) >= 1e-6 * s.sigma[0]);
    if (tiny) {
      ++fallbacks;
      EXPECT_EQ(0, std::memcmp(&r, &s, sizeof(Svd3))) << "a tiny singular value falls back to svd3";
      continue;
    }
    EXPECT_EQ(r.sigma, s.sigma);
    worst_v = std::max(worst_v, (r.V - s.V).norm());
    // U's error grows with sigma_0 / sigma_2 (the division by sigma)
    worst_u = std::max(worst_u, (r.U - s.U).norm() * std::abs(s.sigma[2]) / s.sigma[0]);
  }
  EXPECT_LE(worst_v, 24 * kEps);  // measured 16.4 (Frobenius norm of the 9 entries)
  EXPECT_LE(worst_u, 24 * kEps);  // measured 15.3
  EXPECT_GT(fallbacks, 0) << "the inputs include near-singular matrices";
  std::printf("  restored V within %.2f eps, U within %.2f eps x sigma_0 / sigma_2; %d fallbacks\n", worst_v / kEps,
              worst_u / kEps, fallbacks);
}

TEST(MpmSvd, RecordedDigest) {
  Rng rng(5);
  std::uint64_t h = dsb::fnv1a64("");
  for (int n = 0; n < 100000; ++n) {
    Mat3 A;
    for (int i = 0; i < 9; ++i) A(i) = rng.uniform(-1, 1);
    if (n % 3 == 0) A += Mat3::Identity();
    const Svd3 s = svd3(A);
    h = dsb::fnv1a64(std::string_view(reinterpret_cast<const char*>(&s), sizeof s), h);
  }
  EXPECT_EQ(h, 0x66d845a03ad0f024ULL);
}

// ---- adjoints ------------------------------------------------------------------------------------

constexpr double kStep = 1e-6;

// central differences of a scalar function of A, entry by entry
Mat3 central_diff(const std::function<double(const Mat3&)>& L, const Mat3& A) {
  Mat3 g;
  for (int i = 0; i < 9; ++i) {
    Mat3 p = A, m = A;
    p(i) += kStep;
    m(i) -= kStep;
    g(i) = (L(p) - L(m)) / (2 * kStep);
  }
  return g;
}

double rel_err(const Mat3& got, const Mat3& ref) { return (got - ref).norm() / ref.norm(); }

double inner(const Mat3& a, const Mat3& b) { return a.cwiseProduct(b).sum(); }

// the SVD of A on the branch through `base`: each pair (u_i, v_i) is flipped where the column
// points against base's (the decomposition, determinants and sigma are unchanged by this)
Svd3 svd3_aligned(const Mat3& A, const Svd3& base) {
  Svd3 s = svd3(A);
  for (int i = 0; i < 3; ++i)
    if (s.U.col(i).dot(base.U.col(i)) < 0) {
      s.U.col(i) *= -1;
      s.V.col(i) *= -1;
    }
  return s;
}

TEST(MpmSvd, ClampedAdjointAtSeparatedSingularValues) {
  Rng rng(7);
  double worst = 0;
  for (int n = 0; n < 50; ++n) {
    const Vec3 sv(3.0 + rng.uniform(), 2.0 + rng.uniform(), (n % 2 ? -1.0 : 1.0) * (0.5 + rng.uniform()));
    const Mat3 A = rotation(rng) * sv.asDiagonal() * rotation(rng);
    const Mat3 W1 = gaussian(rng), W2 = gaussian(rng), W3 = gaussian(rng), W4 = gaussian(rng);
    const Vec3 w(rng.normal(), rng.normal(), rng.normal());
    // L = <W1, U> + <w, sigma^2> + <W2, V> + <W3, U> <W4, V> / 2: a smooth function of (U, sigma, V)
    auto loss = [&](const Svd3& s) {
      return inner(W1, s.U) + w.dot(s.sigma.cwiseAbs2()) + inner(W2, s.V) + 0.5 * inner(W3, s.U) * inner(W4, s.V);
    };
    const Svd3 s = svd3(A);
    const Mat3 U_bar = W1 + 0.5 * inner(W4, s.V) * W3;
    const Mat3 V_bar = W2 + 0.5 * inner(W3, s.U) * W4;
    const Vec3 sigma_bar = 2.0 * w.cwiseProduct(s.sigma);
    const Mat3 got = svd3_adjoint(s, U_bar, sigma_bar, V_bar);
    const Mat3 fd = central_diff([&](const Mat3& B) { return loss(svd3_aligned(B, s)); }, A);
    worst = std::max(worst, rel_err(got, fd));
  }
  std::printf("  clamped adjoint, separated singular values: max relative error %.2e\n", worst);
  EXPECT_LE(worst, 1e-7);
}

// L(A) = <W1, U diag(sigma^2) V^T> + <W2, U V^T>, a well-defined function of A, at singular values
// (1 + gap, 1, 0.5): the clamped formula against the stable iso_uv_adjoint, as the gap shrinks
TEST(MpmSvd, ClampedAdjointDegradesAsTheGapShrinks) {
  Rng rng(11);
  const Mat3 R1 = rotation(rng), R2 = rotation(rng), W1 = gaussian(rng), W2 = gaussian(rng);
  std::printf("  gap      clamped rel err   stable rel err\n");
  for (double gap : {1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9}) {
    const Mat3 A = R1 * Vec3(1 + gap, 1, 0.5).asDiagonal() * R2;
    auto loss = [&](const Mat3& B) {
      const Svd3 s = svd3(B);
      return inner(W1, s.U * s.sigma.cwiseAbs2().asDiagonal() * s.V.transpose()) + inner(W2, s.U * s.V.transpose());
    };
    const Mat3 fd = central_diff(loss, A);
    const Svd3 s = svd3(A);
    const Vec3 sq = s.sigma.cwiseAbs2();
    const Mat3 U_bar = W1 * s.V * sq.asDiagonal() + W2 * s.V;
    const Mat3 V_bar = W1.transpose() * s.U * sq.asDiagonal() + W2.transpose() * s.U;
    const Vec3 sigma_bar = 2.0 * s.sigma.cwiseProduct((s.U.transpose() * W1 * s.V).diagonal());
    const double clamped = rel_err(svd3_adjoint(s, U_bar, sigma_bar, V_bar), fd);
    // the same loss through the stable adjoints: f = sigma^2 (dd = sigma_i + sigma_j) and f = 1
    Mat3 dd2, dd1 = Mat3::Zero();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) dd2(i, j) = s.sigma(i) + s.sigma(j);
    const Mat3 stable_grad = iso_uv_adjoint(s, sq, Mat3(2.0 * s.sigma.asDiagonal()), dd2, W1) +
        iso_uv_adjoint(s, Vec3::Ones(), Mat3::Zero(), dd1, W2);
    const double stable = rel_err(stable_grad, fd);
    std::printf("  %.0e   %.2e          %.2e\n", gap, clamped, stable);
    EXPECT_LE(stable, 1e-7) << gap;
    // Measured: the clamped formula agrees with the finite differences (and with the stable
    // adjoint) to 2e-10 .. 4e-10 for gaps 1e-1 .. 1e-6, where sigma_1^2 - sigma_2^2 ~ 2 gap is still
    // above the clamp 1e-6; below that the clamp shrinks the near-degenerate terms and the
    // relative error jumps to 0.41 (gap 1e-7), 0.50 (1e-8), 0.51 (1e-9). The stable adjoint stays
    // at 1e-10 .. 4e-10 throughout.
    if (gap >= 1e-6) {
      EXPECT_LE(clamped, 1e-7) << gap;
    } else {
      EXPECT_GE(clamped, 0.1) << gap;
    }
  }
}

// ---- the isotropic maps ------------------------------------------------------------------------

// inputs: well separated, near-equal, exactly equal singular values (positive determinant unless
// `inverted`; never sigma_i = -sigma_j, where the maps are not differentiable in general)
std::vector<std::pair<std::string, Mat3>> iso_inputs(bool inverted) {
  Rng rng(99);
  std::vector<std::pair<std::string, Mat3>> out;
  auto rot = [&](Vec3 s) { return Mat3(rotation(rng) * s.asDiagonal() * rotation(rng)); };
  for (int n = 0; n < 5; ++n)
    out.push_back(
        {"separated", rot(Vec3(1.7 + 0.1 * rng.uniform(), 1.1 + 0.1 * rng.uniform(), 0.6 + 0.1 * rng.uniform()))});
  out.push_back({"near-equal 1e-9", rot(Vec3(1 + 1e-9, 1, 1 - 1e-9))});
  out.push_back({"near-equal 1e-7 pair", rot(Vec3(1.3, 0.8 + 1e-7, 0.8))});
  out.push_back({"I + 1e-6 gaussian", Mat3(Mat3::Identity() + 1e-6 * gaussian(rng))});
  out.push_back({"identity", Mat3::Identity()});
  out.push_back({"rotation", rotation(rng)});
  out.push_back({"R (2,2,1) R", rot(Vec3(2, 2, 1))});
  if (inverted) {
    out.push_back({"inverted (1.5,1,-0.4)", rot(Vec3(1.5, 1, -0.4))});
    out.push_back({"inverted, equal pair (1,1,-0.5)", rot(Vec3(1, 1, -0.5))});
  }
  return out;
}

// (x^p - y^p) / (x - y) for x, y > 0, stable as x -> y (its limit p x^(p-1) at x = y)
double pow_divided_difference(double x, double y, double p) {
  if (x == y) return p * dm::pow(x, p - 1);
  const double u = (x - y) / y;
  return dm::pow(y, p - 1) * dm::expm1(p * dm::log1p(u)) / u;
}

TEST(MpmSvd, IsoUvAdjointIdentityMapIsExact) {
  Rng rng(3);
  for (const auto& [name, A] : iso_inputs(true)) {
    const Svd3 s = svd3(A);
    const Mat3 X_bar = gaussian(rng);
    const Mat3 got = iso_uv_adjoint(s, s.sigma, Mat3::Identity(), Mat3::Ones(), X_bar);
    EXPECT_LE((got - X_bar).norm(), 8 * kEps * X_bar.norm()) << name;
  }
}

TEST(MpmSvd, IsoUvAdjointPowerMapAgainstFiniteDifferences) {
  const double c = 1.3, alpha = 0.6;  // f = c sigma^alpha (sigma > 0: positive determinants)
  Rng rng(5);
  double worst = 0;
  for (const auto& [name, A] : iso_inputs(false)) {
    const Mat3 W = gaussian(rng);
    auto f_of = [&](const Vec3& sg) {
      return Vec3(c * dm::pow(sg(0), alpha), c * dm::pow(sg(1), alpha), c * dm::pow(sg(2), alpha));
    };
    auto loss = [&](const Mat3& B) {
      const Svd3 s = svd3(B);
      return inner(W, s.U * f_of(s.sigma).asDiagonal() * s.V.transpose());
    };
    const Svd3 s = svd3(A);
    Mat3 dfds = Mat3::Zero(), dd;
    for (int i = 0; i < 3; ++i) {
      dfds(i, i) = c * alpha * dm::pow(s.sigma(i), alpha - 1);
      for (int j = 0; j < 3; ++j) dd(i, j) = c * pow_divided_difference(s.sigma(i), s.sigma(j), alpha);
    }
    const double err = rel_err(iso_uv_adjoint(s, f_of(s.sigma), dfds, dd, W), central_diff(loss, A));
    worst = std::max(worst, err);
    EXPECT_LE(err, 1e-7) << name;
  }
  std::printf("  iso_uv_adjoint, f = c sigma^alpha: max relative error %.2e\n", worst);
}

TEST(MpmSvd, IsoUuAdjointKirchhoffStressAgainstFiniteDifferences) {
  const double mu = 0.8, lam = 1.7;  // g = 2 mu (sigma - 1) sigma + lam J (J - 1)
  Rng rng(13);
  double worst = 0;
  for (const auto& [name, A] : iso_inputs(true)) {
    const Mat3 W = gaussian(rng);
    auto g_of = [&](const Vec3& sg) {
      const double J = sg(0) * sg(1) * sg(2);
      return Vec3(2 * mu * (sg(0) - 1) * sg(0) + lam * J * (J - 1), 2 * mu * (sg(1) - 1) * sg(1) + lam * J * (J - 1),
                  2 * mu * (sg(2) - 1) * sg(2) + lam * J * (J - 1));
    };
    auto loss = [&](const Mat3& B) {
      const Svd3 s = svd3(B);
      return inner(W, s.U * g_of(s.sigma).asDiagonal() * s.U.transpose());
    };
    const Svd3 s = svd3(A);
    const Vec3& sg = s.sigma;
    const double J = sg(0) * sg(1) * sg(2);
    const Vec3 dJ(sg(1) * sg(2), sg(0) * sg(2), sg(0) * sg(1));
    Mat3 dgds, ddg;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        dgds(i, j) = (i == j ? 2 * mu * (2 * sg(i) - 1) : 0.0) + lam * (2 * J - 1) * dJ(j);
        ddg(i, j) = 2 * mu * (sg(i) + sg(j) - 1);  // g_i - g_j = 2 mu (s_i - s_j)(s_i + s_j - 1)
      }
    const double err = rel_err(iso_uu_adjoint(s, dgds, ddg, W), central_diff(loss, A));
    worst = std::max(worst, err);
    EXPECT_LE(err, 1e-7) << name;
  }
  std::printf("  iso_uu_adjoint, fixed-corotated Kirchhoff stress: max relative error %.2e\n", worst);
}

TEST(MpmSvd, AdjointsFiniteAtDegenerateInputs) {
  for (const Mat3& A : {Mat3(Mat3::Zero()), Mat3(Mat3::Identity()), Mat3(Vec3(1, 0, 0).asDiagonal())}) {
    const Svd3 s = svd3(A);
    EXPECT_TRUE(svd3_adjoint(s, Mat3::Ones(), Vec3::Ones(), Mat3::Ones()).allFinite());
    EXPECT_TRUE(iso_uv_adjoint(s, s.sigma, Mat3::Identity(), Mat3::Ones(), Mat3::Ones()).allFinite());
    EXPECT_TRUE(iso_uu_adjoint(s, Mat3::Identity(), Mat3::Ones(), Mat3::Ones()).allFinite());
  }
}

}  // namespace
