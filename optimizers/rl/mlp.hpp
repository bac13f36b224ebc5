#pragma once
// Fully connected network for the RL baselines (ports of Stable-Baselines3's PPO and SAC, see
// Stable-Baselines3's defaults): layer sizes {in, h1, ..., out}, a tanh or relu on every
// hidden layer, a linear output layer.
//
// Parameter layout (one flat vector, so Adam, gradient clipping, Polyak averaging and hashing see
// one span): for layer l = 0 .. L-1 (n_l inputs, n_{l+1} outputs), first its weight matrix W_l
// (n_{l+1} x n_l) in column-major order, W_l(i, k) at weight_offset(l) + i + k n_{l+1}, then its
// bias b_l (n_{l+1}) at bias_offset(l) = weight_offset(l) + n_{l+1} n_l. Gradients use the same
// layout.
//
// Batches are matrices with one column per sample. Determinism: the products are written out here
// rather than left to Eigen's GEMM, which splits the inner dimension into blocks sized from the L1
// cache size it reads from the CPU at run time (in this SSE2 build from about 400 on with a 32 KiB
// L1; with Eigen told the L1 is 8 KiB, a 256 x 256 product changed 58617 of its 65536 entries), so
// its rounding can depend on the machine. Every sum below runs over its index in increasing order;
// the loops vectorise only across independent outputs, so the bits depend on neither the vector
// width nor the CPU (tests/test_rl_mlp.cpp GoldenDigest: one digest at -O0, -O2 -mavx2 -mfma and
// -O3 -march=native).
#include <cstddef>
#include <span>
#include <vector>

#include <Eigen/Dense>

#include "common/rng.hpp"

namespace dsb {

enum class Activation { tanh, relu };
const char* to_string(Activation a);

// What backward needs from one forward pass; owned by the caller, so several passes (two critics,
// their targets) can be in flight at once.
struct MlpCache {
  std::vector<Eigen::MatrixXd> act;  // act[0]: input (n_0 x batch); act[l]: hidden layer l's
                                     // activation (n_l x batch), l = 1 .. L-1
};

class Mlp {
 public:
  // sizes = {in, h1, ..., out}, at least two entries, all >= 1 (ConfigError naming 'sizes'
  // otherwise). Parameters start at zero: call init_orthogonal or init_torch_default.
  Mlp(std::vector<int> sizes, Activation activation);

  const std::vector<int>& sizes() const { return sizes_; }
  Activation activation() const { return activation_; }
  int in_dim() const { return sizes_.front(); }
  int out_dim() const { return sizes_.back(); }
  int layer_count() const { return static_cast<int>(sizes_.size()) - 1; }

  std::span<double> params() { return params_; }
  std::span<const double> params() const { return params_; }
  std::size_t param_count() const { return params_.size(); }
  std::size_t weight_offset(int layer) const { return offsets_[layer]; }
  std::size_t bias_offset(int layer) const {
    return offsets_[layer] + std::size_t(sizes_[layer + 1]) * std::size_t(sizes_[layer]);
  }
  // views into params(): W_l (n_{l+1} x n_l) and b_l (n_{l+1})
  Eigen::Map<const Eigen::MatrixXd> weight(int layer) const;
  Eigen::Map<const Eigen::VectorXd> bias(int layer) const;
  Eigen::Map<Eigen::MatrixXd> weight(int layer);
  Eigen::Map<Eigen::VectorXd> bias(int layer);

  // y = W_{L-1} f(... f(W_0 x + b_0) ...) + b_{L-1}; x (in x batch) -> y (out x batch). Fills
  // cache when given. Throws std::invalid_argument when x has the wrong number of rows.
  Eigen::MatrixXd forward(const Eigen::MatrixXd& x, MlpCache* cache = nullptr) const;
  // one sample: x (in) -> y (out)
  Eigen::VectorXd forward_one(const Eigen::VectorXd& x) const;

  // Backpropagation of dy = dL/dy (out x batch) through the pass recorded in cache:
  // ADDS dL/dparams to grad (param_count(), same layout; an empty span skips the parameter
  // gradient, e.g. for dQ/da through a critic) and, when dx is given, writes dL/dx (in x batch).
  void backward(const MlpCache& cache, const Eigen::MatrixXd& dy, std::span<double> grad,
                Eigen::MatrixXd* dx = nullptr) const;

 private:
  std::vector<int> sizes_;
  Activation activation_;
  std::vector<std::size_t> offsets_;  // weight_offset per layer
  std::vector<double> params_;
};

// Orthogonal matrix (rows x cols) times gain, as torch.nn.init.orthogonal_: G (rows x cols) with
// entries rng.normal() drawn in row-major order; if rows < cols work on G^T; QR by Householder
// reflections, Q's column j multiplied by sign(R_jj) (which makes the result Haar-distributed);
// transposed back if rows < cols. Then W W^T = gain^2 I (wide) or W^T W = gain^2 I (tall).
// The QR is written out here (unblocked Householder, the same construction as Eigen's
// HouseholderQR, which the test compares against) so its rounding cannot depend on the CPU.
Eigen::MatrixXd orthogonal_matrix(int rows, int cols, double gain, Rng& rng);

// SB3 PPO init (ortho_init=True): every hidden layer's weights orthogonal with hidden_gain
// (sqrt(2) in SB3), the output layer's with output_gain (0.01 policy head, 1 value head), all
// biases 0. Layers in order 0 .. L-1, each drawing from rng.
void init_orthogonal(Mlp& net, double output_gain, Rng& rng, double hidden_gain = 1.4142135623730951);

// PyTorch's default nn.Linear init (SAC): W and b ~ U(-1/sqrt(fan_in), 1/sqrt(fan_in)), fan_in = n_l
// (kaiming_uniform_ with a = sqrt(5) gives exactly this bound). Per layer, the weights in row-major
// order (torch's memory order), then the bias.
void init_torch_default(Mlp& net, Rng& rng);

}  // namespace dsb
