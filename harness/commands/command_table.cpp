#include "harness/commands/command.hpp"

namespace dsb {

const std::vector<Command>& harness_commands() {
  static const std::vector<Command> commands = {
      run_command(),   list_command(),   plan_command(),      calibrate_command(), slurm_command(),
      eval_command(),  render_command(), gradcheck_command(), landscape_command(), crosscheck_command(),
      check_command(), merge_command(),  export_command(),    report_command(),
  };
  return commands;
}

}  // namespace dsb
