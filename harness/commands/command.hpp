#pragma once
// One subcommand of `harness`. Every command follows one convention: the file that implements it
// has a function NAME_command() that returns its Command, and harness/commands/command_table.cpp lists
// them all, in the order --help shows. define() adds the command's options to its CLI11
// subcommand, bound to storage the returned action owns, and returns that action: it runs the
// command once the command line is parsed and returns the exit code (harness/commands/cli.hpp); bad input
// is a UsageError naming the value (exit 2, one line).
#include <functional>
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace dsb {

struct Command {
  std::string name;
  std::string help;
  std::function<std::function<int()>(CLI::App&)> define;
};

// every subcommand; `run`'s options are also the program's own (bare flags: harness --all --seeds 5)
const std::vector<Command>& harness_commands();

Command run_command();         // harness/commands/run_command.cpp
Command list_command();        // harness/commands/list_command.cpp
Command plan_command();        // harness/commands/plan_command.cpp
Command calibrate_command();   // harness/commands/calibrate_command.cpp
Command slurm_command();       // harness/commands/slurm_command.cpp
Command eval_command();        // harness/commands/eval_command.cpp
Command render_command();      // harness/commands/render_command.cpp
Command gradcheck_command();   // harness/commands/gradcheck_command.cpp
Command landscape_command();   // harness/commands/landscape_command.cpp
Command crosscheck_command();  // harness/commands/crosscheck_command.cpp
Command check_command();       // harness/commands/check_command.cpp
Command merge_command();       // harness/commands/merge_command.cpp
Command export_command();      // harness/commands/export_command.cpp
Command report_command();      // harness/commands/report_command.cpp

}  // namespace dsb
