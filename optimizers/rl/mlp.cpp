#include "optimizers/rl/mlp.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "common/det_math.hpp"
#include "common/error.hpp"

namespace dsb {

const char* to_string(Activation a) { return a == Activation::tanh ? "tanh" : "relu"; }

Mlp::Mlp(std::vector<int> sizes, Activation activation) : sizes_(std::move(sizes)), activation_(activation) {
  if (sizes_.size() < 2) throw ConfigError("mlp", "sizes", "needs at least {in, out}");
  for (std::size_t l = 0; l < sizes_.size(); ++l)
    if (sizes_[l] < 1) throw ConfigError("mlp", "sizes", "entry " + std::to_string(l) + " must be >= 1");
  // offsets: per layer W_l (n_{l+1} n_l) then b_l (n_{l+1})
  std::size_t n = 0;
  for (int l = 0; l < layer_count(); ++l) {
    offsets_.push_back(n);
    n += std::size_t(sizes_[l + 1]) * std::size_t(sizes_[l]) + std::size_t(sizes_[l + 1]);
  }
  params_.assign(n, 0.0);
}

Eigen::Map<const Eigen::MatrixXd> Mlp::weight(int l) const {
  return {params_.data() + weight_offset(l), sizes_[l + 1], sizes_[l]};
}
Eigen::Map<const Eigen::VectorXd> Mlp::bias(int l) const { return {params_.data() + bias_offset(l), sizes_[l + 1]}; }
Eigen::Map<Eigen::MatrixXd> Mlp::weight(int l) { return {params_.data() + weight_offset(l), sizes_[l + 1], sizes_[l]}; }
Eigen::Map<Eigen::VectorXd> Mlp::bias(int l) { return {params_.data() + bias_offset(l), sizes_[l + 1]}; }

namespace {

// y[j] += sum_t a[t] x_t[j] over t = 0 .. T-1 in increasing order, for j < n. Four terms per pass
// over y (fewer loads and stores of y); the sum for each j is still ((y + a0 x0) + a1 x1) + ...,
// exactly the order of T single passes.
void axpy_sum(double* y, const double* const* x, const double* a, int terms, Eigen::Index n) {
  int t = 0;
  for (; t + 4 <= terms; t += 4) {
    const double* x0 = x[t];
    const double* x1 = x[t + 1];
    const double* x2 = x[t + 2];
    const double* x3 = x[t + 3];
    const double a0 = a[t], a1 = a[t + 1], a2 = a[t + 2], a3 = a[t + 3];
    for (Eigen::Index j = 0; j < n; ++j) y[j] = (((y[j] + x0[j] * a0) + x1[j] * a1) + x2[j] * a2) + x3[j] * a3;
  }
  for (; t < terms; ++t) {
    const double* x0 = x[t];
    const double a0 = a[t];
    for (Eigen::Index j = 0; j < n; ++j) y[j] = y[j] + x0[j] * a0;
  }
}

// z = W x + b (z: rows x batch); z(i, b) = b_i + sum_k W(i, k) x(k, b), k increasing
void affine(const double* w, const double* bias, int rows, int cols, const Eigen::MatrixXd& x, Eigen::MatrixXd& z) {
  const Eigen::Index batch = x.cols();
  z.resize(rows, batch);
  std::vector<const double*> wcols(cols);  // column k of W
  for (int k = 0; k < cols; ++k) wcols[k] = w + std::size_t(k) * rows;
  for (Eigen::Index s = 0; s < batch; ++s) {
    double* zc = z.data() + s * rows;
    for (int i = 0; i < rows; ++i) zc[i] = bias[i];
    axpy_sum(zc, wcols.data(), x.data() + s * cols, cols, rows);
  }
}

// dx = W^T dz (cols x batch); dx(k, b) = sum_i W(i, k) dz(i, b), i increasing. Computed on the
// transposes so the inner loop runs over contiguous samples (same order of the sum).
void affine_input_grad(const double* w, int rows, int cols, const Eigen::MatrixXd& dz, Eigen::MatrixXd& dx) {
  const Eigen::Index batch = dz.cols();
  const Eigen::MatrixXd dzt = dz.transpose();  // batch x rows
  std::vector<const double*> dcols(rows);      // row i of dz, contiguous in dzt
  for (int i = 0; i < rows; ++i) dcols[i] = dzt.data() + std::size_t(i) * batch;
  Eigen::MatrixXd dxt = Eigen::MatrixXd::Zero(batch, cols);
  for (int k = 0; k < cols; ++k)
    axpy_sum(dxt.data() + std::size_t(k) * batch, dcols.data(), w + std::size_t(k) * rows, rows, batch);
  dx = dxt.transpose();
}

// dW += delta a^T, db += delta 1: dW(i, k) += sum_b delta(i, b) a(k, b), db(i) += sum_b delta(i, b),
// b increasing. Transposing a gives, for each k, the coefficients a(k, .) contiguous.
void affine_param_grad(const Eigen::MatrixXd& delta, const Eigen::MatrixXd& a, double* gw, double* gb) {
  const Eigen::Index rows = delta.rows(), cols = a.rows(), batch = delta.cols();
  const Eigen::MatrixXd at = a.transpose();  // batch x cols
  std::vector<const double*> dcols(batch);   // column b of delta
  for (Eigen::Index s = 0; s < batch; ++s) dcols[s] = delta.data() + s * rows;
  for (Eigen::Index k = 0; k < cols; ++k)
    axpy_sum(gw + k * rows, dcols.data(), at.data() + k * batch, static_cast<int>(batch), rows);
  const std::vector<double> ones(batch, 1.0);  // x * 1.0 is exact: the same bits as plain adds
  axpy_sum(gb, dcols.data(), ones.data(), static_cast<int>(batch), rows);
}

}  // namespace

Eigen::MatrixXd Mlp::forward(const Eigen::MatrixXd& x, MlpCache* cache) const {
  if (x.rows() != in_dim())
    throw std::invalid_argument("mlp forward: input has " + std::to_string(x.rows()) + " rows, the network takes " +
                                std::to_string(in_dim()));
  const int L = layer_count();
  if (cache) {
    cache->act.resize(L);
    cache->act[0] = x;
  }
  Eigen::MatrixXd a = x, z;
  for (int l = 0; l < L; ++l) {
    // z_l = W_l a_l + b_l   (n_{l+1} x batch)
    affine(params_.data() + weight_offset(l), params_.data() + bias_offset(l), sizes_[l + 1], sizes_[l], a, z);
    if (l == L - 1) break;  // linear output layer
    // a_{l+1} = f(z_l), f = tanh or relu
    if (activation_ == Activation::tanh)
      for (Eigen::Index i = 0; i < z.size(); ++i) z.data()[i] = dm::tanh(z.data()[i]);
    else
      for (Eigen::Index i = 0; i < z.size(); ++i) z.data()[i] = z.data()[i] > 0.0 ? z.data()[i] : 0.0;
    a.swap(z);
    if (cache) cache->act[l + 1] = a;
  }
  return z;
}

Eigen::VectorXd Mlp::forward_one(const Eigen::VectorXd& x) const { return forward(Eigen::MatrixXd(x)).col(0); }

void Mlp::backward(const MlpCache& cache, const Eigen::MatrixXd& dy, std::span<double> grad,
                   Eigen::MatrixXd* dx) const {
  const int L = layer_count();
  if (static_cast<int>(cache.act.size()) != L || cache.act[0].rows() != in_dim())
    throw std::invalid_argument("mlp backward: the cache is not from a forward pass of this network");
  const Eigen::Index batch = cache.act[0].cols();
  if (dy.rows() != out_dim() || dy.cols() != batch)
    throw std::invalid_argument("mlp backward: dy must be out x batch (" + std::to_string(out_dim()) + " x " +
                                std::to_string(batch) + ")");
  if (!grad.empty() && grad.size() != params_.size())
    throw std::invalid_argument("mlp backward: grad must be empty or hold param_count() values");

  Eigen::MatrixXd delta = dy, da;  // delta = dL/dz_l (n_{l+1} x batch)
  for (int l = L - 1; l >= 0; --l) {
    const int rows = sizes_[l + 1], cols = sizes_[l];
    const Eigen::MatrixXd& a = cache.act[l];  // input of layer l (cols x batch)
    // dL/dW_l += delta a_l^T, dL/db_l += delta 1
    if (!grad.empty()) affine_param_grad(delta, a, grad.data() + weight_offset(l), grad.data() + bias_offset(l));
    if (l == 0 && !dx) break;
    // dL/da_l = W_l^T delta   (cols x batch)
    affine_input_grad(params_.data() + weight_offset(l), rows, cols, delta, da);
    if (l == 0) {
      *dx = std::move(da);
      break;
    }
    // dL/dz_{l-1} = dL/da_l * f'(z_{l-1}); tanh' = 1 - a^2, relu' = [a > 0] (0 at the kink, as torch)
    if (activation_ == Activation::tanh)
      for (Eigen::Index i = 0; i < da.size(); ++i) da.data()[i] *= 1.0 - a.data()[i] * a.data()[i];
    else
      for (Eigen::Index i = 0; i < da.size(); ++i)
        if (!(a.data()[i] > 0.0)) da.data()[i] = 0.0;
    delta.swap(da);
  }
}

Eigen::MatrixXd orthogonal_matrix(int rows, int cols, double gain, Rng& rng) {
  if (rows < 1 || cols < 1) throw std::invalid_argument("orthogonal_matrix: rows and cols must be >= 1");
  // G (rows x cols), entries drawn row by row
  Eigen::MatrixXd g(rows, cols);
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j) g(i, j) = rng.normal();
  const bool wide = rows < cols;
  Eigen::MatrixXd a = wide ? Eigen::MatrixXd(g.transpose()) : g;  // m x n, m >= n
  const int m = static_cast<int>(a.rows()), n = static_cast<int>(a.cols());

  // Householder QR: H_j = I - tau_j v_j v_j^T zeroes A(j+1:, j); R_jj = alpha_j = -sign(x_0) |x|
  std::vector<Eigen::VectorXd> vs(n);
  std::vector<double> taus(n, 0.0), rdiag(n, 0.0);
  for (int j = 0; j < n; ++j) {
    const int len = m - j;
    Eigen::VectorXd v(len);
    double norm2 = 0.0;
    for (int r = 0; r < len; ++r) {
      v[r] = a(j + r, j);
      norm2 += v[r] * v[r];
    }
    const double norm = std::sqrt(norm2);
    const double alpha = v[0] >= 0.0 ? -norm : norm;
    rdiag[j] = alpha;
    v[0] -= alpha;
    double vn2 = 0.0;
    for (int r = 0; r < len; ++r) vn2 += v[r] * v[r];
    taus[j] = vn2 > 0.0 ? 2.0 / vn2 : 0.0;
    // A(j:, j:) <- H_j A(j:, j:)
    for (int c = j; c < n; ++c) {
      double s = 0.0;
      for (int r = 0; r < len; ++r) s += v[r] * a(j + r, c);
      s *= taus[j];
      for (int r = 0; r < len; ++r) a(j + r, c) -= s * v[r];
    }
    vs[j] = std::move(v);
  }
  // Q = H_0 H_1 ... H_{n-1} [I_n; 0]   (m x n), applied right to left
  Eigen::MatrixXd q = Eigen::MatrixXd::Identity(m, n);
  for (int j = n - 1; j >= 0; --j) {
    const int len = m - j;
    for (int c = 0; c < n; ++c) {
      double s = 0.0;
      for (int r = 0; r < len; ++r) s += vs[j][r] * q(j + r, c);
      s *= taus[j];
      for (int r = 0; r < len; ++r) q(j + r, c) -= s * vs[j][r];
    }
  }
  // column j times sign(R_jj), then the gain
  for (int j = 0; j < n; ++j) {
    const double sgn = rdiag[j] > 0.0 ? 1.0 : (rdiag[j] < 0.0 ? -1.0 : 0.0);
    q.col(j) *= sgn * gain;
  }
  return wide ? Eigen::MatrixXd(q.transpose()) : q;
}

void init_orthogonal(Mlp& net, double output_gain, Rng& rng, double hidden_gain) {
  const int L = net.layer_count();
  for (int l = 0; l < L; ++l) {
    const double gain = l == L - 1 ? output_gain : hidden_gain;
    net.weight(l) = orthogonal_matrix(net.sizes()[l + 1], net.sizes()[l], gain, rng);
    net.bias(l).setZero();
  }
}

void init_torch_default(Mlp& net, Rng& rng) {
  for (int l = 0; l < net.layer_count(); ++l) {
    const int rows = net.sizes()[l + 1], cols = net.sizes()[l];
    const double bound = 1.0 / std::sqrt(static_cast<double>(cols));
    auto w = net.weight(l);
    for (int i = 0; i < rows; ++i)
      for (int k = 0; k < cols; ++k) w(i, k) = rng.uniform(-bound, bound);
    auto b = net.bias(l);
    for (int i = 0; i < rows; ++i) b[i] = rng.uniform(-bound, bound);
  }
}

}  // namespace dsb
