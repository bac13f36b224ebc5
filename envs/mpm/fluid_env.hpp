#pragma once
// `fluid` (fluid_config.hpp) as an Env: 10 params (5 segments x forward/back and up/down speed of
// the ladle) -> the MPM episode -> the seed's loss; the gradient by the engine's checkpointed
// reverse pass; an RL view with per-env-step actions. `fluid-hN` is the same task with N env
// steps (N a multiple of 5, N <= 50): the regression grid's short horizon.
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "envs/core/config_model_env.hpp"
#include "envs/core/env.hpp"
#include "envs/core/env_family.hpp"
#include "envs/mpm/fluid_config.hpp"
#include "envs/mpm/mpm_model.hpp"
#include "envs/mpm/mpm_workspace.hpp"

namespace dsb::mpm {

struct FluidWorkspace : Workspace {
  explicit FluidWorkspace(const MpmModel& model) : mpm(model) {}
  MpmWorkspace mpm;
  std::vector<double> actions, actions_bar;  // env_steps x 4
  double cube_height = 0.0;                  // the last rollout's second metric (m above the floor)
};

class FluidEnv : public ConfigModelEnv<FluidConfig, MpmModel> {
 public:
  FluidEnv(std::string name, FluidConfig cfg);
  std::unique_ptr<Workspace> make_workspace() const override;
  std::unique_ptr<RlEnv> make_rl() const override;
  // each env step's (forward/back, up/down) speeds: its segment's two params
  std::vector<double> rl_actions(std::span<const double> x) const override;
  bool renderable() const override { return true; }
  std::vector<dsb::Frame> frames(std::span<const double> x, int n, ThreadTeam& team) const override;  // frames_mpm.cpp
  // the cube's height above the tank floor after the last rollout in ws (NaN if it blew up)
  double episode_metric(const Workspace& ws) const override;

  const FluidConfig& fluid_config() const { return cfg_; }
  // the engine's actions of every env step for params x: env_steps x (bowl x, bowl y, handle x,
  // handle y), each segment's two params held for its env steps
  void actions(std::span<const double> x, std::vector<double>& out) const;
  // the cube's centre and the bowl's position after every env step (index 0 = the start)
  struct TrajectoryPoint {
    Vec3 cube, bowl;
  };
  std::vector<TrajectoryPoint> trajectory(std::span<const double> x, ThreadTeam& team) const;

 protected:
  double rollout(std::span<const double> x, Workspace& ws, ThreadTeam& team) const override;
  double rollout_with_grad(std::span<const double> x, std::span<double> grad, Workspace& ws,
                           ThreadTeam& team) const override;
};

EnvFamily fluid_family();

}  // namespace dsb::mpm
