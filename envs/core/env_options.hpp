#pragma once
// Options of an env, given on the command line as `--set ENV.KEY=VALUE` (and to the Python
// bindings' make(NAME, KEY=VALUE)): values that change what an env computes beyond its name, such
// as a PlasticineLab task's target file. A family lists the options its envs take (`harness
// list` shows them); an option changes the env's config, so its hash and every run key, and an env
// without options has exactly the config it has always had.
#include <map>
#include <string>

namespace dsb {

// key -> value, as given (a path stays as the user wrote it)
using EnvOptions = std::map<std::string, std::string>;

struct EnvOptionInfo {
  std::string key;           // e.g. "target"
  std::string meaning;       // one line
  std::string default_text;  // what the env does without the option
  bool path = false;         // the value names a file (`harness slurm` passes it on as an absolute path)
};

}  // namespace dsb
