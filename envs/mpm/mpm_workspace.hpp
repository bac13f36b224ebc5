#pragma once
// The mutable buffers of MPM rollouts (MuJoCo's mjData): the current particle and primitive
// state, the grid, the bins, and for gradients the env-step checkpoints, one env step's
// substep tapes and the adjoints. Sized once for a model and reused by every rollout of a run,
// so a rollout allocates nothing after the first.
#include <vector>

#include "envs/mpm/grid.hpp"
#include "envs/mpm/lane_chunks.hpp"
#include "envs/mpm/lane_path.hpp"
#include "envs/mpm/mpm_model.hpp"
#include "envs/mpm/primitive.hpp"

namespace dsb::mpm {

constexpr int kMaxPrimitives = 8;

// What the reverse pass of one substep needs (recorded when an env step is recomputed). Of the
// stress update, only each solid's SVD is kept, compactly (svd3.hpp SvdRecord: 7 doubles instead
// of 21); the reverse pass restores U from it and recomputes the return mapping (a few
// logarithms), which costs far less than the SVD it saves.
struct SubstepTape {
  std::vector<Particle> before;  // particles at the start of the substep
  std::vector<SvdRecord> svd;    // per particle: the SVD of F_tmp (solids only)
  std::vector<Pose> poses;       // primitive poses at the start of the substep
  ParticleBins bins;             // the substep's binning of `before`
  GridSnapshot grid;             // active blocks' m, q, v after the grid update
};

// dL/d(x + dt v') split where the advection was not clamped: its part reaching x, and the
// total dL/dv' (v' the G2P velocity).
struct AdvectionAdjoint {
  Vec3 x_bar = Vec3::Zero();
  Vec3 v_bar = Vec3::Zero();
};

// The state at an env-step boundary.
struct Checkpoint {
  std::vector<Particle> particles;
  std::vector<Pose> poses;
};

// Wall seconds spent in each phase of the substeps (filled only when a workspace is given one:
// benchmarks; results never depend on it).
struct PhaseTimes {
  double bin = 0.0;     // binning and clearing active blocks
  double stress = 0.0;  // F update, SVD, return mapping, stress
  double p2g = 0.0;
  double grid = 0.0;  // kinematics and grid update (contact, walls)
  double g2p = 0.0;
  double reverse_g2p = 0.0;        // G2P^T scatter
  double reverse_grid = 0.0;       // grid update^T (and restoring the grid)
  double reverse_particles = 0.0;  // stress recomputation, P2G^T gather, stress adjoint
  double other = 0.0;              // tapes, checkpoints, losses
};

// Sees the state at the env-step boundaries of run_episode (`harness render`): step 0 is the
// initial state, step k the state after env step k.
class EpisodeObserver {
 public:
  virtual ~EpisodeObserver() = default;
  virtual void at_step(int step, const std::vector<Particle>& particles, const std::vector<Pose>& poses) = 0;
};

struct MpmWorkspace {
  explicit MpmWorkspace(const MpmModel& model);

  // current state
  std::vector<Particle> particles;
  std::vector<Pose> poses;
  // per substep scratch
  std::vector<Pose> next_poses;
  std::vector<ContactFrame> frames;
  std::vector<Mat3> affine;  // per particle: A = -(4 dt V / dx^2) tau + m C
  GridFields grid;
  ParticleBins bins;
  // reverse pass
  std::vector<Checkpoint> checkpoints;  // env steps (checkpoint k = state before env step k)
  std::vector<SubstepTape> tapes;       // substeps of one env step, recomputed from its checkpoint
  // the tapes the forward pass keeps (episode.hpp): env step k's substeps at step_tapes[k],
  // allocated on first use and kept for the next rollouts; the first taped_env_steps are valid
  std::vector<std::vector<SubstepTape>> step_tapes;
  int taped_env_steps = 0;
  std::size_t step_tape_bytes = 0;  // the bytes of one env step's tapes, as last measured
  std::vector<ParticleAdjoint> adj, adj_prev;
  std::vector<AdvectionAdjoint> advection;  // per particle, within one substep's reverse
  std::vector<PoseAdjoint> pose_adj;
  GridAdjoint grid_adj;
  SimdPath lanes = default_lane_path();    // the code of the per-particle phases (same bits on every path)
  std::vector<TransferChunk> lane_chunks;  // the lanes path's P2G chunks, one per thread
  PhaseTimes* phase_times = nullptr;       // not owned
  EpisodeObserver* observer = nullptr;     // not owned; run_episode calls it when set (render only)

  void reset_state(const MpmModel& model);                     // particles and poses to the model's initial state
  void reserve_reverse(const MpmModel& model, int env_steps);  // checkpoints and one env step's tapes
  // env step k's tapes for the forward pass to record (allocated on first use)
  SubstepTape* forward_tapes(const MpmModel& model, int k);
};

}  // namespace dsb::mpm
