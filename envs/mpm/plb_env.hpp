#pragma once
// `plb-NAME`: a PlasticineLab task (plb_tasks.hpp) as an Env. Params: 5 segments x the
// manipulators' commands of one env step (TripleMove 90, Assembly and Rope 30, the rest 15), each
// segment held for 10 env steps; loss: PlasticineLab's trajectory objective with the raised contact
// weight (plb_loss.hpp); gradient: the engine's checkpointed reverse pass; second metric: the soft
// IoU of the final state; RL view as PlasticineLab's (200 particles' positions and velocities and
// each primitive's pose). `plb-NAME-hN`: the same task with N env steps (N a multiple of 5).
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "envs/core/config_model_env.hpp"
#include "envs/core/env.hpp"
#include "envs/core/env_family.hpp"
#include "envs/mpm/mpm_workspace.hpp"
#include "envs/mpm/plb_config.hpp"
#include "envs/mpm/plb_loss.hpp"
#include "envs/mpm/plb_model.hpp"

namespace dsb::mpm {

struct PlbWorkspace : Workspace {
  explicit PlbWorkspace(const MpmModel& model) : mpm(model), loss(model) {}
  MpmWorkspace mpm;
  PlbLossScratch loss;
  std::vector<double> actions, actions_bar;  // env_steps x action dim
};

class PlbEnv : public ConfigModelEnv<PlbConfig, PlbModel> {
 public:
  PlbEnv(std::string name, PlbConfig cfg);
  std::unique_ptr<Workspace> make_workspace() const override;
  std::unique_ptr<RlEnv> make_rl() const override;
  // each env step's commands: its segment's params (actions())
  std::vector<double> rl_actions(std::span<const double> x) const override {
    std::vector<double> a;
    actions(x, a);
    return a;
  }
  bool renderable() const override { return true; }
  std::vector<dsb::Frame> frames(std::span<const double> x, int n, ThreadTeam& team) const override;  // frames_mpm.cpp
  // the target grid's cells above 1% of its maximum (its shell as discs: top faces in the state
  // colour, those in dents and the other faces in the trace colour) and PlasticineLab's bounding
  // boxes of its target's bodies (frames_mpm.cpp)
  std::vector<dsb::Frame> target_frames() const override;
  double episode_metric(const Workspace& ws) const override;

  const PlbConfig& plb_config() const { return cfg_; }
  // the engine's actions of every env step for params x (env_steps x action dim)
  void actions(std::span<const double> x, std::vector<double>& out) const;
  // the params that replay the task's reference motion as closely as segments allow: none in
  // general (phases need not align with segments), so this gives the per-env-step actions instead
  std::vector<double> reference_actions() const;

 protected:
  double rollout(std::span<const double> x, Workspace& ws, ThreadTeam& team) const override;
  double rollout_with_grad(std::span<const double> x, std::span<double> grad, Workspace& ws,
                           ThreadTeam& team) const override;

 private:
  int action_dim_ = 0;  // commands of one env step
};

// the reference motion's per-env-step actions of a task (its phases laid end to end, cut or
// padded with zeros to env_steps)
std::vector<double> plb_reference_actions(const PlbTask& task, int env_steps);

EnvFamily plb_family();

}  // namespace dsb::mpm
